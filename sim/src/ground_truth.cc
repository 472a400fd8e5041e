#include "sim/ground_truth.h"

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "world.h"

namespace sim {

std::optional<std::string> GroundTruth::WhyNotRenderable(const rig::CameraIntrinsics& k) const {
  const mjModel* m = world_->m;
  if (!k.distortion.empty() || std::abs(k.fx_px - k.fy_px) > 1e-9 * k.fx_px ||
      std::abs(k.cx_px - 0.5 * (k.width_px - 1)) > 1e-9 ||
      std::abs(k.cy_px - 0.5 * (k.height_px - 1)) > 1e-9)
    return "true-depth rendering needs square pixels, a centred principal point and no distortion "
           "(use RayCastDepth for other cameras)";
  if (k.width_px > m->vis.global.offwidth || k.height_px > m->vis.global.offheight)
    return "true-depth rendering: image larger than the offscreen buffer";
  return std::nullopt;
}

void GroundTruth::PlaceTruthCamera(const Eigen::Isometry3d& world_T_camera,
                                   const rig::CameraIntrinsics& k) const {
  k.Check();
  if (const auto why = WhyNotRenderable(k)) throw rig::RigError(*why);
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
}

TrueView GroundTruth::Render(const Eigen::Isometry3d& world_T_camera,
                             const rig::CameraIntrinsics& k, bool color) const {
  PlaceTruthCamera(world_T_camera, k);
  TrueView view;
  cv::Mat rgb;
  world_->renderer->Render(world_->m, world_->d, world_->truth_camera_id, k.width_px, k.height_px,
                           color ? &rgb : nullptr, &view.depth_m);
  if (color) cv::cvtColor(rgb, view.bgr, cv::COLOR_RGB2BGR);
  return view;
}

GroundTruth::Labels GroundTruth::RenderLabels(const Eigen::Isometry3d& world_T_camera,
                                              const rig::CameraIntrinsics& k) const {
  k.Check();
  if (WhyNotRenderable(k)) {
    Labels l;
    l.depth_m = RayCastDepth(world_T_camera, k, &l.geom_ids);
    l.ray_cast = k.width_px * k.height_px;
    return l;
  }
  PlaceTruthCamera(world_T_camera, k);
  World& w = *world_;
  if (!w.truth_renderer)
    w.truth_renderer = new OffscreenRenderer(w.m, w.m->vis.global.offwidth,
                                             w.m->vis.global.offheight, /*truth=*/true);
  Labels l;
  w.truth_renderer->RenderLabels(w.m, w.d, w.truth_camera_id, k.width_px, k.height_px, &l.depth_m,
                                 &l.geom_ids);
  // Where the raster may not be the exact geometry: faceted builtin
  // shapes, and both sides of every edge between surfaces.
  const mjModel* m = w.m;
  auto faceted = [m](int g) {
    if (g < 0) return false;
    const int type = m->geom_type[g];
    return type == mjGEOM_SPHERE || type == mjGEOM_CAPSULE || type == mjGEOM_ELLIPSOID ||
           type == mjGEOM_CYLINDER;
  };
  constexpr double kJumpShare = 0.01;  // a depth step of 1% between neighbours is an edge
  cv::Mat exact(k.height_px, k.width_px, CV_8U, cv::Scalar(0));
  for (int v = 0; v < k.height_px; ++v)
    for (int u = 0; u < k.width_px; ++u) {
      const int g = l.geom_ids.at<int>(v, u);
      const float z = l.depth_m.at<float>(v, u);
      bool edge = faceted(g);
      for (int dv = -1; dv <= 1 && !edge; ++dv)
        for (int du = -1; du <= 1 && !edge; ++du) {
          const int vv = v + dv, uu = u + du;
          if (vv < 0 || uu < 0 || vv >= k.height_px || uu >= k.width_px) continue;
          const int gn = l.geom_ids.at<int>(vv, uu);
          const float zn = l.depth_m.at<float>(vv, uu);
          edge = gn != g || faceted(gn) || std::abs(zn - z) > kJumpShare * std::max(z, zn);
        }
      if (edge) exact.at<uchar>(v, u) = 1;
    }
  const Eigen::Vector3d origin = world_T_camera.translation();
  for (int v = 0; v < k.height_px; ++v)
    for (int u = 0; u < k.width_px; ++u) {
      if (!exact.at<uchar>(v, u)) continue;
      const Eigen::Vector3d ray_C = k.Ray({u, v});
      const auto hit = CastRay(origin, world_T_camera.linear() * ray_C);
      l.depth_m.at<float>(v, u) = hit ? static_cast<float>(hit->distance_m / ray_C.norm()) : 0.0f;
      l.geom_ids.at<int>(v, u) = hit ? hit->geom_id : -1;
      ++l.ray_cast;
    }
  return l;
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

std::optional<double> GroundTruth::CastRayAt(int geom_id, const Eigen::Vector3d& p_W,
                                             const Eigen::Vector3d& dir_W) const {
  const mjModel* m = world_->m;
  const double norm = dir_W.norm();
  if (geom_id < 0 || geom_id >= m->ngeom || !(norm > 0)) return std::nullopt;
  const Eigen::Vector3d u = dir_W / norm;
  const double dist =
      m->geom_type[geom_id] == mjGEOM_MESH
          ? mj_rayMesh(m, world_->d, geom_id, p_W.data(), u.data())
          : mju_rayGeom(world_->d->geom_xpos + 3 * geom_id, world_->d->geom_xmat + 9 * geom_id,
                        m->geom_size + 3 * geom_id, p_W.data(), u.data(), m->geom_type[geom_id]);
  if (dist < 0) return std::nullopt;
  return dist;
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
