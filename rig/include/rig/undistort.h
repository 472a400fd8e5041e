// Undistortion on capture, shared by every rig: frames leave a rig as
// pinhole images with the same focal lengths and principal point.
#pragma once

#include <opencv2/core.hpp>

#include "rig/types.h"

namespace rig {

/// Remaps images of a camera with lens distortion to the pinhole camera of
/// the same K (OpenCV's model and maps, computed once per camera: a frame
/// costs one remap).
class Undistorter {
 public:
  Undistorter() = default;
  /// `k`'s distortion all zero (or none): Apply copies nothing and returns
  /// the image as it is.
  explicit Undistorter(const CameraIntrinsics& k);

  /// Whether the camera has any distortion to remove.
  bool Active() const { return !map_x_.empty(); }
  /// The undistorted image (bicubic); `raw` itself when not Active().
  cv::Mat Apply(const cv::Mat& raw) const;
  /// `k` without its distortion: what an undistorted frame reports.
  static CameraIntrinsics Pinhole(const CameraIntrinsics& k);

 private:
  cv::Mat map_x_, map_y_;
};

}  // namespace rig
