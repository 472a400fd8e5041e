#include "fovea/zero_crossings.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace {
fovea::ZeroCrossingOptions Options() { return {}; }
}  // namespace

TEST_CASE("a step edge gives one crossing per row at the edge, with its polarity", "[fovea][zc]") {
  cv::Mat img(120, 200, CV_8UC1, cv::Scalar(50));
  img.colRange(100, 200).setTo(200);  // edge between columns 99 and 100
  const auto zc = fovea::ExtractZeroCrossings(img, Options());
  int rows_with_one = 0;
  for (int y = 0; y < zc.rows(); ++y) {
    const int n = zc.row_begin[y + 1] - zc.row_begin[y];
    if (n == 0) continue;
    REQUIRE(n == 1);
    ++rows_with_one;
    const auto& c = zc.crossings[zc.row_begin[y]];
    CHECK(c.x_px == Approx(99.5).margin(0.02));  // symmetric step: the LoG crosses midway
    CHECK(c.polarity == -1);                     // LoG positive on the dark side
    CHECK(std::abs(std::abs(c.orientation_rad) - M_PI) < 0.01);
  }
  CHECK(rows_with_one > 100);
}

TEST_CASE("homogeneous regions give no crossings, even with sensor noise", "[fovea][zc]") {
  cv::Mat img(200, 200, CV_8UC1, cv::Scalar(128));
  cv::Mat noise(img.size(), CV_32F);
  cv::RNG(3).fill(noise, cv::RNG::NORMAL, 0, 2.0);
  cv::Mat f;
  img.convertTo(f, CV_32F);
  f += noise;
  f.convertTo(img, CV_8U);
  CHECK(fovea::ExtractZeroCrossings(img, Options()).crossings.empty());
}

TEST_CASE("a sinusoid's crossings alternate in polarity, a period apart", "[fovea][zc]") {
  const double period = 20;
  cv::Mat img(60, 300, CV_8UC1);
  for (int x = 0; x < img.cols; ++x)
    img.col(x).setTo(cv::saturate_cast<uchar>(128 + 60 * std::sin(2 * M_PI * x / period)));
  const auto zc = fovea::ExtractZeroCrossings(img, Options());
  const auto periods = fovea::SamePolarityPeriods(zc);
  int checked = 0;
  for (int y = 20; y < 40; ++y)
    for (int i = zc.row_begin[y]; i + 1 < zc.row_begin[y + 1]; ++i) {
      CHECK(zc.crossings[i].polarity == -zc.crossings[i + 1].polarity);
      CHECK(zc.crossings[i + 1].x_px - zc.crossings[i].x_px == Approx(period / 2).margin(0.05));
      if (std::isfinite(periods[i])) {
        CHECK(periods[i] == Approx(period).margin(0.05));
        ++checked;
      }
    }
  CHECK(checked > 200);
}

TEST_CASE("the unambiguous disparity limit keeps the asked share of periods above it",
          "[fovea][zc]") {
  std::vector<float> periods(95, 20.0f);
  periods.insert(periods.end(), 5, 6.0f);
  // 90%: the 10th smallest period is 20, so d_max just under it.
  CHECK(fovea::UnambiguousDisparityLimit(periods, 0.90) == Approx(19.5));
  // 97%: the 3rd smallest is 6.
  CHECK(fovea::UnambiguousDisparityLimit(periods, 0.97) == Approx(5.5));
  CHECK(fovea::UnambiguousDisparityLimit({}, 0.9) == 0);
  // Whatever the share, at least that share of periods exceeds d_max.
  for (double share : {0.5, 0.9, 0.95, 0.99}) {
    const double d = fovea::UnambiguousDisparityLimit(periods, share);
    const auto above =
        std::count_if(periods.begin(), periods.end(), [&](float p) { return p > d; });
    CHECK(above >= share * periods.size());
  }
}
