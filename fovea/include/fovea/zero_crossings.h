// Laplacian-of-Gaussian zero crossings: IDR's matching primitive (paper
// section II-A). Only crossings along image rows are kept: matching runs along
// scanlines.
#pragma once

#include <opencv2/core.hpp>
#include <vector>

namespace fovea {

struct ZeroCrossingOptions {
  double sigma_px = 3.0;  ///< LoG scale; the paper used 2.5 to 3.5
  /// A crossing counts only if the LoG (normalized: sigma^2 times the
  /// Laplacian of the blurred image, grey levels) changes by at least this
  /// much across it. Measured at sigma 3 on 640x480 images of pure Gaussian
  /// noise: slopes reach 0.28 / 0.51 / 0.98 (maximum) at noise sigma 1 / 2 /
  /// 4 grey levels (about 0.25 times the noise sigma), while the catalog's
  /// textures put 90% of their crossings above 0.33 to 0.98. 0.6 keeps
  /// homogeneous regions free of crossings up to noise sigma 2.3.
  double min_slope = 0.6;
  void Check() const;  ///< throws rig::InputError naming the key (fovea/params.h)
};

/// One zero crossing between pixels (x, y) and (x + 1, y).
struct ZeroCrossing {
  float x_px;             ///< sub-pixel column where the LoG crosses zero
  int y_px;               ///< row
  signed char polarity;   ///< +1 where the LoG rises left to right, -1 where it falls
  float orientation_rad;  ///< direction of the LoG gradient, atan2(gy, gx), in (-pi, pi]
  float slope;            ///< |LoG(x + 1) - LoG(x)|
};

/// Zero crossings of one image, sorted by row then column, with an index of
/// where each row's crossings start.
struct ZeroCrossingImage {
  std::vector<ZeroCrossing> crossings;
  std::vector<int>
      row_begin;  ///< size rows + 1: row y's crossings are [row_begin[y], row_begin[y+1])
  cv::Mat log;    ///< the normalized LoG response, CV_32F

  int rows() const { return static_cast<int>(row_begin.size()) - 1; }
};

/// LoG-filters a CV_8UC1 image and extracts its horizontal zero crossings.
/// `options` must have passed Check(): the run checks them once, before
/// its work (RunFovea, RunIdr, RunConfig::Check), never per call.
ZeroCrossingImage ExtractZeroCrossings(const cv::Mat& gray, const ZeroCrossingOptions& options);

/// For each crossing, the distance in pixels to the next crossing of the same
/// polarity on its row (its local period); +infinity for the last one.
std::vector<float> SamePolarityPeriods(const ZeroCrossingImage& zc);

/// The largest disparity d_max such that at least `unique_share` of the
/// crossings have a period greater than d_max (paper section II-A: a search
/// window narrower than a crossing's period holds only its true match).
/// Returns 0 if there are no crossings.
double UnambiguousDisparityLimit(const std::vector<float>& periods, double unique_share);

}  // namespace fovea
