#include "rig/kinematics.h"

#include <cmath>

namespace rig {

Eigen::Matrix3d HeadFromCameraRotation() {
  Eigen::Matrix3d r;
  // Columns: the camera's x, y, z axes expressed in the head frame.
  r.col(0) = Eigen::Vector3d::UnitX();
  r.col(1) = -Eigen::Vector3d::UnitZ();
  r.col(2) = Eigen::Vector3d::UnitY();
  return r;
}

Eigen::Isometry3d RigGeometry::WorldFromHead(Side side, const CameraStage& stage) const {
  const HeadGeometry& head = (*this)[side];
  Eigen::Isometry3d world_T_head = Eigen::Isometry3d::Identity();
  world_T_head.translation() = head.rail_zero_W + stage.carriage_m * Eigen::Vector3d::UnitX();
  world_T_head.linear() = (Eigen::AngleAxisd(stage.pan_rad, Eigen::Vector3d::UnitZ()) *
                           Eigen::AngleAxisd(stage.tilt_rad, Eigen::Vector3d::UnitX()))
                              .toRotationMatrix();
  return world_T_head;
}

CameraStage RigGeometry::FacingStage(Side side, double carriage_m,
                                     const Eigen::Vector3d& p_W) const {
  const Eigen::Vector3d v = p_W - WorldFromHead(side, {carriage_m, 0, 0}).translation();
  return {carriage_m, std::atan2(-v.x(), v.y()), std::atan2(v.z(), std::hypot(v.x(), v.y()))};
}

Eigen::Isometry3d RigGeometry::WorldFromCamera(Side side, const CameraStage& stage) const {
  Eigen::Isometry3d head_T_camera = Eigen::Isometry3d::Identity();
  head_T_camera.translation() = (*this)[side].optical_centre_H;
  head_T_camera.linear() = HeadFromCameraRotation();
  return WorldFromHead(side, stage) * head_T_camera;
}

}  // namespace rig
