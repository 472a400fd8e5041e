#include "fovea/geometry.h"

namespace fovea {

std::optional<Eigen::Vector2d> ProjectWorldPoint(const Eigen::Isometry3d& world_T_camera,
                                                 const rig::CameraIntrinsics& intrinsics,
                                                 const Eigen::Vector3d& p_W) {
  const Eigen::Vector3d p_C = world_T_camera.inverse() * p_W;
  if (!(p_C.z() > 1e-9)) return std::nullopt;
  return intrinsics.Project(p_C);
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

}  // namespace fovea
