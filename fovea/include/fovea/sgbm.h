// OpenCV's StereoSGBM as the second matcher, for comparison with NL1.
#pragma once

#include <opencv2/core.hpp>

#include "fovea/matcher.h"
#include "rig/types.h"

namespace fovea {

struct SgbmOptions {
  int block_size = 5;
  int uniqueness_ratio = 5;
  int speckle_window = 50;
  int speckle_range = 2;
  void Check() const;  ///< throws rig::InputError naming the key (fovea/params.h)
};

/// StereoSGBM plugged into the foveated stage: it runs on one level's
/// images, whose rows the tessellation has aligned to half a pixel, over one
/// global range covering every pixel's [lo, hi]; results outside a pixel's
/// own range are dropped.
class SgbmMatcher : public StereoMatcher {
 public:
  explicit SgbmMatcher(const SgbmOptions& options = {}) : options_(options) {}
  DisparityMap Match(const cv::Mat& left, const cv::Mat& right, const cv::Mat& lo_px,
                     const cv::Mat& hi_px) const override;
  std::string Name() const override { return "sgbm"; }

 private:
  SgbmOptions options_;
};

/// StereoSGBM on a rectified copy of a full vergent pair (cv::stereoRectify
/// from the poses and intrinsics), searching the rectified disparities of
/// depths in [min_depth_m, max_depth_m]. Returns, per left (unrectified)
/// pixel, the planar depth in the left camera (CV_32F, 0 where none).
cv::Mat RectifiedSgbmDepth(const rig::CameraView& left, const rig::CameraView& right,
                           double min_depth_m, double max_depth_m, const SgbmOptions& options = {});

}  // namespace fovea
