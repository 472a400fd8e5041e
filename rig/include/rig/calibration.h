// The calibration file of a rig (OpenCV FileStorage YAML, written by `fovea
// calibrate` or by hand): what the hardware rig's kinematics and cameras use.
#pragma once

#include <Eigen/Core>
#include <string>

#include "rig/kinematics.h"
#include "rig/types.h"

namespace rig {

/// The calibration file format this program writes; it reads this one and
/// the older ones.
///  1: intrinsics, distortion and optical_centre_H_m per camera (no version key).
///  2: adds `version`, and per camera mount_rpy_deg, pan_zero_deg, tilt_zero_deg.
inline constexpr int kCalibrationVersion = 2;

/// What a calibration file holds (OpenCV FileStorage YAML, written by
/// `fovea calibrate` or by hand): per camera the intrinsics with distortion
/// and its head: the optical centre's offset from its pan/tilt axes (head
/// frame), its mounting rotation and the pan and tilt encoders' zero
/// offsets (see HeadGeometry; rail_zero_W is not part of a calibration).
struct RigCalibration {
  int version = kCalibrationVersion;  ///< of the file it was read from
  CameraIntrinsics left, right;
  HeadGeometry left_head, right_head;

  const CameraIntrinsics& Intrinsics(Side side) const { return side == Side::kLeft ? left : right; }
  const HeadGeometry& Head(Side side) const { return side == Side::kLeft ? left_head : right_head; }
  /// The rig's kinematics as this calibration has it: both heads, their
  /// rail zeros at the world origin (the rail's centre).
  RigGeometry Geometry() const;
};
/// Reads a calibration file (a regular file of at most 64 MiB, OpenCV YAML,
/// format version 1 or 2). Throws InputError naming the file and the
/// missing or bad entry, or a version newer than kCalibrationVersion.
RigCalibration LoadCalibration(const std::string& path);
void SaveCalibration(const std::string& path, const RigCalibration& calibration);
/// Throws InputError unless both cameras of `calibration` (read from
/// `path`) are for images of width_px x height_px (rig.width_px, rig.height_px).
void CheckCalibrationSize(const RigCalibration& calibration, const std::string& path, int width_px,
                          int height_px);

}  // namespace rig
