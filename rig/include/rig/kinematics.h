// Forward kinematics of the Texas Active Vision Testbed heads.
#pragma once

#include <Eigen/Geometry>

#include "rig/types.h"

namespace rig {

/// Where one head's camera sits. With carriage position s, pan p and tilt t:
///   world_T_head   = Translation(rail_zero_W + s * X) * Rz(p) * Rx(t)
///   head_T_camera  = Translation(optical_centre_H) * R_head_camera
/// where the head frame H is x right, y forward, z up at p = t = 0, and
/// R_head_camera maps the OpenCV camera axes (x right, y down, z forward) to
/// head x, -z, y. optical_centre_H is the offset of the optical centre from
/// the intersection of the pan and tilt axes (real cameras are offset).
struct HeadGeometry {
  Eigen::Vector3d rail_zero_W = Eigen::Vector3d::Zero();
  Eigen::Vector3d optical_centre_H = Eigen::Vector3d::Zero();
};

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
};

/// Rotation taking OpenCV camera axes to head axes (x -> x, y -> -z, z -> y).
Eigen::Matrix3d HeadFromCameraRotation();

}  // namespace rig
