// Head calibration: each camera's intrinsics and distortion, its pose in its
// tilt frame (the hand-eye problem) and its pan encoder's zero, from
// chessboard views taken with the rig at many stage states; and a
// simulator-rendered set of such views of a known imperfect rig to test it.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "rig/calibration.h"
#include "rig/rig.h"
#include "sim/config.h"

namespace experiments {

/// One image pair of a head calibration: the stage readings it was taken
/// at and which board placement it shows (the board stays put within a
/// placement while the rig moves).
struct HeadView {
  rig::StageState state;
  std::string left, right;  ///< image files
  int placement = 0;
};

/// Reads views.yaml: `views:` a list of {left, right, placement, state: [6
/// numbers, metres and radians in StageState::ToArray order]}; image paths
/// relative to the file's folder. Throws UsageError naming the file and entry.
/// With `images` false, the images may be absent (a plan of stage states
/// to capture at).
std::vector<HeadView> LoadHeadViews(const std::string& path, bool images = true);
/// Writes views.yaml (atomically), image paths as given.
void SaveHeadViews(const std::string& path, const std::vector<HeadView>& views);

/// What CalibrateHead recovers, with its spread.
struct HeadCalibrationResult {
  /// Intrinsics and distortion (k1, k2, p1, p2, and k3 held at 0), and per head the
  /// optical centre, mount rotation and pan zero. The tilt zero is written
  /// 0 and folded into the mount (no camera can tell them apart, see
  /// rig::HeadGeometry).
  rig::RigCalibration calibration;
  double rms_px = 0;  ///< reprojection RMS over every corner of the joint fit
  std::array<double, 2> rms_intrinsics_px{};  ///< cv::calibrateCamera's, per camera
  std::array<int, 2> views{};                 ///< views with the board found, per camera
  int placements = 0;
  std::vector<std::string> skipped;  ///< files where the board was not found
  /// One standard deviation of each estimate (from the fit's covariance),
  /// per camera: focal length px, mount rotation deg (largest axis),
  /// optical centre m (largest axis), pan zero deg.
  std::array<double, 2> focal_sd_px{}, mount_sd_deg{}, centre_sd_m{}, pan_zero_sd_deg{};
};

/// Finds a board of `cols` x `rows` inner corners `square_m` apart in every
/// view, calibrates each camera's intrinsics (OpenCV), solves the hand-eye
/// problem for a start (OpenCV's calibrateHandEye, Tsai) and refines every
/// parameter of both kinematic chains and every board placement jointly by
/// Levenberg-Marquardt on the reprojection error. Throws UsageError, one
/// line, for a board of another size, too few views or stage states, or a
/// chain the views cannot determine (naming the parameter and what to vary).
HeadCalibrationResult CalibrateHead(const std::vector<HeadView>& views, int cols, int rows,
                                    double square_m);

/// What a calibration's errors do to depth: a grid of points around
/// fixation points 0.7 to 1.3 m ahead, within 15 degrees of straight ahead
/// and 8 of level; the cameras verged on each through `belief`'s chain, 0.06
/// m apart (a fixation's baseline); each point imaged by the `truth` rig,
/// its pixels undistorted with `belief`'s lens and triangulated with
/// `belief`'s chain. Relative error: the triangulated point's distance from
/// the true one over the true one's distance from the left camera.
struct CalibrationDepthError {
  double median_rel = 0, p90_rel = 0;
  /// How far the two believed rays miss each other at the point, as pixels
  /// of the left camera there (vertical disparity after rectification).
  double median_miss_px = 0, p90_miss_px = 0;
  int points = 0;  ///< points both true cameras image
};
CalibrationDepthError DepthErrorAgainst(const rig::RigCalibration& truth,
                                        const rig::RigCalibration& belief);

/// Captures a head-calibration set with any rig: for each entry of `plan` in
/// order, moves to its stage state, grabs a raw pair (distortion kept) and
/// writes left_NN.png, right_NN.png; then views.yaml with the readings the
/// stages report and each entry's placement. `before_placement` is called
/// before the first view of each placement (to let someone move the board).
/// Throws rig::RigError for a state the rig refuses or a failed capture.
void CaptureHeadViews(rig::Rig& rig, const std::vector<HeadView>& plan, const std::string& dir,
                      const std::function<void(int placement)>& before_placement);

/// Renders a head-calibration set with the simulated rig `config` (its
/// imperfections included): `placements` board placements (9 x 6 inner
/// corners, `square_m` squares, about 0.8 m away at different heights and
/// slants), `views_per_placement` stage states each (carriages, pans and
/// tilts drawn from `seed`, the board kept in both views). Writes
/// left_NN.png, right_NN.png (raw: distortion kept) and views.yaml into
/// `dir`; returns the rig's true calibration (its tilt zeros not folded).
rig::RigCalibration RenderHeadChessboards(const std::string& dir, const sim::SimRigConfig& config,
                                          int placements, int views_per_placement, double square_m,
                                          uint64_t seed);

}  // namespace experiments
