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
  fovea::Nl1Options options;
  options.cost = GENERATE(as<std::string>(), "window_mean", "prenormalized", "zero_mean_ssd");
  INFO("cost " << options.cost);
  const fovea::Nl1Matcher matcher(options);
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

namespace {
// The matcher's rules written plainly, pixel by pixel and disparity by
// disparity, as an oracle for the cost volume's strips, column ranges and
// vectorized winners: texture test, band [floor(lo) - 1, ceil(hi) + 1]
// within the image, winner-take-all with its minimum inside the band, the
// matched right pixel's winner among the left pixels whose bands reach it
// (left-right check), equiangular sub-pixel (the right pixel's from its
// neighbouring candidates), the two views' estimates averaged.
struct Reference {
  cv::Mat disparity;
  int searched = 0, matched = 0, texture = 0;
};

Reference MatchPlainly(const cv::Mat& left, const cv::Mat& right, const cv::Mat& lo,
                       const cv::Mat& hi, const fovea::Nl1Options& o) {
  const int h = o.window_half_px, n = 2 * h + 1, cols = left.cols;
  const float inf = std::numeric_limits<float>::infinity();
  cv::Mat ml, fl, fr, wl, wr;
  cv::boxFilter(left, ml, CV_32F, cv::Size(n, n));
  left.convertTo(fl, CV_32F);
  right.convertTo(fr, CV_32F);
  // Pre-normalized: less the mean over twice the window.
  cv::boxFilter(fl, wl, CV_32F, cv::Size(2 * n + 1, 2 * n + 1));
  cv::boxFilter(fr, wr, CV_32F, cv::Size(2 * n + 1, 2 * n + 1));
  const cv::Mat a = fl - wl, b = fr - wr;
  cv::Mat mr;
  cv::boxFilter(right, mr, CV_32F, cv::Size(n, n));
  const bool window_mean = o.cost == "window_mean";
  auto cost = [&](int x, int y, int d) {
    const int xr = x - d;
    if (x - h < 0 || x + h >= cols || xr - h < 0 || xr + h >= cols) return inf;
    if (o.cost == "zero_mean_ssd") {
      // Both windows less their own means, squared, the root of the mean.
      const double offset = ml.at<float>(y, x) - mr.at<float>(y, xr);
      double c = 0;
      for (int dy = -h; dy <= h; ++dy)
        for (int dx = -h; dx <= h; ++dx) {
          const double e = fl.at<float>(y + dy, x + dx) - fr.at<float>(y + dy, xr + dx) - offset;
          c += e * e;
        }
      return static_cast<float>(std::sqrt(c / (n * n)));
    }
    if (window_mean) {
      // The paper's: both windows less their own means, exactly: with D =
      // L - R and S its sum over the window, sum |D - S / n^2| = sum |n^2 D
      // - S| / n^2, an integer over n^2, over n^2 again for the mean.
      int s = 0;
      for (int dy = -h; dy <= h; ++dy)
        for (int dx = -h; dx <= h; ++dx)
          s += left.at<uchar>(y + dy, x + dx) - right.at<uchar>(y + dy, xr + dx);
      int64_t c = 0;
      for (int dy = -h; dy <= h; ++dy)
        for (int dx = -h; dx <= h; ++dx)
          c += std::abs(int64_t{n * n} *
                            (left.at<uchar>(y + dy, x + dx) - right.at<uchar>(y + dy, xr + dx)) -
                        s);
      return static_cast<float>(c) * (1.0f / static_cast<float>(n * n * n * n));
    }
    // Pre-normalized.
    float c = 0;
    for (int dy = -h; dy <= h; ++dy)
      for (int dx = -h; dx <= h; ++dx)
        c += std::abs(a.at<float>(y + dy, x + dx) - b.at<float>(y + dy, xr + dx));
    return c / (n * n);
  };
  auto sub = [](double c0, double c1, double c2) {
    const double s = std::max(c0 - c1, c2 - c1);
    return s > 0 ? std::clamp(0.5 * (c0 - c2) / s, -0.5, 0.5) : 0.0;
  };
  Reference r;
  r.disparity = cv::Mat(left.size(), CV_32F, cv::Scalar(std::nanf("")));
  cv::Mat blo(left.size(), CV_32S, cv::Scalar(1)), bhi(left.size(), CV_32S, cv::Scalar(0));
  for (int y = h; y < left.rows - h; ++y)
    for (int x = h; x < cols - h; ++x) {
      if (!(lo.at<float>(y, x) <= hi.at<float>(y, x))) continue;
      ++r.searched;
      float mad = 0;
      for (int dy = -h; dy <= h; ++dy)
        for (int dx = -h; dx <= h; ++dx)
          mad += std::abs(fl.at<float>(y + dy, x + dx) - ml.at<float>(y, x));
      if (mad < o.min_texture_dn * n * n) {
        ++r.texture;
        continue;
      }
      const float dmin = x - (cols - 1 - h), dmax = x - h;
      blo.at<int>(y, x) =
          static_cast<int>(std::clamp(std::floor(lo.at<float>(y, x)) - 1, dmin - 1, dmax + 1));
      bhi.at<int>(y, x) =
          static_cast<int>(std::clamp(std::ceil(hi.at<float>(y, x)) + 1, dmin - 1, dmax + 1));
    }
  for (int y = h; y < left.rows - h; ++y)
    for (int x = h; x < cols - h; ++x) {
      const int l = blo.at<int>(y, x), u = bhi.at<int>(y, x);
      if (l > u) continue;
      int d = l;
      float best = inf;
      for (int dd = l; dd <= u; ++dd)
        if (cost(x, y, dd) < best) {
          best = cost(x, y, dd);
          d = dd;
        }
      if (!std::isfinite(best) || d == l || d == u) continue;
      const float c0 = cost(x, y, d - 1), c2 = cost(x, y, d + 1);
      if (!std::isfinite(c0) || !std::isfinite(c2)) continue;
      const double left_d = d + sub(c0, best, c2);
      const int xr = x - d;
      int dr = 0;
      float rbest = inf;
      for (int xx = h; xx < cols - h; ++xx) {
        const int dd = xx - xr;
        if (dd < blo.at<int>(y, xx) || dd > bhi.at<int>(y, xx)) continue;
        const float c = cost(xx, y, dd);
        if (c < rbest || (c == rbest && dd < dr)) {
          rbest = c;
          dr = dd;
        }
      }
      if (!std::isfinite(rbest)) continue;
      // The neighbours among the candidates: left pixels whose bands hold them.
      auto candidate = [&](int xl, int dl) {
        return xl >= 0 && xl < cols && blo.at<int>(y, xl) <= dl && dl <= bhi.at<int>(y, xl)
                   ? cost(xl, y, dl)
                   : inf;
      };
      const float r0 = candidate(xr + dr - 1, dr - 1), r2 = candidate(xr + dr + 1, dr + 1);
      const bool refined = std::isfinite(r0) && std::isfinite(r2);
      const double right_d = dr + (refined ? sub(r0, rbest, r2) : 0.0);
      if (std::abs(right_d - left_d) > o.lr_tolerance_px) continue;
      r.disparity.at<float>(y, x) = static_cast<float>(refined ? 0.5 * (left_d + right_d) : left_d);
      ++r.matched;
    }
  return r;
}
}  // namespace

