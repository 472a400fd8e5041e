// IDR's pieces on synthetic images with known answers.
#include "fovea/idr.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace {

// Band-limited random texture (sum of blurred noise octaves), 8-bit.
cv::Mat Texture(int rows, int cols, uint64_t seed) {
  cv::RNG rng(seed);
  cv::Mat sum(rows, cols, CV_32F, cv::Scalar(0));
  for (double sigma : {1.0, 2.0, 4.0}) {
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

// The image content moved left by `d` pixels (the right view of a
// fronto-parallel surface at disparity d).
cv::Mat Shift(const cv::Mat& img, double d) {
  cv::Mat out;
  const cv::Mat m = (cv::Mat_<double>(2, 3) << 1, 0, -d, 0, 1, 0);
  cv::warpAffine(img, out, m, img.size(), cv::INTER_CUBIC, cv::BORDER_REFLECT);
  return out;
}

fovea::DisparityWindows Global(double lo, double hi) {
  fovea::DisparityWindows w;
  w.global = true;
  w.global_lo_px = lo;
  w.global_hi_px = hi;
  return w;
}

}  // namespace

TEST_CASE("matching a shifted texture recovers its disparity", "[fovea][idr]") {
  const cv::Mat left = Texture(200, 300, 1);
  for (double d : {7.0, 7.4, 11.75}) {
    INFO("disparity " << d);
    const cv::Mat right = Shift(left, d);
    fovea::ZeroCrossingOptions zo;
    const auto zl = fovea::ExtractZeroCrossings(left, zo),
               zr = fovea::ExtractZeroCrossings(right, zo);
    fovea::ZcMatchStats stats;
    const auto matches =
        fovea::MatchZeroCrossings(zl, zr, Global(0, 14), Global(0, 14), {}, &stats);
    REQUIRE(matches.size() > 0.6 * zl.crossings.size());
    int close = 0;
    for (const auto& m : matches)
      if (std::abs(m.disparity_px - d) < 0.25) ++close;
    // Sub-pixel crossing positions: nearly all within a quarter pixel.
    CHECK(close > 0.95 * matches.size());
    CHECK(stats.matches == int(matches.size()));
    CHECK(stats.unique + stats.ambiguous + stats.no_candidate == stats.searched);
  }
}

TEST_CASE("a window wider than the period makes periodic matches ambiguous", "[fovea][idr]") {
  const double period = 20, d = 6;
  cv::Mat left(80, 300, CV_8UC1);
  for (int x = 0; x < left.cols; ++x)
    left.col(x).setTo(cv::saturate_cast<uchar>(128 + 70 * std::sin(2 * M_PI * x / period)));
  const cv::Mat right = Shift(left, d);
  const auto zl = fovea::ExtractZeroCrossings(left, {}),
             zr = fovea::ExtractZeroCrossings(right, {});
  fovea::ZcMatchStats narrow, wide, nearest;
  const auto good = fovea::MatchZeroCrossings(zl, zr, Global(0, 15), Global(0, 15), {}, &narrow);
  CHECK(narrow.UnambiguousShare() > 0.99);
  for (const auto& m : good) CHECK(m.disparity_px == Approx(d).margin(0.1));
  const auto none = fovea::MatchZeroCrossings(zl, zr, Global(0, 45), Global(0, 45), {}, &wide);
  // (Only crossings whose aliases fall outside the image stay unique.)
  CHECK(wide.UnambiguousShare() < 0.15);
  CHECK(none.size() < 0.15 * zl.crossings.size());
  // A matcher that takes the nearest candidate matches them anyway, wrongly
  // whenever the true disparity is not the smallest in the window.
  fovea::ZcMatchOptions take;
  take.take_nearest_when_ambiguous = true;
  const cv::Mat far_right = Shift(left, d + period);  // true disparity 26
  const auto zf = fovea::ExtractZeroCrossings(far_right, {});
  const auto wrong =
      fovea::MatchZeroCrossings(zl, zf, Global(0, 45), Global(0, 45), take, &nearest);
  REQUIRE(wrong.size() > 0.5 * zl.crossings.size());
  const auto aliased = std::count_if(wrong.begin(), wrong.end(), [&](const auto& m) {
    return std::abs(m.disparity_px - d) < 0.1;  // one period short of the truth
  });
  CHECK(aliased > 0.85 * wrong.size());
}

TEST_CASE("expansion factor from the minimum separation and the slant limit", "[fovea][idr]") {
  // Fronto-parallel limit: k = s_min.
  CHECK(fovea::ExpansionFactor(10, 5, 1000, 0) == Approx(10));
  // g = d s tan(theta) / f.
  const double g = 5 * 10 * std::tan(M_PI / 3) / 1000;
  CHECK(fovea::ExpansionFactor(10, 5, 1000, M_PI / 3) == Approx(10 / (1 + g)));
  // Larger disparities allow less expansion.
  CHECK(fovea::ExpansionFactor(10, 50, 1000, M_PI / 3) <
        fovea::ExpansionFactor(10, 5, 1000, M_PI / 3));
}

TEST_CASE("per-crossing windows come from nearby anchors", "[fovea][idr]") {
  fovea::DisparityWindows w;
  w.global = false;
  w.rows.assign(10, {});
  w.rows[5] = {{10, 4, 6}, {30, 8, 9}};
  w.reach_px = 3;
  w.row_reach = 1;
  double lo, hi;
  REQUIRE(w.Window(12, 5, &lo, &hi));
  CHECK(lo == 4);
  CHECK(hi == 6);
  REQUIRE(w.Window(11, 6, &lo, &hi));  // a row away still counts
  CHECK_FALSE(w.Window(20, 5, &lo, &hi));
  CHECK_FALSE(w.Window(12, 8, &lo, &hi));
}

TEST_CASE("samples at a depth discontinuity are flagged", "[fovea][idr]") {
  std::vector<fovea::DisparitySample> s;
  for (int x = 0; x < 40; x += 4) s.push_back({double(x), 0, x < 20 ? 30.0 : 12.0});
  s.push_back({5, 20, 30});  // far from the step
  const auto flags = fovea::NearDiscontinuity(s, 6, 2);
  for (size_t i = 0; i < s.size(); ++i) {
    const bool at_step = s[i].y_px == 0 && (s[i].x_px == 16 || s[i].x_px == 20);
    INFO("x " << s[i].x_px << " y " << s[i].y_px);
    CHECK(bool(flags[i]) == at_step);
  }
}

TEST_CASE("patches from disparities back-project to the right depth", "[fovea][idr]") {
  rig::CameraView view;
  view.intrinsics = rig::CameraIntrinsics::FromHorizontalFov(128, 96, 0.6);
  const double baseline = 0.05, z = 0.8;
  const double d = view.intrinsics.fx_px * baseline / z;
  std::vector<fovea::DisparitySample> samples;
  for (int y = 0; y < 96; ++y)
    for (int x = 0; x < 128; x += 3) samples.push_back({x + 0.2, double(y), d});
  const fovea::PatchMap map =
      fovea::PatchesFromDisparities(samples, view, baseline, 16, {}, fovea::PatchLevel::kIdr);
  CHECK(map.size() == (128 / 16) * (96 / 16));
  for (const auto& p : map.patches()) {
    for (const auto& c : p.corners_W) CHECK(c.z() == Approx(z).margin(1e-9));
    CHECK(p.level == fovea::PatchLevel::kIdr);
  }
}

TEST_CASE("IDR blocks whose plane is seen too obliquely give no patch", "[fovea][idr]") {
  rig::CameraView view;
  view.intrinsics = rig::CameraIntrinsics::FromHorizontalFov(128, 96, 0.6);
  const rig::CameraIntrinsics& k = view.intrinsics;
  // A plane through (0, 0, z0) turned 70 degrees about the vertical axis:
  // 1 / Z = (1 + u tan 70) / z0 along the ray (u, v, 1), so the view angle
  // runs from about 50 degrees at the right edge to 90 at the left.
  const double baseline = 0.05, z0 = 0.8, slope = std::tan(70 * M_PI / 180);
  std::vector<fovea::DisparitySample> samples;
  for (int y = 0; y < 96; ++y)
    for (int x = 0; x < 128; x += 2) {
      const double u = (x + 0.2 - k.cx_px) / k.fx_px;
      const double d = k.fx_px * baseline * (1 + u * slope) / z0;
      if (d > 0.5) samples.push_back({x + 0.2, double(y), d});
    }
  const Eigen::Vector3d eye_W = view.world_T_camera.translation();
  const fovea::PatchMap any =
      fovea::PatchesFromDisparities(samples, view, baseline, 16, {}, fovea::PatchLevel::kIdr);
  const fovea::PatchMap limited =
      fovea::PatchesFromDisparities(samples, view, baseline, 16, {}, fovea::PatchLevel::kIdr, 60);
  size_t within = 0;
  for (const auto& p : any.patches()) within += p.ViewAngleRad(eye_W) <= 60 * M_PI / 180;
  INFO(any.size() << " patches, " << within << " within 60 degrees, " << limited.size()
                  << " with the limit");
  CHECK(within >= 6);
  CHECK(any.size() >= within + 6);
  CHECK(limited.size() == within);
  for (const auto& p : limited.patches()) CHECK(p.ViewAngleRad(eye_W) <= 60 * M_PI / 180);
}
