// Stereo calibration from chessboard views (OpenCV), and a synthetic set of
// such views rendered by the simulator at known poses to test it against.
#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "rig/calibration.h"

namespace experiments {

struct CalibrationResult {
  rig::RigCalibration
      calibration;  ///< intrinsics and distortion; head offsets zero (not identifiable)
  cv::Mat r_right_left, t_right_left;  ///< right camera from left camera
  double baseline_m = 0;               ///< |T|
  double rms_left_px = 0, rms_right_px = 0, rms_stereo_px = 0;
  int views = 0;                     ///< pairs with the board found in both images
  std::vector<std::string> skipped;  ///< files where it was not found
};

/// Finds a board of `cols` x `rows` inner corners, `square_m` apart, in each
/// left/right pair (sorted file lists of equal length), calibrates each
/// camera (k1, k2, p1, p2, k3) and then the pair with the intrinsics fixed.
/// Throws UsageError on unreadable files, mismatched sizes or fewer than 3
/// usable pairs.
CalibrationResult CalibrateStereo(const std::vector<std::string>& left_files,
                                  const std::vector<std::string>& right_files, int cols, int rows,
                                  double square_m);

/// Writes `views` pairs left_NN.png / right_NN.png of a chessboard (9 x 6
/// inner corners, `square_m` squares) rendered by the simulator at known,
/// varied poses in front of the rig at its home pose, into `dir`; returns
/// the true intrinsics of the left camera and the true baseline.
struct SyntheticTruth {
  double fx_px = 0, fy_px = 0, cx_px = 0, cy_px = 0, baseline_m = 0;
};
SyntheticTruth RenderChessboardViews(const std::string& dir, int views, double square_m,
                                     uint64_t seed);

/// Files matching a shell pattern, sorted; throws UsageError if none.
std::vector<std::string> Glob(const std::string& pattern);

}  // namespace experiments
