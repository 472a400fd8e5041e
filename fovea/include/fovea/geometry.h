// Projective geometry on rig camera models (OpenCV frames, metres, pixels).
#pragma once

#include <Eigen/Geometry>
#include <optional>

#include "rig/types.h"

namespace fovea {

/// A depth that stands for infinity in disparity searches: a point this far
/// is within a tenth of a pixel of the point at infinity for any focal length
/// under 2,000 px and baseline under 4 m.
constexpr double kFarDepthM = 1e5;

/// Pixel where the world point p_W appears in a camera at world_T_camera;
/// nullopt if the point is behind or on the camera plane.
std::optional<Eigen::Vector2d> ProjectWorldPoint(const Eigen::Isometry3d& world_T_camera,
                                                 const rig::CameraIntrinsics& intrinsics,
                                                 const Eigen::Vector3d& p_W);

/// The same from the inverse pose (camera_T_world = world_T_camera^-1), for
/// callers that project many points into one camera.
inline std::optional<Eigen::Vector2d> ProjectIntoCamera(const Eigen::Isometry3d& camera_T_world,
                                                        const rig::CameraIntrinsics& intrinsics,
                                                        const Eigen::Vector3d& p_W) {
  const Eigen::Vector3d p_C = camera_T_world * p_W;
  if (!(p_C.z() > 1e-9)) return std::nullopt;
  return intrinsics.Project(p_C);
}

/// A ray in the world: origin and unit direction.
struct Ray {
  Eigen::Vector3d origin_W;
  Eigen::Vector3d direction_W;
};

/// The world ray through pixel uv of a camera.
Ray PixelRay(const Eigen::Isometry3d& world_T_camera, const rig::CameraIntrinsics& intrinsics,
             const Eigen::Vector2d& uv);

/// Full-resolution horizontal disparity u - u_right of the point at planar
/// depth z on the left camera's ray through pixel (u, v), in a pair whose
/// right camera is at right_T_left from the left one; NaN if the point is
/// behind or on the right camera's plane.
double DisparityAtDepth(const rig::CameraView& left, const rig::CameraView& right,
                        const Eigen::Isometry3d& right_T_left, double u, double v, double z);

/// Midpoint of the shortest segment between two rays, and that segment's
/// length (the rays' miss distance). nullopt for (near) parallel rays or a
/// point behind either camera.
struct Triangulation {
  Eigen::Vector3d p_W;
  double miss_distance_m = 0;
};
std::optional<Triangulation> TriangulateMidpoint(const Ray& a, const Ray& b);

}  // namespace fovea
