#include "fovea/geometry.h"

#include <limits>

namespace fovea {

std::optional<Eigen::Vector2d> ProjectWorldPoint(const Eigen::Isometry3d& world_T_camera,
                                                 const rig::CameraIntrinsics& intrinsics,
                                                 const Eigen::Vector3d& p_W) {
  return ProjectIntoCamera(world_T_camera.inverse(), intrinsics, p_W);
}

Ray PixelRay(const Eigen::Isometry3d& world_T_camera, const rig::CameraIntrinsics& intrinsics,
             const Eigen::Vector2d& uv) {
  return {world_T_camera.translation(),
          (world_T_camera.linear() * intrinsics.Ray(uv)).normalized()};
}

std::optional<Triangulation> TriangulateMidpoint(const Ray& a, const Ray& b) {
  // Minimize |a.o + s a.d - (b.o + t b.d)| over s, t (unit directions).
  const Eigen::Vector3d w = a.origin_W - b.origin_W;
  const double c = a.direction_W.dot(b.direction_W);
  const double denom = 1 - c * c;
  if (denom < 1e-12) return std::nullopt;
  const double da = a.direction_W.dot(w), db = b.direction_W.dot(w);
  const double s = (c * db - da) / denom;
  const double t = (db - c * da) / denom;
  if (s <= 0 || t <= 0) return std::nullopt;
  const Eigen::Vector3d pa = a.origin_W + s * a.direction_W;
  const Eigen::Vector3d pb = b.origin_W + t * b.direction_W;
  return Triangulation{0.5 * (pa + pb), (pa - pb).norm()};
}

double DisparityAtDepth(const rig::CameraView& left, const rig::CameraView& right,
                        const Eigen::Isometry3d& right_T_left, double u, double v, double z) {
  const Eigen::Vector3d p_R = right_T_left * (z * left.intrinsics.Ray({u, v}));
  if (p_R.z() <= 1e-6) return std::numeric_limits<double>::quiet_NaN();
  const double ur = right.intrinsics.fx_px * p_R.x() / p_R.z() + right.intrinsics.cx_px;
  return u - ur;
}

}  // namespace fovea
