// What frames leave a rig as, shared by every rig: the images of two
// pinhole cameras with one K, no distortion, each aligned with its head.
#pragma once

#include <Eigen/Core>
#include <array>
#include <opencv2/core.hpp>

#include "rig/calibration.h"
#include "rig/types.h"

namespace rig {

/// Remaps the images of a camera (its K and lens distortion, OpenCV's
/// model) to those of a pinhole camera at the same optical centre, turned
/// by a rotation and with another K: OpenCV's rectification maps, computed
/// once per camera, so that a frame costs one remap.
class Undistorter {
 public:
  Undistorter() = default;
  /// `delivered_R_raw` takes the raw camera's axes to the delivered one's.
  /// When it is the identity, `raw` has no distortion and `delivered` its
  /// K, Apply copies nothing and returns the image as it is.
  Undistorter(const CameraIntrinsics& raw, const Eigen::Matrix3d& delivered_R_raw,
              const CameraIntrinsics& delivered);

  /// Whether the remap moves any pixel.
  bool Active() const { return !map_x_.empty(); }
  /// The delivered image (bicubic); `raw` itself when not Active().
  cv::Mat Apply(const cv::Mat& raw) const;
  /// For every delivered pixel, the raw pixel it samples (CV_32FC1; empty
  /// when not Active()).
  const cv::Mat& MapX() const { return map_x_; }
  const cv::Mat& MapY() const { return map_y_; }
  /// `k` without its distortion.
  static CameraIntrinsics Pinhole(const CameraIntrinsics& k);

 private:
  cv::Mat map_x_, map_y_;
};

/// How a rig delivers the frames of a calibrated pair (unless asked for raw
/// ones): as the images of pinhole cameras that both have the left camera's
/// K and no distortion, each at its calibrated optical centre and aligned
/// with its head (no mounting rotation). A mount's rotation is about the
/// optical centre and never changes, so one bicubic remap per frame removes
/// it together with the lens distortion and the pair's difference in K.
/// What is left for the algorithms is an ideal pair's geometry: a fixation
/// frame resamples only what an ideal rig's would. (Leaving the mounts' roll to
/// each fixation frame's bilinear resampling of an undistorted image cost
/// fine texture: with the rig of issue 22 and its exact calibration,
/// cylinder_planes' median error was 0.71 mm that way and is 0.62 mm so,
/// the ideal rig's 0.63.)
struct DeliveredPair {
  explicit DeliveredPair(const RigCalibration& calibration);

  RigGeometry raw_geometry;              ///< the calibration's: raw captures' poses
  RigGeometry geometry;                  ///< the same, every mount rotation zero
  CameraIntrinsics intrinsics;           ///< both cameras': the left one's, without distortion
  std::array<Undistorter, 2> undistort;  ///< raw -> delivered, per side
  /// Per side, the rotation from the raw camera's axes to the delivered
  /// one's (the calibrated mount, in camera axes).
  std::array<Eigen::Matrix3d, 2> delivered_R_raw;
};

}  // namespace rig
