// Forward kinematics of the Texas Active Vision Testbed heads.
#pragma once

#include <Eigen/Geometry>

#include "rig/types.h"

namespace rig {

/// Where one head's camera sits. With carriage position s and pan and tilt
/// readings p and t (what the stages report):
///   world_T_head   = Translation(rail_zero_W + s * X) * Rz(p + pan_zero) * Rx(t + tilt_zero)
///   head_T_camera  = Translation(optical_centre_H) * R_mount * R_head_camera
/// where the head frame H is x right, y forward, z up at p = t = 0, and
/// R_head_camera maps the OpenCV camera axes (x right, y down, z forward) to
/// head x, -z, y. optical_centre_H is the offset of the optical centre from
/// the intersection of the pan and tilt axes (real cameras are offset);
/// R_mount = Rz(yaw) * Rx(pitch) * Ry(roll) is the camera's mounting rotation
/// against its head (roll about the forward axis, pitch about x, yaw about
/// z); pan_zero and tilt_zero are the encoders' home errors: the true angle
/// is the reading plus the zero. An ideal head has all of these zero but
/// the offset.
///
/// To any camera, the tilt zero and the mount are one rotation:
/// Rx(tilt_zero) * (R_mount, optical_centre_H) is a mount with tilt_zero 0
/// that images exactly the same. Calibration therefore folds the tilt zero
/// into the mount (HeadGeometry::FoldTiltZero).
struct HeadGeometry {
  Eigen::Vector3d rail_zero_W = Eigen::Vector3d::Zero();
  Eigen::Vector3d optical_centre_H = Eigen::Vector3d::Zero();
  Eigen::Vector3d mount_rpy_rad = Eigen::Vector3d::Zero();  ///< roll, pitch, yaw
  double pan_zero_rad = 0, tilt_zero_rad = 0;

  /// R_mount from mount_rpy_rad.
  Eigen::Matrix3d MountRotation() const;
  /// The mount alone: Translation(optical_centre_H) * R_mount * R_head_camera.
  Eigen::Isometry3d MountPose() const;
  /// head_T_camera at pan = tilt = 0 (readings), the zeros included: the
  /// camera's pose in the head frame that a calibration can observe.
  Eigen::Isometry3d HeadFromCamera() const;
  /// The same head with its tilt zero folded into the mount: images the same.
  HeadGeometry FoldTiltZero() const;
};

/// Roll, pitch, yaw of R = Rz(yaw) * Rx(pitch) * Ry(roll) (pitch within
/// +-90 degrees), the inverse of HeadGeometry::MountRotation.
Eigen::Vector3d MountRpyFromRotation(const Eigen::Matrix3d& r);

/// Geometry of both heads.
struct RigGeometry {
  HeadGeometry left, right;

  const HeadGeometry& operator[](Side side) const { return side == Side::kLeft ? left : right; }

  /// Pose of the pan/tilt axes intersection (head frame) in the world.
  Eigen::Isometry3d WorldFromHead(Side side, const CameraStage& stage) const;
  /// Pose of the camera (OpenCV frame) in the world.
  Eigen::Isometry3d WorldFromCamera(Side side, const CameraStage& stage) const;
  /// Pan and tilt (two atan2 calls) that turn one head, its carriage at
  /// `carriage_m`, so that its forward axis runs from the pan/tilt axes'
  /// intersection through p_W: the camera faces p_W, exactly when the
  /// optical centre lies on the axes (else Verge refines it).
  CameraStage FacingStage(Side side, double carriage_m, const Eigen::Vector3d& p_W) const;
  /// Pan and tilt readings that point the camera's optical axis along world
  /// +y (straight ahead, level), its carriage at `carriage_m`: both cameras
  /// so placed are parallel whatever their mounts and encoder zeros. Pan =
  /// tilt = 0 for a head without either.
  CameraStage ParallelStage(Side side, double carriage_m) const;
};

/// Rotation taking OpenCV camera axes to head axes (x -> x, y -> -z, z -> y).
Eigen::Matrix3d HeadFromCameraRotation();

}  // namespace rig