TEST_CASE("the cost-volume matcher gives what its rules give, pixel by pixel", "[fovea][matcher]") {
  // 300 rows: several times the pixels to match at which the matcher
  // splits a crop between two threads (8192).
  const int rows = GENERATE(72, 300);
  INFO("rows " << rows);
  const cv::Mat left = Texture(rows, 150, 21);
  // A disparity that grows across the image (a slanted surface), and bands
  // that vary per pixel: narrow about a map's prediction, wide where it is
  // silent, absurd where a ray grazes the right camera, none here and there,
  // and bands that reach past the image's left edge.
  cv::Mat right(left.size(), CV_8U);
  cv::Mat map_x(left.size(), CV_32F), map_y(left.size(), CV_32F);
  for (int y = 0; y < left.rows; ++y)
    for (int x = 0; x < left.cols; ++x) {
      map_x.at<float>(y, x) = static_cast<float>(x + (2.0 + 0.03 * x));
      map_y.at<float>(y, x) = static_cast<float>(y);
    }
  cv::remap(left, right, map_x, map_y, cv::INTER_CUBIC, cv::BORDER_REFLECT);
  cv::RNG rng(4);
  cv::Mat lo(left.size(), CV_32F), hi(left.size(), CV_32F);
  // Layouts: mixed bands; or two bands far apart in each row (the left
  // half's near the truth, the right half's 20 px off), whose hull holds
  // disparities no pixel searches.
  const int layout = GENERATE(0, 1, 2);
  INFO("layout " << layout);
  for (int y = 0; y < left.rows; ++y)
    for (int x = 0; x < left.cols; ++x) {
      // right(x) = left(x + 2 + 0.03 x): d = x_left - x_right.
      const double truth = (2.0 + 0.03 * x) / 1.03;
      double l = truth - rng.uniform(1.0, 3.0), u = truth + rng.uniform(1.0, 3.0);
      if (layout == 1 && x >= left.cols / 2) l += 20, u += 20;
      const int kind = layout == 0 ? rng.uniform(0, 20) : -1;
      if (kind == 0) l = truth - 25, u = truth + 15;  // silent: wide
      if (kind == 1) l = -1e30, u = 1e30;             // grazing ray
      if (kind == 2) l = 1, u = 0;                    // not searched
      if (kind == 3) l = truth + 40, u = truth + 60;  // beside the image
      // Layout 2: beside the image's left edge, bands that hold the truth
      // and reach past the edge (the right window leaves the image beyond d
      // = x - h: there the cost is +inf, and a minimum at x - h is not
      // one), over 29 pixels in odd rows and only 3 in even ones (a run of
      // columns narrower than the others of its strip).
      if (layout == 2 && x < 32) {
        l = 1, u = 0;
        if (y % 2 ? x >= 3 : x >= 5 && x < 8) l = truth - 1.5, u = x - 3 + 1.5;
      }
      lo.at<float>(y, x) = static_cast<float>(l);
      hi.at<float>(y, x) = static_cast<float>(u);
    }
  fovea::Nl1Options options;
  options.weak_window_half_px = 0;  // the plain matcher's one window
  options.cost = GENERATE(as<std::string>(), "window_mean", "prenormalized", "zero_mean_ssd");
  INFO("cost " << options.cost);
  const Reference ref = MatchPlainly(left, right, lo, hi, options);
  const fovea::DisparityMap fast = fovea::Nl1Matcher(options).Match(left, right, lo, hi);
  CHECK(fast.searched == ref.searched);
  CHECK(fast.rejected_texture == ref.texture);
  REQUIRE(ref.matched > (layout == 1 ? 0.3 : 0.5) * ref.searched);
  // The paper's cost is exact (integer sums, one rounding): the same
  // disparity at every pixel. The others' box sums run down the strip in
  // floating point: a tie between two disparities may break differently,
  // nothing more.
  const int tolerance = options.cost == "window_mean" ? 0 : ref.matched / 1000;
  int disagree = 0;
  for (int y = 0; y < left.rows; ++y)
    for (int x = 0; x < left.cols; ++x) {
      const float f = fast.disparity_px.at<float>(y, x), r = ref.disparity.at<float>(y, x);
      if (std::isfinite(f) != std::isfinite(r) || (std::isfinite(f) && std::abs(f - r) > 1e-3))
        ++disagree;
    }
  CHECK(disagree <= tolerance);
  CHECK(std::abs(fast.matched - ref.matched) <= tolerance);
}

