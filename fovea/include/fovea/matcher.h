// Scanline stereo matchers for the foveated stage: any reasonable algorithm
// may be plugged in (paper section III-C). Images are one resolution level of
// the unrectified vergent pair; disparities are signed, d = x_left - x_right.
#pragma once

#include <opencv2/core.hpp>
#include <string>

namespace fovea {

/// Per-pixel disparity at one level: NaN where there is none.
struct DisparityMap {
  cv::Mat disparity_px;  ///< CV_32F
  cv::Mat confidence;    ///< CV_32F in [0, 1]; 0 where no disparity
  int searched = 0, matched = 0, rejected_texture = 0, rejected_lr = 0, rejected_edge = 0;
};

class StereoMatcher {
 public:
  virtual ~StereoMatcher() = default;
  /// Matches every left pixel with lo_px <= hi_px (CV_32F maps, same size as
  /// the images) along its row, searching d in [lo, hi].
  virtual DisparityMap Match(const cv::Mat& left, const cv::Mat& right, const cv::Mat& lo_px,
                             const cv::Mat& hi_px) const = 0;
  virtual std::string Name() const = 0;
};

struct Nl1Options {
  int window_half_px = 3;        ///< a 7 x 7 window
  double min_texture_dn = 2.0;   ///< mean absolute deviation of the left window
  double lr_tolerance_px = 1.0;  ///< left-right check
  /// Beyond the paper: a pixel whose window of this half width has a faint
  /// texture (standard deviation below weak_texture_dn) is matched with that
  /// wider window instead of window_half_px's, and every other pixel with
  /// the narrow one. On a faint texture the sensor's noise swamps a 7 x 7
  /// window; a wide window that holds a strong edge or texture anywhere is
  /// not faint, so the wide windows never reach across such an edge. 0, or
  /// not wider than window_half_px: one window everywhere, the paper's.
  /// 11 x 11 below 5 grey levels: with the fallback after stalled fixations
  /// and the map's reading rule, over the accuracy benchmark (and its
  /// held-out seeds) it mapped the faint surfaces, gained good coverage and
  /// kept every accuracy figure, for a few more wrong pixels (README, "The
  /// map's trust"); before them it broke the catalog's RMSE line.
  int weak_window_half_px = 5;
  double weak_texture_dn = 5;
  /// "window_mean" (the paper's) or "prenormalized" (params::kNl1Cost).
  std::string cost = "window_mean";
  void Check() const;  ///< throws rig::InputError naming the key (fovea/params.h)
};

/// Normalized L1 window matching, winner-take-all, equiangular sub-pixel
/// refinement, left-right consistency check (the matched right pixel's own
/// winner among the left pixels whose bands reach it; the two views'
/// sub-pixel estimates are averaged); confidence from the margin between the
/// best and the second-best non-adjacent cost. The cost is the mean absolute
/// difference of mean-free windows: by default the paper's sum |(L - mean L)
/// - (R - mean R)| with the means of the two windows compared, or each image
/// less its local mean over twice the window (pre-normalized, so that window
/// sums run: several times faster, but beside depth edges the two views'
/// local means differ and the map's edges come out worse; README, "The
/// foveated matcher"). Costs are computed per strip of rows, each disparity
/// only over the columns whose bands hold it, once for both directions of
/// the left-right check.
class Nl1Matcher : public StereoMatcher {
 public:
  explicit Nl1Matcher(const Nl1Options& options = {});
  DisparityMap Match(const cv::Mat& left, const cv::Mat& right, const cv::Mat& lo_px,
                     const cv::Mat& hi_px) const override;
  std::string Name() const override { return "nl1"; }

 private:
  /// Match on a crop that holds every searched pixel (`searched` of them:
  /// lo <= hi) with its window and the right columns its band reaches;
  /// writes into `out`'s maps (views of the crop, initialized) and counts
  /// into its counters.
  static void MatchCrop(const Nl1Options& options, const cv::Mat& left, const cv::Mat& right,
                        const cv::Mat& lo_px, const cv::Mat& hi_px, int searched,
                        DisparityMap* out);
  /// Match() with one window size, `options`'.
  static DisparityMap MatchOneWindow(const Nl1Options& options, const cv::Mat& left,
                                     const cv::Mat& right, const cv::Mat& lo_px,
                                     const cv::Mat& hi_px);
  Nl1Options options_;
};

}  // namespace fovea
