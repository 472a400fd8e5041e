#include "fovea/zero_crossings.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "fovea/params.h"

namespace fovea {

void ZeroCrossingOptions::Check() const {
  rig::CheckParam(params::kIdrLogSigmaPx, sigma_px);
  rig::CheckParam(params::kIdrLogMinSlope, min_slope);
}

ZeroCrossingImage ExtractZeroCrossings(const cv::Mat& gray, const ZeroCrossingOptions& options) {
  CV_Assert(gray.type() == CV_8UC1);
  ZeroCrossingImage out;
  cv::Mat f, blurred;
  gray.convertTo(f, CV_32F);
  cv::GaussianBlur(f, blurred, cv::Size(0, 0), options.sigma_px, options.sigma_px,
                   cv::BORDER_REPLICATE);
  cv::Laplacian(blurred, out.log, CV_32F, 1, options.sigma_px * options.sigma_px, 0,
                cv::BORDER_REPLICATE);
  cv::Mat gx, gy;
  cv::Sobel(out.log, gx, CV_32F, 1, 0, 3, 0.125);
  cv::Sobel(out.log, gy, CV_32F, 0, 1, 3, 0.125);

  // The filter's support reaches past the border; crossings there are unreliable.
  const int margin = static_cast<int>(std::ceil(2 * options.sigma_px));
  out.row_begin.assign(gray.rows + 1, 0);
  for (int y = 0; y < gray.rows; ++y) {
    out.row_begin[y] = static_cast<int>(out.crossings.size());
    if (y < margin || y >= gray.rows - margin) continue;
    const float* l = out.log.ptr<float>(y);
    for (int x = margin; x + 1 < gray.cols - margin; ++x) {
      const float a = l[x], b = l[x + 1];
      // A sign change between x and x + 1 (a zero at x counts once, on its right).
      if (!((a < 0 && b >= 0) || (a > 0 && b <= 0))) continue;
      const float slope = std::abs(b - a);
      if (slope < options.min_slope) continue;
      ZeroCrossing zc;
      zc.x_px = x + a / (a - b);
      zc.y_px = y;
      zc.polarity = b > a ? 1 : -1;
      // Gradient at the nearer pixel.
      const int xn = std::abs(a) < std::abs(b) ? x : x + 1;
      zc.orientation_rad = std::atan2(gy.at<float>(y, xn), gx.at<float>(y, xn));
      zc.slope = slope;
      out.crossings.push_back(zc);
    }
  }
  out.row_begin[gray.rows] = static_cast<int>(out.crossings.size());
  return out;
}

std::vector<float> SamePolarityPeriods(const ZeroCrossingImage& zc) {
  std::vector<float> periods(zc.crossings.size(), std::numeric_limits<float>::infinity());
  for (int y = 0; y < zc.rows(); ++y) {
    // Last seen index of each polarity, scanning right to left.
    int next[2] = {-1, -1};
    for (int i = zc.row_begin[y + 1] - 1; i >= zc.row_begin[y]; --i) {
      const int p = zc.crossings[i].polarity > 0 ? 1 : 0;
      if (next[p] >= 0) periods[i] = zc.crossings[next[p]].x_px - zc.crossings[i].x_px;
      next[p] = i;
    }
  }
  return periods;
}

double UnambiguousDisparityLimit(const std::vector<float>& periods, double unique_share) {
  if (periods.empty()) return 0;
  std::vector<float> sorted = periods;
  // The crossing at index k (ascending) bounds d_max for the share above it.
  const size_t allowed = static_cast<size_t>(std::floor((1.0 - unique_share) * sorted.size()));
  std::nth_element(sorted.begin(), sorted.begin() + allowed, sorted.end());
  const float p = sorted[allowed];  // at least `unique_share` of periods are >= p
  if (!std::isfinite(p)) return 1e9;
  // Periods must exceed d_max strictly; keep half a pixel of margin for
  // sub-pixel positions.
  return std::max(0.0, static_cast<double>(p) - 0.5);
}

}  // namespace fovea