TEST_CASE("every NL1 cost matches a shifted texture to a tenth of a pixel", "[fovea][matcher]") {
  const cv::Mat left = Texture(80, 120, 13);
  const cv::Mat right = Shift(left, 4.4);
  const cv::Mat lo(left.size(), CV_32F, cv::Scalar(0)), hi(left.size(), CV_32F, cv::Scalar(8));
  fovea::Nl1Options options;
  options.cost = GENERATE(as<std::string>(), "window_mean", "prenormalized", "zero_mean_ssd");
  INFO("cost " << options.cost);
  const auto r = fovea::Nl1Matcher(options).Match(left, right, lo, hi);
  std::vector<double> errs;
  for (int y = 5; y < 75; ++y)
    for (int x = 20; x < 110; ++x)
      if (std::isfinite(r.disparity_px.at<float>(y, x)))
        errs.push_back(std::abs(r.disparity_px.at<float>(y, x) - 4.4));
  REQUIRE(errs.size() > 0.95 * 70 * 90);
  std::nth_element(errs.begin(), errs.begin() + errs.size() / 2, errs.end());
  CHECK(errs[errs.size() / 2] < 0.1);
}

TEST_CASE("NL1 takes a wider window on a faint texture, and the narrow one elsewhere",
          "[fovea][matcher]") {
  // Left half: a strong texture (grey levels 20 to 235); right half: a dark,
  // faint copy (40 to 58); both views under 2 grey levels of sensor noise.
  const int rows = 120, cols = 240;
  const cv::Mat strong = Texture(rows, cols, 21);
  cv::Mat faint;
  strong.convertTo(faint, CV_32F, 18.0 / 215, 40);
  cv::Mat scene;
  strong.convertTo(scene, CV_32F);
  faint.colRange(cols / 2, cols).copyTo(scene.colRange(cols / 2, cols));
  const double d = 4.4;
  cv::Mat right = Shift(scene, d), left = scene.clone();
  cv::RNG rng(3);
  for (cv::Mat* m : {&left, &right}) {
    cv::Mat noise(rows, cols, CV_32F);
    rng.fill(noise, cv::RNG::NORMAL, 0, 2);
    *m += noise;
    m->convertTo(*m, CV_8U);
  }
  const cv::Mat lo(left.size(), CV_32F, cv::Scalar(-4)), hi(left.size(), CV_32F, cv::Scalar(12));
  fovea::Nl1Options narrow_only;
  narrow_only.weak_window_half_px = 0;
  fovea::Nl1Options split = narrow_only;
  split.weak_window_half_px = 5;
  split.weak_texture_dn = 8;
  const auto n = fovea::Nl1Matcher(narrow_only).Match(left, right, lo, hi);
  const auto s = fovea::Nl1Matcher(split).Match(left, right, lo, hi);
  CHECK(s.searched == n.searched);
  // On the faint half the wide window finds the shift at many more pixels,
  // and no more wrong ones.
  auto tally = [&](const cv::Mat& disparity, int x0, int x1, int* good, int* wrong) {
    *good = *wrong = 0;
    for (int y = 10; y < rows - 10; ++y)
      for (int x = x0; x < x1; ++x) {
        const float m = disparity.at<float>(y, x);
        if (!std::isfinite(m)) continue;
        ++(std::abs(m - d) < 1 ? *good : *wrong);
      }
  };
  int n_good, n_wrong, s_good, s_wrong;
  tally(n.disparity_px, cols / 2 + 20, cols - 20, &n_good, &n_wrong);
  tally(s.disparity_px, cols / 2 + 20, cols - 20, &s_good, &s_wrong);
  const int faint_pixels = (rows - 20) * (cols / 2 - 40);
  INFO("faint half: narrow " << n_good << " good, " << n_wrong << " wrong; split " << s_good
                             << " good, " << s_wrong << " wrong, of " << faint_pixels);
  CHECK(s_good > 0.75 * faint_pixels);  // 0.83 (the narrow window: 0.47)
  CHECK(s_good > 1.5 * n_good);
  CHECK(s_wrong <= n_wrong);
  // On the strong half, away from the faint one, every pixel is matched as
  // with the narrow window alone.
  for (int y = 0; y < rows; ++y)
    for (int x = 0; x < cols / 2 - 30; ++x) {
      const float a = n.disparity_px.at<float>(y, x), b = s.disparity_px.at<float>(y, x);
      REQUIRE(((std::isnan(a) && std::isnan(b)) || a == b));
    }
}
