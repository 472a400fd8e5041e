// Visual servoing of the fixation (paper section III): find the disparity of
// the left image's centre window in the right image with the normalized L1
// cost, and null it by turning the right camera.
#pragma once

#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "fovea/fixation_frame.h"
#include "rig/rig.h"

namespace fovea {

/// Normalized L1 cost of two (2 half + 1)^2 windows centred at integer
/// pixels: mean over the window of |(L - mean L) - (R - mean R)|, grey
/// levels. Windows must lie inside their images.
double NormalizedL1(const cv::Mat& left, int xl, int yl, const cv::Mat& right, int xr, int yr,
                    int half);

struct ServoOptions {
  int window_half_px = 15;  ///< a 31 x 31 window
  int search_px = 40;       ///< first measurement: horizontal search +- this many pixels
  /// Later measurements, after a move that nulled the last one d: +- the
  /// larger of this and |d| / 4 (a move is good to a few per cent).
  int refine_px = 8;
  double tolerance_px = 0.5;  ///< done when the residual disparity is below this
  int max_steps = 6;          ///< step budget
  /// A search over a depth range (see Servo) keeps its best match only if
  /// its cost is below this share of the best match elsewhere (a repeated
  /// texture's other copies): 1 keeps any minimum.
  double unique_ratio = 0.85;
  /// Beyond the paper: a converged servo's match must be mutual, i.e. the
  /// right image's centre window, searched +- search_px along the left
  /// image's row, must find the left centre within this many pixels;
  /// otherwise the right camera sees another surface (an occluder, a
  /// repeated texture's copy) and the servo has not converged. 0: no check.
  double mutual_tolerance_px = 4.0;
  /// Measure in the pair's fixation frame (ToFixationFrame), the frame the
  /// foveal stereo matches in. Set by Fixate from foveal.rectify, not a
  /// parameter of its own.
  bool rectify = true;
  void Check() const;  ///< throws rig::InputError naming the key (fovea/params.h)
};

/// Depths along the left optical axis, metres.
struct DepthRange {
  double near_m = 0, far_m = 0;
};

/// Where the left image's centre window appears in the right image, searched
/// +- search_px about the right principal point, as a horizontal offset in
/// pixels from it (sub-pixel by
/// a parabola through the cost minimum); nullopt if the minimum is at the
/// edge of the search or the window has no texture (mean absolute deviation
/// under 2 grey levels).
std::optional<double> CentreDisparity(const rig::StereoFrame& frame, const ServoOptions& options,
                                      int search_px);

/// The same over the right-image positions of the points at `depths` on the
/// left optical axis (their projections, one pixel of margin), keeping the
/// best match only if it is unique (options.unique_ratio); nullopt also when
/// it is not.
std::optional<double> CentreDisparity(const rig::StereoFrame& frame, const ServoOptions& options,
                                      const DepthRange& depths);

/// Whether the left image's window at `pixel` has one clear match among the
/// right image's windows at the projections of the depths [near, far] along
/// its ray (normalized L1, windows of options.window_half_px, unique as in
/// the depth-range CentreDisparity: no other minimum within
/// options.unique_ratio of the best, and the best not at the range's end);
/// with options.mutual_tolerance_px, that match's window must also find its
/// best match along its own ray, over the same depths, within that many
/// pixels of `pixel` (the servo's mutual check, asked in advance).
/// For any pair, verged or not: the loop asks it of a hole before moving
/// the rig there, from the images it has.
bool UniqueAlongRay(const rig::StereoFrame& frame, const Eigen::Vector2d& pixel,
                    const DepthRange& depths, const ServoOptions& options);

/// The reverse of CentreDisparity: where the right image's centre window
/// appears in the left image, searched +- options.search_px along its row,
/// against where the left centre's match `residual_px` (CentreDisparity's
/// answer) puts it; pixels, nullopt if the reverse search finds no match.
/// Near 0 when both cameras see the same surface at their centres.
std::optional<double> MutualMismatch(const rig::StereoFrame& frame, const ServoOptions& options,
                                     double residual_px);

struct ServoResult {
  bool converged = false;
  /// With options.mutual_tolerance_px, once the residual is within
  /// tolerance: MutualMismatch there, and whether it is within
  /// mutual_tolerance_px (if not, converged is false).
  std::optional<double> mutual_mismatch_px;
  bool mutual = true;
  int iterations = 0;                ///< moves made after the first
  double residual_px = 0;            ///< last measured centre disparity
  std::vector<double> residuals_px;  ///< one per measurement
  rig::StageState state;             ///< where the rig ended
  rig::StereoFrame frame;            ///< the last pair captured
  /// That pair as measured (ToFixationFrame with options.rectify, else
  /// OriginalFrame): the frame the foveal stereo matches in.
  FixationFrame measured;
  double motion_time_s = 0;
};

/// Moves to `start`, then repeats: capture, measure the centre disparity d,
/// turn the right camera by -atan(d / f), until |d| < tolerance or the step
/// budget is spent. The first measurement searches +- search_px about the
/// start, or, given `first_depths` (the start's depth is a guess), every
/// position a point at those depths can take. Throws rig::RigError if the
/// rig refuses a move.
/// `options` must have passed Check(): the run checks them once, before
/// its work (RunFovea, RunIdr, RunConfig::Check), never per call.
ServoResult Servo(rig::Rig& rig, const rig::StageState& start, const ServoOptions& options,
                  const std::optional<DepthRange>& first_depths = std::nullopt);

}  // namespace fovea
