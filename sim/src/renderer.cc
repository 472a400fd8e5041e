#include <algorithm>
#include <cstring>
#include <opencv2/core.hpp>

#include "sim/config.h"
#include "world.h"

namespace sim {

OffscreenRenderer::OffscreenRenderer(mjModel* m, int width_px, int height_px, bool truth)
    : width_px_(width_px), height_px_(height_px) {
  context_ = OSMesaCreateContextExt(OSMESA_RGBA, 24, 8, 0, nullptr);
  if (!context_) throw rig::RigError("cannot create an OSMesa rendering context");
  window_buffer_.resize(static_cast<size_t>(width_px) * height_px * 4);
  if (!OSMesaMakeCurrent(context_, window_buffer_.data(), GL_UNSIGNED_BYTE, width_px, height_px)) {
    OSMesaDestroyContext(context_);
    throw rig::RigError("cannot make the OSMesa rendering context current");
  }
  mjv_defaultScene(&scene_);
  mjv_makeScene(m, &scene_, 2000);
  mjv_defaultOption(&option_);
  // Groups 0-2 are the scene; 3-5 hold the rig's own geoms, never imaged.
  for (int g = 0; g < mjNGROUP; ++g) option_.geomgroup[g] = g < 3 ? 1 : 0;
  mjr_defaultContext(&context_mj_);
  // The context takes its multisampling and the facets of the builtin
  // spheres, capsules and cylinders from the model: set for it alone.
  const auto quality = m->vis.quality;
  if (truth) {
    m->vis.quality.offsamples = 0;
    m->vis.quality.numslices = std::max(quality.numslices, 128);
    m->vis.quality.numstacks = std::max(quality.numstacks, 64);
  }
  mjr_makeContext(m, &context_mj_, mjFONTSCALE_100);
  m->vis.quality = quality;
  mjr_setBuffer(mjFB_OFFSCREEN, &context_mj_);
  if (context_mj_.offWidth < width_px || context_mj_.offHeight < height_px) {
    throw SceneError("offscreen buffer " + std::to_string(context_mj_.offWidth) + "x" +
                     std::to_string(context_mj_.offHeight) + " is smaller than the images");
  }
}

OffscreenRenderer::~OffscreenRenderer() {
  OSMesaMakeCurrent(context_, window_buffer_.data(), GL_UNSIGNED_BYTE, width_px_, height_px_);
  mjr_freeContext(&context_mj_);
  mjv_freeScene(&scene_);
  OSMesaDestroyContext(context_);
}

namespace {

// Window depth d in [0, 1] (bottom row first) to planar depth, top row
// first: z = near / (1 - d (1 - near / far)); 0 where the far plane was hit.
void WindowToPlanarDepth(const mjModel* m, const cv::Mat& window, cv::Mat* depth_m) {
  const double extent = m->stat.extent;
  const double near_m = m->vis.map.znear * extent, far_m = m->vis.map.zfar * extent;
  depth_m->create(window.size(), CV_32FC1);
  for (int r = 0; r < window.rows; ++r) {
    const float* src = window.ptr<float>(window.rows - 1 - r);
    float* dst = depth_m->ptr<float>(r);
    for (int c = 0; c < window.cols; ++c) {
      const double w = src[c];
      dst[c] = w >= 1.0 ? 0.0f : static_cast<float>(near_m / (1.0 - w * (1.0 - near_m / far_m)));
    }
  }
}

}  // namespace

void OffscreenRenderer::UpdateScene(const mjModel* m, mjData* d, int cam_id) {
  // Several renderers may live in one process (tests): make ours current.
  OSMesaMakeCurrent(context_, window_buffer_.data(), GL_UNSIGNED_BYTE, width_px_, height_px_);
  mjr_setBuffer(mjFB_OFFSCREEN, &context_mj_);
  mjvCamera camera;
  mjv_defaultCamera(&camera);
  camera.type = mjCAMERA_FIXED;
  camera.fixedcamid = cam_id;
  mjv_updateScene(m, d, &option_, nullptr, &camera, mjCAT_ALL, &scene_);
}

void OffscreenRenderer::RenderLabels(const mjModel* m, mjData* d, int cam_id, int width_px,
                                     int height_px, cv::Mat* depth_m, cv::Mat* geom_ids) {
  UpdateScene(m, d, cam_id);
  // Each geom in its own colour, segid + 1 as r + 256 g + 65536 b, unlit.
  scene_.flags[mjRND_SEGMENT] = 1;
  scene_.flags[mjRND_IDCOLOR] = 1;
  const mjrRect viewport = {0, 0, width_px, height_px};
  mjr_render(viewport, &scene_, &context_mj_);
  scene_.flags[mjRND_SEGMENT] = 0;
  scene_.flags[mjRND_IDCOLOR] = 0;
  cv::Mat rgb_up(height_px, width_px, CV_8UC3), depth_up(height_px, width_px, CV_32FC1);
  mjr_readPixels(rgb_up.ptr<unsigned char>(), depth_up.ptr<float>(), viewport, &context_mj_);
  WindowToPlanarDepth(m, depth_up, depth_m);
  // segid -> geom id, for the geoms of the scene this frame drew.
  std::vector<int> geom_of_segid(scene_.ngeom + 1, -1);
  for (int i = 0; i < scene_.ngeom; ++i) {
    const mjvGeom& g = scene_.geoms[i];
    if (g.segid >= 0 && g.segid < scene_.ngeom && g.objtype == mjOBJ_GEOM)
      geom_of_segid[g.segid + 1] = g.objid;
  }
  geom_ids->create(height_px, width_px, CV_32SC1);
  for (int r = 0; r < height_px; ++r) {
    const unsigned char* src = rgb_up.ptr<unsigned char>(height_px - 1 - r);
    int* dst = geom_ids->ptr<int>(r);
    for (int c = 0; c < width_px; ++c) {
      const int id = src[3 * c] + 256 * src[3 * c + 1] + 65536 * src[3 * c + 2];
      dst[c] = id > 0 && id <= scene_.ngeom ? geom_of_segid[id] : -1;
    }
  }
}

void OffscreenRenderer::Render(const mjModel* m, mjData* d, int cam_id, int width_px, int height_px,
                               cv::Mat* rgb, cv::Mat* depth_m) {
  UpdateScene(m, d, cam_id);
  const mjrRect viewport = {0, 0, width_px, height_px};
  mjr_render(viewport, &scene_, &context_mj_);

  cv::Mat rgb_up, depth_up;
  if (rgb) rgb_up.create(height_px, width_px, CV_8UC3);
  if (depth_m) depth_up.create(height_px, width_px, CV_32FC1);
  mjr_readPixels(rgb ? rgb_up.ptr<unsigned char>() : nullptr,
                 depth_m ? depth_up.ptr<float>() : nullptr, viewport, &context_mj_);
  // OpenGL returns the bottom row first.
  if (rgb) cv::flip(rgb_up, *rgb, 0);
  if (depth_m) WindowToPlanarDepth(m, depth_up, depth_m);
}

World::~World() {
  delete truth_renderer;
  delete renderer;
  if (d) mj_deleteData(d);
  if (m) mj_deleteModel(m);
}

Eigen::Isometry3d CameraPoseFromMujoco(const mjData* d, int cam_id) {
  Eigen::Isometry3d world_T_camera = Eigen::Isometry3d::Identity();
  Eigen::Matrix3d world_R_mj;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) world_R_mj(r, c) = d->cam_xmat[9 * cam_id + 3 * r + c];
  // MuJoCo camera axes: x right, y up, looking along -z. OpenCV: x right, y
  // down, z forward. So OpenCV = MuJoCo * diag(1, -1, -1).
  world_T_camera.linear() = world_R_mj * Eigen::Vector3d(1, -1, -1).asDiagonal();
  world_T_camera.translation() = Eigen::Vector3d(
      d->cam_xpos[3 * cam_id], d->cam_xpos[3 * cam_id + 1], d->cam_xpos[3 * cam_id + 2]);
  return world_T_camera;
}

Eigen::Quaterniond MujocoCameraQuat(const Eigen::Matrix3d& world_R_camera) {
  const Eigen::Matrix3d world_R_mj = world_R_camera * Eigen::Vector3d(1, -1, -1).asDiagonal();
  return Eigen::Quaterniond(world_R_mj).normalized();
}

}  // namespace sim
