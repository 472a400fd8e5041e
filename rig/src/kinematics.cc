#include "rig/kinematics.h"

#include <algorithm>
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

Eigen::Matrix3d HeadGeometry::MountRotation() const {
  return (Eigen::AngleAxisd(mount_rpy_rad.z(), Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(mount_rpy_rad.y(), Eigen::Vector3d::UnitX()) *
          Eigen::AngleAxisd(mount_rpy_rad.x(), Eigen::Vector3d::UnitY()))
      .toRotationMatrix();
}

Eigen::Isometry3d HeadGeometry::MountPose() const {
  Eigen::Isometry3d head_T_camera = Eigen::Isometry3d::Identity();
  head_T_camera.translation() = optical_centre_H;
  head_T_camera.linear() = MountRotation() * HeadFromCameraRotation();
  return head_T_camera;
}

Eigen::Isometry3d HeadGeometry::HeadFromCamera() const {
  const Eigen::Isometry3d tilt_zero(Eigen::AngleAxisd(tilt_zero_rad, Eigen::Vector3d::UnitX()));
  return tilt_zero * MountPose();
}

HeadGeometry HeadGeometry::FoldTiltZero() const {
  HeadGeometry folded = *this;
  const Eigen::Isometry3d head_T_camera = HeadFromCamera();
  folded.tilt_zero_rad = 0;
  folded.optical_centre_H = head_T_camera.translation();
  folded.mount_rpy_rad =
      MountRpyFromRotation(head_T_camera.linear() * HeadFromCameraRotation().transpose());
  return folded;
}

Eigen::Vector3d MountRpyFromRotation(const Eigen::Matrix3d& r) {
  // R = Rz(y) Rx(p) Ry(r): R(2,1) = sin p, R(0,1) = -sin y cos p,
  // R(1,1) = cos y cos p, R(2,0) = -cos p sin r, R(2,2) = cos p cos r.
  const double pitch = std::asin(std::clamp(r(2, 1), -1.0, 1.0));
  const double yaw = std::atan2(-r(0, 1), r(1, 1));
  const double roll = std::atan2(-r(2, 0), r(2, 2));
  return {roll, pitch, yaw};
}

Eigen::Isometry3d RigGeometry::WorldFromHead(Side side, const CameraStage& stage) const {
  const HeadGeometry& head = (*this)[side];
  Eigen::Isometry3d world_T_head = Eigen::Isometry3d::Identity();
  world_T_head.translation() = head.rail_zero_W + stage.carriage_m * Eigen::Vector3d::UnitX();
  world_T_head.linear() =
      (Eigen::AngleAxisd(stage.pan_rad + head.pan_zero_rad, Eigen::Vector3d::UnitZ()) *
       Eigen::AngleAxisd(stage.tilt_rad + head.tilt_zero_rad, Eigen::Vector3d::UnitX()))
          .toRotationMatrix();
  return world_T_head;
}

CameraStage RigGeometry::FacingStage(Side side, double carriage_m,
                                     const Eigen::Vector3d& p_W) const {
  const HeadGeometry& head = (*this)[side];
  const Eigen::Vector3d v = p_W - WorldFromHead(side, {carriage_m, 0, 0}).translation();
  return {carriage_m, std::atan2(-v.x(), v.y()) - head.pan_zero_rad,
          std::atan2(v.z(), std::hypot(v.x(), v.y())) - head.tilt_zero_rad};
}

CameraStage RigGeometry::ParallelStage(Side side, double carriage_m) const {
  const HeadGeometry& head = (*this)[side];
  // The optical axis in the head frame at zero readings, before the zeros:
  // Rz(p + pan_zero) Rx(t + tilt_zero) d = +y. Tilt first lays d level
  // (its z to 0), then pan turns it forward.
  const Eigen::Vector3d d = head.MountPose().linear().col(2);
  const double tilt = std::atan2(-d.z(), d.y());
  const double level_y = d.y() * std::cos(tilt) - d.z() * std::sin(tilt);
  const double pan = std::atan2(d.x(), level_y);
  return {carriage_m, pan - head.pan_zero_rad, tilt - head.tilt_zero_rad};
}

Eigen::Isometry3d RigGeometry::WorldFromCamera(Side side, const CameraStage& stage) const {
  // WorldFromHead turns by the tilt zero already: the mount alone here.
  return WorldFromHead(side, stage) * (*this)[side].MountPose();
}

}  // namespace rig
