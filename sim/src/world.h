// Internal to sim/: the MuJoCo model and data, the offscreen renderer, and the
// ids of the rig's joints, actuators and cameras.
#pragma once

#include <GL/osmesa.h>
#include <mujoco/mujoco.h>

#include <Eigen/Geometry>
#include <array>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "rig/types.h"

namespace sim {

/// OSMesa context plus MuJoCo's visualization and rendering state. Renders any
/// model camera into the offscreen buffer; no display and no GPU needed.
class OffscreenRenderer {
 public:
  /// `truth`: a renderer for ground truth, not for the cameras: no
  /// multisampling (an edge pixel shows one surface, not a blend) and the
  /// builtin curved geoms drawn with finer facets.
  OffscreenRenderer(mjModel* m, int width_px, int height_px, bool truth = false);
  ~OffscreenRenderer();
  OffscreenRenderer(const OffscreenRenderer&) = delete;
  OffscreenRenderer& operator=(const OffscreenRenderer&) = delete;

  /// Renders camera `cam_id` at width x height (top row first). `rgb` gets
  /// CV_8UC3 in RGB order; `depth_m` gets planar depth in metres (CV_32FC1, 0
  /// where the far plane was hit). Either may be null.
  void Render(const mjModel* m, mjData* d, int cam_id, int width_px, int height_px, cv::Mat* rgb,
              cv::Mat* depth_m);

  /// Renders depth and, per pixel, the geom shown (CV_32SC1, -1: none) by
  /// MuJoCo's segmentation rendering (mjRND_SEGMENT, mjRND_IDCOLOR).
  void RenderLabels(const mjModel* m, mjData* d, int cam_id, int width_px, int height_px,
                    cv::Mat* depth_m, cv::Mat* geom_ids);

 private:
  /// Makes this renderer current and fills its scene for camera `cam_id`.
  void UpdateScene(const mjModel* m, mjData* d, int cam_id);
  OSMesaContext context_ = nullptr;
  std::vector<unsigned char> window_buffer_;
  int width_px_, height_px_;
  mjvScene scene_;
  mjrContext context_mj_;
  mjvOption option_;
};

struct World {
  mjModel* m = nullptr;
  mjData* d = nullptr;
  std::string scene_path;
  std::array<int, rig::kNumAxes> joint_ids{};     // ordered as rig::Axis
  std::array<int, rig::kNumAxes> actuator_ids{};  // ordered as rig::Axis
  std::array<int, 2> camera_ids{};                // left, right
  int truth_camera_id = -1;
  std::vector<unsigned char> visible_groups;    // mj_ray filter: groups 0-2
  OffscreenRenderer* renderer = nullptr;        // owned
  OffscreenRenderer* truth_renderer = nullptr;  // owned; made on first use (GroundTruth)

  ~World();
};

/// Pose of a MuJoCo camera (looking along its -z, y up) as an OpenCV camera
/// pose (x right, y down, z forward) in the world.
Eigen::Isometry3d CameraPoseFromMujoco(const mjData* d, int cam_id);

/// Inverse: the MuJoCo camera orientation (quaternion w, x, y, z) for an
/// OpenCV camera orientation.
Eigen::Quaterniond MujocoCameraQuat(const Eigen::Matrix3d& world_R_camera);

}  // namespace sim

namespace sim {
struct Box3;
/// Enforces the scene rules (scenes/README.md): the scene must not attach
/// anything to the rig, drive its joints (actuators, tendons, equality
/// constraints), or put geometry inside the rig's workspace `keep_out`.
/// Throws SceneError naming the scene, the offending element and the rule.
void CheckSceneRules(const World& world, const Box3& keep_out);
/// True if the geom's material carries a texture with visible contrast.
bool GeomTextured(const mjModel* m, int geom_id);
}  // namespace sim
