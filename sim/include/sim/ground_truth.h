// What only a simulator can know: true depth, exact ray casts, which surface
// a pixel shows. Used by experiments/ and tests, never by fovea/.
#pragma once

#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "rig/types.h"

namespace sim {

struct World;

/// A ray's first hit on a visible scene surface (geom groups 0 to 2; the rig's
/// own geoms are never hit).
struct RayHit {
  double distance_m = 0;  ///< along the unit ray direction
  int geom_id = -1;
  Eigen::Vector3d point_W = Eigen::Vector3d::Zero();
};

/// An image and its true depth seen by a virtual camera.
struct TrueView {
  cv::Mat bgr;      ///< CV_8UC3; empty unless asked for
  cv::Mat depth_m;  ///< CV_32FC1, planar depth (camera z) in metres; 0 where nothing is hit
};

class GroundTruth {
 public:
  explicit GroundTruth(World* world) : world_(world) {}

  /// Renders the scene (OpenGL depth buffer converted to metres with the
  /// model's near and far planes) from an arbitrary camera pose. The
  /// intrinsics must be undistorted with square pixels, a centred principal
  /// point and a size no larger than the rig's images; throws rig::RigError
  /// otherwise.
  TrueView Render(const Eigen::Isometry3d& world_T_camera, const rig::CameraIntrinsics& intrinsics,
                  bool color = false) const;

  /// What a view shows, without casting a ray per pixel: planar depth from
  /// the OpenGL depth buffer and the geom per pixel from MuJoCo's
  /// segmentation rendering, one pass of a renderer kept for ground truth
  /// (no multisampling). Exact ray casting (CastRay) only where the raster
  /// can differ from the exact geometry: the pixels of builtin spheres,
  /// capsules, ellipsoids and cylinders (drawn with facets) and the pixels
  /// beside a change of geom or a depth jump (edge rasterization). Agrees
  /// with RayCastDepth within 1 mm on every pixel of the catalog's views
  /// (ground_truth_test). Intrinsics Render cannot draw (distortion, an
  /// off-centre principal point, larger than the offscreen buffer) are ray cast
  /// on every pixel.
  struct Labels {
    cv::Mat depth_m;   ///< CV_32FC1, planar depth; 0 where nothing is hit
    cv::Mat geom_ids;  ///< CV_32SC1, -1 where nothing is hit
    int ray_cast = 0;  ///< pixels ray cast exactly
  };
  Labels RenderLabels(const Eigen::Isometry3d& world_T_camera,
                      const rig::CameraIntrinsics& intrinsics) const;

  /// Exact per-pixel ray casting: planar depth in metres (0 where nothing is
  /// hit) and, if `geom_ids` is given, the hit geom per pixel (CV_32SC1, -1
  /// where nothing is hit). Any intrinsics, distortion included.
  cv::Mat RayCastDepth(const Eigen::Isometry3d& world_T_camera,
                       const rig::CameraIntrinsics& intrinsics, cv::Mat* geom_ids = nullptr) const;

  /// First hit of the ray from p_W along dir_W (any non-zero length).
  std::optional<RayHit> CastRay(const Eigen::Vector3d& p_W, const Eigen::Vector3d& dir_W) const;

  /// Distance along the ray from p_W along dir_W to one geom alone (any
  /// non-zero length), nullopt if it misses: which of two coplanar faces
  /// a pixel shows is a tie the renderer and CastRay may break differently.
  std::optional<double> CastRayAt(int geom_id, const Eigen::Vector3d& p_W,
                                  const Eigen::Vector3d& dir_W) const;

  /// The geom's name, or "geom<N>" for an unnamed one.
  std::string GeomName(int geom_id) const;

  /// Whether a geom shows texture (its material's texture has visible
  /// contrast); false for plain colours and the uniform texture, and for -1.
  bool Textured(int geom_id) const;

  /// CV_8UC1 mask, 255 where `geom_ids` (from RayCastDepth) shows a textured
  /// surface.
  cv::Mat TexturedMask(const cv::Mat& geom_ids) const;

 private:
  World* world_;
  /// Why Render cannot draw these intrinsics (RenderLabels then ray casts);
  /// nullopt when it can.
  std::optional<std::string> WhyNotRenderable(const rig::CameraIntrinsics& intrinsics) const;
  /// Poses the truth camera; throws rig::RigError for intrinsics it cannot render.
  void PlaceTruthCamera(const Eigen::Isometry3d& world_T_camera,
                        const rig::CameraIntrinsics& intrinsics) const;
  mutable std::vector<signed char> textured_;  // per geom, computed on first use
};

}  // namespace sim
