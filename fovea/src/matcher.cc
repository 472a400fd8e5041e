#include "fovea/matcher.h"

#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <vector>

#include "fovea/params.h"

namespace fovea {

void Nl1Options::Check() const {
  rig::CheckParam(params::kNl1WindowHalfPx, window_half_px);
  rig::CheckParam(params::kNl1MinTextureDn, min_texture_dn);
  rig::CheckParam(params::kNl1LrTolerancePx, lr_tolerance_px);
}

Nl1Matcher::Nl1Matcher(const Nl1Options& options) : options_(options) { options_.Check(); }

namespace {

// NL1 cost of the windows at integer centres, using precomputed window means.
inline float Cost(const cv::Mat& l, const cv::Mat& r, const cv::Mat& ml, const cv::Mat& mr, int x,
                  int y, int xr, int h) {
  const float offset = ml.at<float>(y, x) - mr.at<float>(y, xr);
  float c = 0;
  for (int dy = -h; dy <= h; ++dy) {
    const uchar* pl = l.ptr<uchar>(y + dy) + x;
    const uchar* pr = r.ptr<uchar>(y + dy) + xr;
    for (int dx = -h; dx <= h; ++dx) c += std::abs(static_cast<float>(pl[dx]) - pr[dx] - offset);
  }
  return c / ((2 * h + 1) * (2 * h + 1));
}

struct Best {
  int d = 0;
  float cost = std::numeric_limits<float>::infinity();
  float second = std::numeric_limits<float>::infinity();
  double sub = 0;
  bool edge = false;
};

// Searches d in [lo, hi] (integers) for the left pixel (x, y) against the
// right image (or the reverse when `reverse`: right pixel x, left at x + d).
Best Search(const cv::Mat& a, const cv::Mat& b, const cv::Mat& ma, const cv::Mat& mb, int x, int y,
            int lo, int hi, int h, bool reverse, std::vector<float>& costs) {
  Best best;
  costs.assign(hi - lo + 1, std::numeric_limits<float>::infinity());
  for (int d = lo; d <= hi; ++d) {
    const int xb = reverse ? x + d : x - d;
    if (xb - h < 0 || xb + h >= b.cols) continue;
    costs[d - lo] = Cost(a, b, ma, mb, x, y, xb, h);
  }
  int bi = -1;
  for (int i = 0; i < static_cast<int>(costs.size()); ++i)
    if (std::isfinite(costs[i]) && (bi < 0 || costs[i] < costs[bi])) bi = i;
  if (bi < 0) return best;
  best.d = lo + bi;
  best.cost = costs[bi];
  for (int i = 0; i < static_cast<int>(costs.size()); ++i)
    if (std::abs(i - bi) > 1) best.second = std::min(best.second, costs[i]);
  if (bi == 0 || bi + 1 == static_cast<int>(costs.size()) || !std::isfinite(costs[bi - 1]) ||
      !std::isfinite(costs[bi + 1])) {
    best.edge = true;
    return best;
  }
  const double c0 = costs[bi - 1], c1 = costs[bi], c2 = costs[bi + 1];
  const double denom = c0 - 2 * c1 + c2;
  best.sub = denom > 0 ? std::clamp(0.5 * (c0 - c2) / denom, -0.5, 0.5) : 0.0;
  return best;
}

}  // namespace

DisparityMap Nl1Matcher::Match(const cv::Mat& left, const cv::Mat& right, const cv::Mat& lo_px,
                               const cv::Mat& hi_px) const {
  CV_Assert(left.type() == CV_8UC1 && right.type() == CV_8UC1 && left.size() == right.size());
  const int h = options_.window_half_px;
  DisparityMap out;
  out.disparity_px =
      cv::Mat(left.size(), CV_32F, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
  out.confidence = cv::Mat(left.size(), CV_32F, cv::Scalar(0));
  cv::Mat ml, mr, texture;
  cv::boxFilter(left, ml, CV_32F, cv::Size(2 * h + 1, 2 * h + 1));
  cv::boxFilter(right, mr, CV_32F, cv::Size(2 * h + 1, 2 * h + 1));
  std::vector<float> costs;
  for (int y = h; y < left.rows - h; ++y) {
    for (int x = h; x < left.cols - h; ++x) {
      const float lo = lo_px.at<float>(y, x), hi = hi_px.at<float>(y, x);
      if (!(lo <= hi)) continue;
      ++out.searched;
      // Texture: the window's mean absolute deviation.
      float mad = 0;
      const float m = ml.at<float>(y, x);
      for (int dy = -h; dy <= h; ++dy)
        for (int dx = -h; dx <= h; ++dx) mad += std::abs(left.at<uchar>(y + dy, x + dx) - m);
      if (mad / ((2 * h + 1) * (2 * h + 1)) < options_.min_texture_dn) {
        ++out.rejected_texture;
        continue;
      }
      const int dlo = static_cast<int>(std::floor(lo)) - 1,
                dhi = static_cast<int>(std::ceil(hi)) + 1;
      const Best b = Search(left, right, ml, mr, x, y, dlo, dhi, h, false, costs);
      if (!std::isfinite(b.cost) || b.edge) {
        ++out.rejected_edge;
        continue;
      }
      // Left-right check: from the matched right pixel, search back.
      const int xr = x - b.d;
      const Best back = Search(right, left, mr, ml, xr, y, dlo, dhi, h, true, costs);
      if (!std::isfinite(back.cost) ||
          std::abs((back.d + back.sub) - (b.d + b.sub)) > options_.lr_tolerance_px) {
        ++out.rejected_lr;
        continue;
      }
      out.disparity_px.at<float>(y, x) = static_cast<float>(b.d + b.sub);
      const float margin =
          std::isfinite(b.second) ? (b.second - b.cost) / (b.second + 1e-3f) : 1.0f;
      out.confidence.at<float>(y, x) = std::clamp(margin, 0.0f, 1.0f);
      ++out.matched;
    }
  }
  return out;
}

}  // namespace fovea
