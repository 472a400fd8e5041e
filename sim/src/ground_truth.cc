#include "sim/ground_truth.h"

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "world.h"

namespace sim {

TrueView GroundTruth::Render(const Eigen::Isometry3d& world_T_camera,
                             const rig::CameraIntrinsics& k, bool color) const {
  k.Check();
  const mjModel* m = world_->m;
  if (!k.distortion.empty() || std::abs(k.fx_px - k.fy_px) > 1e-9 * k.fx_px ||
      std::abs(k.cx_px - 0.5 * (k.width_px - 1)) > 1e-9 ||
      std::abs(k.cy_px - 0.5 * (k.height_px - 1)) > 1e-9) {
    throw rig::RigError(
        "true-depth rendering needs square pixels, a centred principal point and no distortion "
        "(use RayCastDepth for other cameras)");
  }
  if (k.width_px > m->vis.global.offwidth || k.height_px > m->vis.global.offheight)
    throw rig::RigError("true-depth rendering: image larger than the offscreen buffer");

  // Place the truth camera (a world-body camera) at the pose and field asked.
  const int id = world_->truth_camera_id;
  const Eigen::Quaterniond q = MujocoCameraQuat(world_T_camera.linear());
  const Eigen::Vector3d p = world_T_camera.translation();
  for (int i = 0; i < 3; ++i) world_->m->cam_pos[3 * id + i] = p[i];
  world_->m->cam_quat[4 * id + 0] = q.w();
  world_->m->cam_quat[4 * id + 1] = q.x();
  world_->m->cam_quat[4 * id + 2] = q.y();
  world_->m->cam_quat[4 * id + 3] = q.z();
  world_->m->cam_fovy[id] = k.VerticalFovRad() * 180 / M_PI;
  mj_camlight(world_->m, world_->d);

  TrueView view;
  cv::Mat rgb;
  world_->renderer->Render(world_->m, world_->d, id, k.width_px, k.height_px,
                           color ? &rgb : nullptr, &view.depth_m);
  if (color) cv::cvtColor(rgb, view.bgr, cv::COLOR_RGB2BGR);
  return view;
}

std::optional<RayHit> GroundTruth::CastRay(const Eigen::Vector3d& p_W,
                                           const Eigen::Vector3d& dir_W) const {
  const double norm = dir_W.norm();
  if (!(norm > 0)) return std::nullopt;
  const Eigen::Vector3d u = dir_W / norm;
  int geom = -1;
  const double dist = mj_ray(world_->m, world_->d, p_W.data(), u.data(),
                             world_->visible_groups.data(), 1, -1, &geom);
  if (dist < 0 || geom < 0) return std::nullopt;
  return RayHit{dist, geom, p_W + dist * u};
}

cv::Mat GroundTruth::RayCastDepth(const Eigen::Isometry3d& world_T_camera,
                                  const rig::CameraIntrinsics& k, cv::Mat* geom_ids) const {
  k.Check();
  cv::Mat depth(k.height_px, k.width_px, CV_32FC1, cv::Scalar(0));
  if (geom_ids) geom_ids->create(k.height_px, k.width_px, CV_32SC1);
  const Eigen::Vector3d origin = world_T_camera.translation();
  for (int v = 0; v < k.height_px; ++v) {
    for (int u = 0; u < k.width_px; ++u) {
      const Eigen::Vector3d ray_C = k.Ray({u, v});  // z = 1
      const auto hit = CastRay(origin, world_T_camera.linear() * ray_C);
      // Planar depth = range * (z component of the unit ray).
      if (hit) depth.at<float>(v, u) = static_cast<float>(hit->distance_m / ray_C.norm());
      if (geom_ids) geom_ids->at<int>(v, u) = hit ? hit->geom_id : -1;
    }
  }
  return depth;
}

std::string GroundTruth::GeomName(int geom_id) const {
  if (geom_id < 0 || geom_id >= world_->m->ngeom) return "none";
  const char* name = mj_id2name(world_->m, mjOBJ_GEOM, geom_id);
  return name ? name : "geom" + std::to_string(geom_id);
}

bool GroundTruth::Textured(int geom_id) const {
  const mjModel* m = world_->m;
  if (geom_id < 0 || geom_id >= m->ngeom) return false;
  if (textured_.empty()) {
    textured_.resize(m->ngeom);
    for (int g = 0; g < m->ngeom; ++g) textured_[g] = GeomTextured(m, g) ? 1 : 0;
  }
  return textured_[geom_id] != 0;
}

cv::Mat GroundTruth::TexturedMask(const cv::Mat& geom_ids) const {
  cv::Mat mask(geom_ids.size(), CV_8UC1);
  for (int r = 0; r < geom_ids.rows; ++r)
    for (int c = 0; c < geom_ids.cols; ++c)
      mask.at<uchar>(r, c) = Textured(geom_ids.at<int>(r, c)) ? 255 : 0;
  return mask;
}

}  // namespace sim
