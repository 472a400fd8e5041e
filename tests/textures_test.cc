#include "scenes/textures.h"

#include <catch2/catch.hpp>
#include <opencv2/imgproc.hpp>

#include "sim/config.h"

namespace {
cv::Mat Gray(const cv::Mat& bgr) {
  cv::Mat g;
  cv::cvtColor(bgr, g, cv::COLOR_BGR2GRAY);
  g.convertTo(g, CV_32F);
  return g;
}
// Mean absolute difference between horizontally adjacent texels.
double FineDetail(const cv::Mat& gray) {
  cv::Mat dx = cv::abs(gray.colRange(1, gray.cols) - gray.colRange(0, gray.cols - 1));
  return cv::mean(dx)[0];
}
// Power spectrum of the column-averaged row profile (or row profile of the
// transposed image).
std::vector<double> ProfileSpectrum(const cv::Mat& gray) {
  cv::Mat profile;
  cv::reduce(gray, profile, 0, cv::REDUCE_AVG);
  profile -= cv::mean(profile)[0];
  cv::Mat spectrum;
  cv::dft(profile, spectrum, cv::DFT_COMPLEX_OUTPUT);
  std::vector<double> power(profile.cols / 2);
  for (int k = 0; k < int(power.size()); ++k) {
    const cv::Vec2f c = spectrum.at<cv::Vec2f>(0, k);
    power[k] = c[0] * c[0] + c[1] * c[1];
  }
  return power;
}
}  // namespace

TEST_CASE("textures are identical for the same seed and differ between seeds", "[scenes]") {
  for (const std::string& kind : scenes::TextureKinds()) {
    INFO(kind);
    const cv::Mat a = scenes::MakeTexture(kind, 5, 256), b = scenes::MakeTexture(kind, 5, 256);
    const cv::Mat c = scenes::MakeTexture(kind, 6, 256);
    CHECK(cv::norm(a, b, cv::NORM_INF) == 0);
    CHECK(cv::norm(a, c, cv::NORM_INF) > 0);
  }
  CHECK_THROWS_AS(scenes::MakeTexture("marble", 1), sim::SceneError);
}

TEST_CASE("textured kinds have detail at the texel scale, and uniform has no gradient",
          "[scenes]") {
  for (const std::string& kind : scenes::TextureKinds()) {
    INFO(kind);
    const cv::Mat g = Gray(scenes::MakeTexture(kind, 3));
    if (kind == "uniform") {
      CHECK(FineDetail(g) == 0);
      CHECK(FineDetail(g.t()) == 0);
    } else {
      // At least 2 grey levels per texel on average across the horizontal
      // (the matching direction): real detail at the pixel scale.
      CHECK(FineDetail(g) > 2.0);
    }
  }
}

TEST_CASE("periodic textures have exactly their period", "[scenes]") {
  const int size = scenes::kTextureSizePx, period = scenes::kPeriodicPeriodPx;
  const int fundamental = size / period;
  for (const std::string kind : {"stripes", "checker"}) {
    INFO(kind);
    const cv::Mat g = Gray(scenes::MakeTexture(kind, 9));
    // Stripes: every row equal; columns repeat with the period exactly.
    CHECK(cv::norm(g.colRange(0, size - period), g.colRange(period, size), cv::NORM_INF) == 0);
    CHECK(cv::norm(g.rowRange(0, size - period), g.rowRange(period, size), cv::NORM_INF) == 0);
    // Spectrum: all the energy at the fundamental and its harmonics.
    // (For the checker, one full-contrast row: averaging rows would cancel.)
    int best_row = 0;
    double best_std = -1;
    for (int r = 0; r < period; ++r) {
      cv::Scalar mean, std;
      cv::meanStdDev(g.row(r), mean, std);
      if (std[0] > best_std) best_std = std[0], best_row = r;
    }
    const cv::Mat profile_source = std::string(kind) == "checker" ? g.row(best_row) : g;
    const auto power = ProfileSpectrum(profile_source);
    double total = 0, harmonic = 0;
    for (size_t k = 1; k < power.size(); ++k) {
      total += power[k];
      if (k % fundamental == 0) harmonic += power[k];
    }
    CHECK(harmonic / total > 0.999);
    const auto peak = std::max_element(power.begin() + 1, power.end()) - power.begin();
    CHECK(peak == fundamental);
  }
  // The non-periodic kinds have no such line.
  const auto power = ProfileSpectrum(Gray(scenes::MakeTexture("photo", 9)));
  double total = 0;
  for (size_t k = 1; k < power.size(); ++k) total += power[k];
  CHECK(power[fundamental] / total < 0.05);
}

TEST_CASE("texture file names", "[scenes]") {
  const auto t = scenes::ParseTextureName("wood-s42.png");
  REQUIRE(t);
  CHECK(t->kind == "wood");
  CHECK(t->seed == 42);
  CHECK_FALSE(scenes::ParseTextureName("wood.png"));
  CHECK_FALSE(scenes::ParseTextureName("textures/wood-s1.png"));
  CHECK_FALSE(scenes::ParseTextureName("wood-s1.jpg"));
}
