// The baseline FOVEA is compared with: StereoSGBM on a static parallel pair,
// its depth turned into patches so that the same scoring applies.
#pragma once

#include <opencv2/core.hpp>

#include "fovea/patch.h"
#include "rig/rig.h"

namespace experiments {

struct StaticSgbmOptions {
  double baseline_m = 0;     ///< 0: the widest useful one (see StaticBaseline)
  double min_depth_m = 0.4;  ///< nearest scene depth searched
  int block_px = 8;          ///< patch size, pixels (as the fovea's)
};

struct StaticSgbmResult {
  fovea::PatchMap map;
  double baseline_m = 0;
  double motion_time_s = 0, compute_time_s = 0;
  long depth_pixels = 0;  ///< pixels SGBM gave a depth
};

/// The widest baseline the rig's carriages allow at which a point at
/// `min_depth_m` straight ahead still has a disparity of at most half the
/// image width (wider pairs share too little of their views).
double StaticBaseline(const rig::Rig& rig, double min_depth_m);

/// Block plane fits of a planar-depth image (CV_32F, 0 = none) of `view`:
/// fitted in fb / Z, which is affine in the image for a plane, with a 1 px
/// tolerance; every patch is full-resolution (level foveal, resolution 0).
fovea::PatchMap DepthToPatches(const rig::CameraView& view, const cv::Mat& depth_m, double fb_px,
                               int block_px);

/// Moves to the home pose's heads at the static baseline, captures, runs
/// StereoSGBM on the rectified pair and fits patches.
StaticSgbmResult RunStaticSgbm(rig::Rig& rig, const StaticSgbmOptions& options);

}  // namespace experiments
