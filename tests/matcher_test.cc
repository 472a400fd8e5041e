#include "fovea/matcher.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "fovea/sgbm.h"

namespace {
cv::Mat Texture(int rows, int cols, uint64_t seed) {
  cv::RNG rng(seed);
  cv::Mat sum(rows, cols, CV_32F, cv::Scalar(0));
  for (double sigma : {0.8, 1.5, 3.0}) {
    cv::Mat n(rows, cols, CV_32F);
    rng.fill(n, cv::RNG::NORMAL, 0, 1);
    cv::GaussianBlur(n, n, cv::Size(0, 0), sigma);
    cv::normalize(n, n, -1, 1, cv::NORM_MINMAX);
    sum += n;
  }
  cv::Mat out;
  cv::normalize(sum, out, 20, 235, cv::NORM_MINMAX, CV_8U);
  return out;
}
cv::Mat Shift(const cv::Mat& img, double d) {
  cv::Mat out;
  const cv::Mat m = (cv::Mat_<double>(2, 3) << 1, 0, -d, 0, 1, 0);
  cv::warpAffine(img, out, m, img.size(), cv::INTER_CUBIC, cv::BORDER_REFLECT);
  return out;
}
}  // namespace

TEST_CASE("NL1 matching recovers signed sub-pixel disparities", "[fovea][matcher]") {
  const cv::Mat left = Texture(120, 160, 5);
  const fovea::Nl1Matcher matcher;
  for (double d : {-6.3, 0.0, 4.5, 9.25}) {
    INFO("disparity " << d);
    // A brightness offset between the views: the normalized cost ignores it.
    cv::Mat right = Shift(left, d);
    right.convertTo(right, CV_8U, 1.0, 12);
    const cv::Mat lo(left.size(), CV_32F, cv::Scalar(-12)), hi(left.size(), CV_32F, cv::Scalar(12));
    const auto r = matcher.Match(left, right, lo, hi);
    int good = 0;
    std::vector<double> errs;
    for (int y = 10; y < 110; ++y)
      for (int x = 30; x < 130; ++x) {
        const float m = r.disparity_px.at<float>(y, x);
        if (!std::isfinite(m)) continue;
        errs.push_back(std::abs(m - d));
        if (std::abs(m - d) < 0.5) ++good;
      }
    REQUIRE(errs.size() > 9000);  // nearly every pixel of the 100 x 100 interior
    std::nth_element(errs.begin(), errs.begin() + errs.size() / 2, errs.end());
    CHECK(errs[errs.size() / 2] < 0.15);  // sub-pixel, median
    CHECK(good > 0.99 * 10000 * 0.9);
  }
}

TEST_CASE("NL1 matching: ranges bound the search, texture and left-right checks reject",
          "[fovea][matcher]") {
  const cv::Mat left = Texture(80, 120, 9);
  const cv::Mat right = Shift(left, 5);
  const fovea::Nl1Matcher matcher;
  // A range that excludes the truth: most pixels' minimum sits at the edge
  // of the search and is rejected; spurious interior minima (about a fifth
  // here) survive, but never outside the searched range (+-1 px of slack).
  const cv::Mat lo(left.size(), CV_32F, cv::Scalar(-3)), hi(left.size(), CV_32F, cv::Scalar(1));
  const auto r = matcher.Match(left, right, lo, hi);
  CHECK(r.matched < 0.35 * r.searched);
  CHECK(r.rejected_edge > 0.5 * r.searched);
  for (int y = 0; y < r.disparity_px.rows; ++y)
    for (int x = 0; x < r.disparity_px.cols; ++x) {
      const float m = r.disparity_px.at<float>(y, x);
      if (std::isfinite(m)) REQUIRE((m >= -4.5f && m <= 2.5f));
    }
  // lo > hi: the pixel is not searched.
  const cv::Mat skip_lo(left.size(), CV_32F, cv::Scalar(1)),
      skip_hi(left.size(), CV_32F, cv::Scalar(0));
  CHECK(matcher.Match(left, right, skip_lo, skip_hi).searched == 0);
  // A flat image has no texture to match.
  const cv::Mat flat(left.size(), CV_8U, cv::Scalar(100));
  const cv::Mat wlo(left.size(), CV_32F, cv::Scalar(0)), whi(left.size(), CV_32F, cv::Scalar(8));
  const auto f = matcher.Match(flat, flat, wlo, whi);
  CHECK(f.matched == 0);
  CHECK(f.rejected_texture == f.searched);
}

TEST_CASE("SGBM plugs into the same interface and finds the same disparity", "[fovea][matcher]") {
  const cv::Mat left = Texture(120, 200, 7);
  const fovea::SgbmMatcher sgbm;
  for (double d : {-5.0, 6.5}) {
    INFO("disparity " << d);
    const cv::Mat right = Shift(left, d);
    const cv::Mat lo(left.size(), CV_32F, cv::Scalar(-10)), hi(left.size(), CV_32F, cv::Scalar(10));
    const auto r = sgbm.Match(left, right, lo, hi);
    std::vector<double> errs;
    for (int y = 10; y < 110; ++y)
      for (int x = 40; x < 160; ++x)
        if (std::isfinite(r.disparity_px.at<float>(y, x)))
          errs.push_back(std::abs(r.disparity_px.at<float>(y, x) - d));
    REQUIRE(errs.size() > 0.8 * 100 * 120);
    std::nth_element(errs.begin(), errs.begin() + errs.size() / 2, errs.end());
    CHECK(errs[errs.size() / 2] < 0.2);
    CHECK(sgbm.Name() == "sgbm");
  }
}
