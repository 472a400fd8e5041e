// The calibration file of a rig (OpenCV FileStorage YAML, written by `fovea
// calibrate` or by hand): what the hardware rig's kinematics and cameras use.
#pragma once

#include <Eigen/Core>
#include <string>

#include "rig/types.h"

namespace rig {

/// What a calibration file holds (OpenCV FileStorage YAML, written by
/// `fovea calibrate` or by hand): per camera the intrinsics with distortion
/// and the optical centre's offset from its pan/tilt axes (head frame).
struct RigCalibration {
  CameraIntrinsics left, right;
  Eigen::Vector3d left_optical_centre_H = Eigen::Vector3d::Zero();
  Eigen::Vector3d right_optical_centre_H = Eigen::Vector3d::Zero();
};
/// Reads a calibration file (a regular file of at most 64 MiB, OpenCV YAML).
/// Throws InputError naming the file and the missing or bad entry.
RigCalibration LoadCalibration(const std::string& path);
void SaveCalibration(const std::string& path, const RigCalibration& calibration);

}  // namespace rig
