#include "fovea/patch.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <random>

#include "fovea/foveal.h"
#include "test_views.h"

namespace {
std::vector<fovea::DisparitySample> PlaneSamples(double a, double b, double c, double x0, double y0,
                                                 int size, int step) {
  std::vector<fovea::DisparitySample> s;
  for (int y = 0; y < size; y += step)
    for (int x = 0; x < size; x += step)
      s.push_back({x0 + x + 0.3, y0 + y, a * (x0 + x + 0.3) + b * (y0 + y) + c});
  return s;
}
// Whether ErodeAtDisparityJumps(radius, jump, ...) should drop pixel (x,
// y) of `d`, by its rule written plainly: a pixel within `radius` whose
// disparity is more than `jump` below this one's, and which has at least 3
// of its 8 neighbours within `jump` of its own.
bool ErodedByRule(const cv::Mat& d, int x, int y, int radius, double jump) {
  auto surface = [&](int u, int v) {
    const double here = d.at<float>(v, u);
    int support = 0;
    for (int j = std::max(0, v - 1); j <= std::min(d.rows - 1, v + 1); ++j)
      for (int i = std::max(0, u - 1); i <= std::min(d.cols - 1, u + 1); ++i)
        support += (i != u || j != v) && std::abs(d.at<float>(j, i) - here) <= jump;
    return std::isfinite(here) && support >= 3;
  };
  const float before = d.at<float>(y, x);
  for (int v = std::max(0, y - radius); v <= std::min(d.rows - 1, y + radius); ++v)
    for (int u = std::max(0, x - radius); u <= std::min(d.cols - 1, x + radius); ++u)
      if (before - d.at<float>(v, u) > jump && surface(u, v)) return true;
  return false;
}
fovea::Patch Square(double z, double half) {
  fovea::Patch p;
  p.corners_W = {Eigen::Vector3d(-half, -half, z), Eigen::Vector3d(half, -half, z),
                 Eigen::Vector3d(half, half, z), Eigen::Vector3d(-half, half, z)};
  return p;
}
}  // namespace

TEST_CASE("a plane is fitted exactly from samples on it", "[fovea][patch]") {
  const auto samples = PlaneSamples(0.05, -0.02, 30, 32, 48, 16, 3);
  Eigen::Vector4d box;
  const auto fit = fovea::FitDisparityPlane(samples, 32, 48, 16, 16, {}, &box);
  REQUIRE(fit);
  CHECK(fit->a == Approx(0.05).margin(1e-9));
  CHECK(fit->b == Approx(-0.02).margin(1e-9));
  CHECK(fit->c == Approx(30).margin(1e-7));
  CHECK(fit->rms_px < 1e-9);
  CHECK(fit->support == int(samples.size()));
  CHECK(box(0) == Approx(32.3));
  CHECK(box(2) == Approx(47.3));
}

TEST_CASE("plane fitting drops outliers and rejects mixed or thin support", "[fovea][patch]") {
  auto samples = PlaneSamples(0, 0, 20, 0, 0, 16, 2);  // 64 samples
  const int n = int(samples.size());
  samples[5].disparity_px += 15;  // two wrong matches
  samples[40].disparity_px -= 9;
  const auto fit = fovea::FitDisparityPlane(samples, 0, 0, 16, 16, {});
  REQUIRE(fit);
  CHECK(fit->support == n - 2);
  CHECK(fit->c == Approx(20).margin(1e-9));

  // A depth step through the block: two populations, rejected.
  auto step = PlaneSamples(0, 0, 20, 0, 0, 16, 2);
  for (auto& s : step)
    if (s.x_px > 8) s.disparity_px = 35;
  CHECK_FALSE(fovea::FitDisparityPlane(step, 0, 0, 16, 16, {}));

  // Too few samples; all on one row; one quadrant empty.
  CHECK_FALSE(fovea::FitDisparityPlane(PlaneSamples(0, 0, 20, 0, 0, 16, 8), 0, 0, 16, 16, {}));
  std::vector<fovea::DisparitySample> row;
  for (int x = 0; x < 16; ++x) row.push_back({double(x), 3, 20});
  CHECK_FALSE(fovea::FitDisparityPlane(row, 0, 0, 16, 16, {}));
  auto corner = PlaneSamples(0, 0, 20, 0, 0, 16, 1);
  corner.erase(std::remove_if(corner.begin(), corner.end(),
                              [](const auto& s) { return s.x_px >= 8 && s.y_px >= 8; }),
               corner.end());
  CHECK_FALSE(fovea::FitDisparityPlane(corner, 0, 0, 16, 16, {}));
}

TEST_CASE("a plane is fitted over a rectangle, its quadrants the rectangle's", "[fovea][patch]") {
  // A 16-px square of samples on one plane; the fit over its right half
  // (x0 16, width 8, height 16) sees only that half's 128 samples.
  const auto samples = PlaneSamples(0.05, -0.02, 30, 8, 0, 16, 1);
  const auto fit = fovea::FitDisparityPlane(samples, 16, 0, 8, 16, {});
  REQUIRE(fit);
  CHECK(fit->measurements == 128);
  CHECK(fit->support == 128);
  CHECK(fit->a == Approx(0.05).margin(1e-9));
  CHECK(fit->c == Approx(30).margin(1e-7));
  // Without the half's lower right quarter (x >= 20, y >= 8) a quadrant of
  // the rectangle is empty, though the square's lower right holds data.
  auto corner = samples;
  corner.erase(std::remove_if(corner.begin(), corner.end(),
                              [](const auto& s) { return s.x_px >= 20 && s.y_px >= 8; }),
               corner.end());
  CHECK(fovea::FitDisparityPlane(corner, 8, 0, 16, 16, {}));
  CHECK_FALSE(fovea::FitDisparityPlane(corner, 16, 0, 8, 16, {}));
  fovea::PlaneFitOptions anywhere;
  anywhere.require_quadrants = false;
  const auto loose = fovea::FitDisparityPlane(corner, 16, 0, 8, 16, anywhere);
  REQUIRE(loose);
  CHECK(loose->measurements == 96);
}

TEST_CASE("a patch's view angle: 0 face on, growing as it turns edge on", "[fovea][patch]") {
  const fovea::Patch face = Square(1.0, 0.05);
  CHECK(face.ViewAngleRad(Eigen::Vector3d::Zero()) == Approx(0).margin(1e-12));
  // Seen from behind: the same angle (the corner order does not matter).
  CHECK(face.ViewAngleRad(Eigen::Vector3d(0, 0, 2)) == Approx(0).margin(1e-12));
  // Turned about the y axis through its centre, seen from the origin along z.
  for (const double deg : {30.0, 70.0, 85.0}) {
    const Eigen::AngleAxisd turn(deg * M_PI / 180, Eigen::Vector3d::UnitY());
    fovea::Patch turned = face;
    for (auto& c : turned.corners_W)
      c = Eigen::Vector3d(0, 0, 1) + turn * (c - Eigen::Vector3d(0, 0, 1));
    CHECK(turned.ViewAngleRad(Eigen::Vector3d::Zero()) == Approx(deg * M_PI / 180).epsilon(1e-9));
  }
  // Off the axis, the line of sight counts, not the camera's axis: a wall
  // at z = 1 seen 45 degrees off to the side.
  fovea::Patch side = Square(1.0, 0.05);
  for (auto& c : side.corners_W) c.x() += 1.0;
  CHECK(side.ViewAngleRad(Eigen::Vector3d::Zero()) == Approx(M_PI / 4).epsilon(1e-9));
}

TEST_CASE("patch map: rays hit the nearest patch", "[fovea][patch]") {
  fovea::PatchMap map;
  map.Add(Square(2.0, 0.5));
  map.Add(Square(1.0, 0.1));
  const auto hit = map.CastRay(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ());
  REQUIRE(hit);
  CHECK(hit->patch == 1);
  CHECK(hit->distance_m == Approx(1.0));
  const auto far = map.CastRay(Eigen::Vector3d(0.3, 0, 0), Eigen::Vector3d::UnitZ());
  REQUIRE(far);
  CHECK(far->patch == 0);
  CHECK(far->distance_m == Approx(2.0));
  CHECK_FALSE(map.CastRay(Eigen::Vector3d(0.7, 0, 0), Eigen::Vector3d::UnitZ()));
  CHECK(map.patches()[0].Normal().z() == Approx(1));
  CHECK(map.patches()[0].SizeM() == Approx(std::sqrt(2.0)));
}

TEST_CASE("patch map: a ray through a quad's diagonal or a shared edge hits it", "[fovea][patch]") {
  // A grid of 4 px patches at 1 m seen at 150 px focal length: pixel centres
  // fall exactly on the diagonals, where rounding once let rays slip between
  // a quad's two triangles.
  auto at = [](double u, double v) {
    return Eigen::Vector3d((u - 79.5) / 150, 1, -(v - 59.5) / 150);
  };
  fovea::PatchMap map;
  for (int y = 0; y < 120; y += 4)
    for (int x = 0; x < 160; x += 4) {
      fovea::Patch p;
      p.corners_W = {at(x - 0.5, y - 0.5), at(x + 3.5, y - 0.5), at(x + 3.5, y + 3.5),
                     at(x - 0.5, y + 3.5)};
      map.Add(p);
    }
  int missed = 0, missed_brute = 0;
  for (int v = 0; v < 120; ++v)
    for (int u = 0; u < 160; ++u) {
      const Eigen::Vector3d d = at(u, v).normalized();
      const auto hit = map.CastRay(Eigen::Vector3d::Zero(), d);
      missed += !hit || std::abs(hit->distance_m * d.y() - 1) > 1e-9;
      missed_brute += !map.CastRayBruteForce(Eigen::Vector3d::Zero(), d);
    }
  CHECK(missed == 0);  // 245 of 19,200 before the edges were closed
  CHECK(missed_brute == 0);
}

TEST_CASE("patch map: rendering into a view gives depth and patch ids", "[fovea][patch]") {
  fovea::PatchMap map;
  map.Add(Square(2.0, 0.5));
  map.Add(Square(1.0, 0.1));
  const auto k = rig::CameraIntrinsics::FromHorizontalFov(200, 150, 1.0);
  cv::Mat depth, ids;
  map.Render(Eigen::Isometry3d::Identity(), k, &depth, &ids);
  CHECK(depth.at<float>(75, 100) == Approx(1.0f));  // the near patch covers the centre
  CHECK(ids.at<int>(75, 100) == 1);
  // 0.3 m off-axis at 2 m: only the far patch.
  const int u = int(std::lround(k.cx_px + k.fx_px * 0.3 / 2.0));
  CHECK(depth.at<float>(75, u) == Approx(2.0f));
  CHECK(ids.at<int>(75, u) == 0);
  CHECK(depth.at<float>(2, 2) == 0);  // 0.5 m square at 2 m leaves the corners empty
  CHECK(ids.at<int>(2, 2) == -1);
  // Agrees with ray casting everywhere it is set.
  for (int v = 0; v < 150; v += 10)
    for (int x = 0; x < 200; x += 10) {
      const auto hit =
          map.CastRay(Eigen::Vector3d::Zero(), k.Ray({double(x), double(v)}).normalized());
      if (!hit) continue;
      CHECK(depth.at<float>(v, x) ==
            Approx(hit->distance_m / k.Ray({double(x), double(v)}).norm()).epsilon(1e-5));
    }
}

TEST_CASE("patch map: a render draws exactly the pixels inside a patch's projection",
          "[fovea][patch]") {
  // Rotated, slanted, thin and partly outside the image: each pixel centre
  // well inside either triangle of the projected quad is drawn, and none
  // well outside (Render only tests the columns of each row about a
  // triangle's span).
  const auto k = rig::CameraIntrinsics::FromHorizontalFov(160, 120, 1.0);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  int inside = 0, wrong = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const Eigen::Vector3d centre(0.6 * u(rng), 0.45 * u(rng), 1.5 + 0.4 * u(rng));
    const double angle = M_PI * u(rng), w = 0.2 * (1.05 + u(rng)), h = 0.2 * (1.05 + u(rng));
    const Eigen::Vector3d a(std::cos(angle), std::sin(angle), 0.3 * u(rng));
    const Eigen::Vector3d b(-std::sin(angle), std::cos(angle), 0.3 * u(rng));
    fovea::Patch p;
    p.corners_W = {centre - w * a - h * b, centre + w * a - h * b, centre + w * a + h * b,
                   centre - w * a + h * b};
    fovea::PatchMap map;
    map.Add(p);
    cv::Mat depth, ids;
    map.Render(Eigen::Isometry3d::Identity(), k, &depth, &ids);
    Eigen::Vector2d q[4];
    for (int c = 0; c < 4; ++c) q[c] = k.Project(p.corners_W[c]);
    // Signed distance in pixels of (x, y) inside triangle (i, j, l): the
    // least over its edges, positive inside.
    auto margin = [&](int i, int j, int l, double x, double y) {
      const Eigen::Vector2d t[3] = {q[i], q[j], q[l]};
      const double area =
          (t[1] - t[0]).x() * (t[2] - t[0]).y() - (t[1] - t[0]).y() * (t[2] - t[0]).x();
      double least = 1e300;
      for (int e = 0; e < 3; ++e) {
        const Eigen::Vector2d &s = t[e], &f = t[(e + 1) % 3];
        const double cross = (f - s).x() * (y - s.y()) - (f - s).y() * (x - s.x());
        least = std::min(least, (area > 0 ? cross : -cross) / (f - s).norm());
      }
      return least;
    };
    for (int y = 0; y < k.height_px; ++y)
      for (int x = 0; x < k.width_px; ++x) {
        const double m = std::max(margin(0, 1, 2, x, y), margin(0, 2, 3, x, y));
        const bool drawn = ids.at<int>(y, x) == 0;
        if (m > 1e-3) {
          ++inside;
          wrong += !drawn;
        } else if (m < -1e-3) {
          wrong += drawn;
        }
      }
  }
  CHECK(inside > 10000);
  CHECK(wrong == 0);
}

TEST_CASE("patch map: a render of a region equals the whole render there, empty elsewhere",
          "[fovea][patch]") {
  fovea::PatchMap map;
  map.Add(Square(2.0, 0.5));
  map.Add(Square(1.0, 0.1));
  map.Add(Square(1.02, 0.3));  // the same surface as the near patch, about it
  const auto k = rig::CameraIntrinsics::FromHorizontalFov(200, 150, 1.0);
  cv::Mat depth, ids;
  map.Render(Eigen::Isometry3d::Identity(), k, &depth, &ids);
  // Regions across the patches' edges, one reaching past the image.
  for (const cv::Rect region : {cv::Rect(80, 60, 30, 20), cv::Rect(150, 100, 80, 80)}) {
    cv::Mat region_depth, region_ids;
    map.Render(Eigen::Isometry3d::Identity(), k, &region_depth, &region_ids, region);
    REQUIRE(region_depth.size() == depth.size());
    const cv::Rect inside = region & cv::Rect(0, 0, 200, 150);
    int differ = 0, drawn_outside = 0, set = 0;
    for (int v = 0; v < 150; ++v)
      for (int u = 0; u < 200; ++u) {
        if (inside.contains({u, v})) {
          differ += region_depth.at<float>(v, u) != depth.at<float>(v, u) ||
                    region_ids.at<int>(v, u) != ids.at<int>(v, u);
          set += region_ids.at<int>(v, u) >= 0;
        } else {
          drawn_outside += region_depth.at<float>(v, u) != 0 || region_ids.at<int>(v, u) != -1;
        }
      }
    INFO("region " << region);
    CHECK(differ == 0);
    CHECK(drawn_outside == 0);
    CHECK(set > 0);
  }
}

TEST_CASE("patch map: a large render on two threads equals its quarters' renders on one",
          "[fovea][patch]") {
  // 600 overlapping patches at random depths, some of them the same surface
  // as others (the finer level wins there, else the nearer): the whole
  // 640 x 480 view is drawn on two threads, each quarter (under the
  // threads' 2^17 pixels) on one; every pixel agrees.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  fovea::PatchMap map;
  for (int i = 0; i < 600; ++i) {
    const Eigen::Vector3d centre(0.5 * u(rng), 0.4 * u(rng), 1.2 + 0.02 * std::round(4 * u(rng)));
    const double w = 0.05 + 0.04 * u(rng), h = 0.05 + 0.04 * u(rng), slant = 0.2 * u(rng);
    fovea::Patch p;
    p.corners_W = {
        centre + Eigen::Vector3d(-w, -h, -slant * w), centre + Eigen::Vector3d(w, -h, slant * w),
        centre + Eigen::Vector3d(w, h, slant * w), centre + Eigen::Vector3d(-w, h, -slant * w)};
    p.level = i % 3 == 0 ? fovea::PatchLevel::kFoveal : fovea::PatchLevel::kPeripheral;
    p.sigma_z_m = 0.005;
    map.Add(p);
  }
  const auto k = rig::CameraIntrinsics::FromHorizontalFov(640, 480, 1.0);
  cv::Mat depth, ids;
  map.Render(Eigen::Isometry3d::Identity(), k, &depth, &ids);
  int differ = 0, drawn = 0;
  for (const cv::Rect quarter : {cv::Rect(0, 0, 320, 240), cv::Rect(320, 0, 320, 240),
                                 cv::Rect(0, 240, 320, 240), cv::Rect(320, 240, 320, 240)}) {
    cv::Mat quarter_depth, quarter_ids;
    map.Render(Eigen::Isometry3d::Identity(), k, &quarter_depth, &quarter_ids, quarter);
    for (int v = quarter.y; v < quarter.br().y; ++v)
      for (int x = quarter.x; x < quarter.br().x; ++x) {
        differ += quarter_depth.at<float>(v, x) != depth.at<float>(v, x) ||
                  quarter_ids.at<int>(v, x) != ids.at<int>(v, x);
        drawn += ids.at<int>(v, x) >= 0;
      }
  }
  CHECK(differ == 0);
  CHECK(drawn > 640 * 480 / 2);
}

TEST_CASE("blocks across a depth step split instead of bridging it", "[fovea][patch]") {
  // A 64 x 64 disparity image: 10 px left of x = 37, 20 px right of it
  // (noise 0.1 px), except a 4 px strip left of the step where matching
  // found nothing (the nearer surface's fattening, dropped).
  cv::Mat d(64, 64, CV_32F);
  std::mt19937_64 rng(5);
  std::normal_distribution<float> noise(0, 0.1f);
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x)
      d.at<float>(y, x) = x >= 33 && x < 37 ? std::numeric_limits<float>::quiet_NaN()
                                            : (x < 37 ? 10.f : 20.f) + noise(rng);
  fovea::PlaneFitOptions options;
  options.min_inlier_share = 0.8;
  const fovea::BlockOptions paper{/*min_fill_share=*/0, /*min_block_px=*/16,
                                  /*clip_to_inliers=*/false};
  const fovea::BlockOptions quarters{/*min_fill_share=*/0.5, /*min_block_px=*/4,
                                     /*clip_to_inliers=*/false};
  const auto whole = fovea::FitBlocks(d, 16, options, paper, nullptr);
  const auto split = fovea::FitBlocks(d, 16, options, quarters, nullptr);
  // A plane may reach over the step by no more than the fit tolerance: at
  // every pixel of its block, the true disparity lies within it of the plane.
  auto worst = [&](const std::vector<fovea::BlockFit>& fits) {
    double w = 0;
    for (const fovea::BlockFit& b : fits)
      for (int y = b.y; y < b.y + b.size; ++y)
        for (int x = b.x; x < b.x + b.size; ++x)
          if (x < 33 || x >= 37) w = std::max(w, std::abs((x < 37 ? 10.0 : 20.0) - b.fit(x, y)));
    return w;
  };
  INFO("whole blocks: worst " << worst(whole) << " px over " << whole.size()
                              << " blocks; split: worst " << worst(split) << " px over "
                              << split.size() << " blocks");
  CHECK(worst(whole) > 5);  // the paper's whole blocks: one reaches over the step
  CHECK(worst(split) <= options.fit_tolerance_px);
  // Away from the step the blocks stay whole.
  int whole_blocks = 0;
  for (const fovea::BlockFit& b : split) whole_blocks += b.size == 16;
  CHECK(whole_blocks == 12);  // 4 rows x (2 left + 1 right) blocks clear of x = 32..47
}

TEST_CASE("with half_agreement a half-block extends a whole neighbour's surface up to a step",
          "[fovea][patch]") {
  // Two 16-pixel blocks that cannot be split (min_block_px 16, the
  // periphery's), side by side or one above the other. A nearer slanted
  // surface (disparity 20 + 0.05 x) fills the first block and the first
  // half of the second; a farther one (10) the second half; noise 0.1 px.
  std::mt19937_64 rng(9);
  std::normal_distribution<float> noise(0, 0.1f);
  auto near = [](int x) { return 20.0 + 0.05 * x; };
  fovea::PlaneFitOptions options;
  options.min_support = 12;
  options.fit_tolerance_px = 0.7;
  options.min_inlier_share = 0.8;
  fovea::BlockOptions blocks;
  blocks.min_block_px = 16;
  for (const bool rows : {false, true}) {
    INFO((rows ? "blocks one above the other" : "blocks side by side"));
    const cv::Size size = rows ? cv::Size(16, 32) : cv::Size(32, 16);
    cv::Mat d(size, CV_32F);
    for (int y = 0; y < d.rows; ++y)
      for (int x = 0; x < d.cols; ++x)
        d.at<float>(y, x) = static_cast<float>(((rows ? y : x) < 24 ? near(x) : 10.0) + noise(rng));
    blocks.half_agreement = 0;
    const auto without = fovea::FitBlocks(d, 16, options, blocks, nullptr);
    REQUIRE(without.size() == 1);  // the first block; the second is not whole
    blocks.half_agreement = 2;
    const auto with = fovea::FitBlocks(d, 16, options, blocks, nullptr);
    // The first block, then its surface's half of the second. The farther
    // half is whole too, but no whole block beside it holds its surface.
    REQUIRE(with.size() == 2);
    CHECK(with[0].footprint.isApprox(without[0].footprint));
    const Eigen::Vector4d half =
        rows ? Eigen::Vector4d(-0.5, 15.5, 15.5, 23.5) : Eigen::Vector4d(15.5, -0.5, 23.5, 15.5);
    CHECK(with[1].footprint.isApprox(half));
    // No footprint reaches over the step: its plane is within the fit
    // tolerance of the truth at every pixel it covers.
    double worst = 0;
    for (const fovea::BlockFit& b : with)
      for (int y = 0; y < d.rows; ++y)
        for (int x = 0; x < d.cols; ++x)
          if (x >= b.footprint(0) && x <= b.footprint(2) && y >= b.footprint(1) &&
              y <= b.footprint(3))
            worst = std::max(worst, std::abs(((rows ? y : x) < 24 ? near(x) : 10.0) - b.fit(x, y)));
    CHECK(worst <= options.fit_tolerance_px);
  }
  // A half of another depth (a false match, 30 px) beside scattered
  // matches, next to a whole block of the nearer surface: it extends
  // nothing, so it stays out.
  cv::Mat d(16, 32, CV_32F);
  std::uniform_real_distribution<float> anywhere(0, 40);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 32; ++x)
      d.at<float>(y, x) = x < 16   ? static_cast<float>(near(x)) + noise(rng)
                          : x < 24 ? 30.f + noise(rng)
                                   : anywhere(rng);
  blocks.half_agreement = 2;
  CHECK(fovea::FitBlocks(d, 16, options, blocks, nullptr).size() == 1);
}

TEST_CASE("a block's patch covers its inliers, not the far side of an edge without data",
          "[fovea][patch]") {
  // One 16-pixel block: a plane on its left 11 columns; the rest has no
  // match (the far side of a depth edge, eroded or occluded). The inliers
  // fill 69% of the block, so it stays whole; its patch must stop where the
  // data stops instead of extrapolating the plane over the far side.
  cv::Mat d(16, 16, CV_32F, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 11; ++x) d.at<float>(y, x) = 12.f + 0.05f * x;
  fovea::PlaneFitOptions options;
  fovea::BlockOptions blocks;  // the defaults: clipped
  const auto clipped = fovea::FitBlocks(d, 16, options, blocks, nullptr);
  REQUIRE(clipped.size() == 1);
  CHECK(clipped[0].footprint.isApprox(Eigen::Vector4d(-0.5, -0.5, 10.5, 15.5)));
  CHECK(clipped[0].fit(5, 5) == Approx(12.25).margin(1e-9));
  blocks.clip_to_inliers = false;  // the paper's tiling: the whole block
  const auto tiled = fovea::FitBlocks(d, 16, options, blocks, nullptr);
  REQUIRE(tiled.size() == 1);
  CHECK(tiled[0].footprint.isApprox(Eigen::Vector4d(-0.5, -0.5, 15.5, 15.5)));
}

TEST_CASE("with clip_diagonals a block's patch stops at an edge that crosses it at a slant",
          "[fovea][patch]") {
  // One 16-pixel block: a plane where x >= y - 4, no match below that
  // line (the far side of a depth edge crossing the block at 45 degrees).
  // The inliers (190) fill 74% of the block and reach all four quadrants,
  // so it stays whole; the 66 pixels beyond the edge are empty.
  cv::Mat d(16, 16, CV_32F, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
  for (int y = 0; y < 16; ++y)
    for (int x = std::max(0, y - 4); x < 16; ++x) d.at<float>(y, x) = 12.f + 0.05f * x;
  fovea::PlaneFitOptions options;
  fovea::BlockOptions blocks;
  blocks.clip_diagonals = true;
  const auto hugged = fovea::FitBlocks(d, 16, options, blocks, nullptr);
  REQUIRE(hugged.size() == 1);
  // Whether a pixel centre lies inside the convex quad (either orientation).
  auto inside = [](const fovea::Quad2d& q, double x, double y) {
    int positive = 0, negative = 0;
    for (int c = 0; c < 4; ++c) {
      const Eigen::Vector2d a = q[c], b = q[(c + 1) % 4];
      const double cross = (b - a).x() * (y - a.y()) - (b - a).y() * (x - a.x());
      positive += cross > 1e-9;
      negative += cross < -1e-9;
    }
    return positive == 0 || negative == 0;
  };
  int inliers_in = 0, beyond = 0;
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) {
      if (!inside(hugged[0].corners, x, y)) continue;
      inliers_in += x >= y - 4;
      beyond += x < y - 4;
    }
  // Four corners cannot follow the inliers' five-sided hull: the quad
  // leaves out a sliver of them (the pixels under its side from (0, 4) to
  // the bottom-right corner), but nothing past the edge.
  INFO("inliers covered " << inliers_in << " of 190");
  CHECK(inliers_in >= 160);
  CHECK(beyond == 0);
  // The bounding box (the default) reaches over the whole lower triangle.
  blocks.clip_diagonals = false;
  const auto boxed = fovea::FitBlocks(d, 16, options, blocks, nullptr);
  REQUIRE(boxed.size() == 1);
  CHECK(boxed[0].footprint.isApprox(Eigen::Vector4d(-0.5, -0.5, 15.5, 15.5)));
  int boxed_beyond = 0;
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < y - 4; ++x) boxed_beyond += inside(boxed[0].corners, x, y);
  CHECK(boxed_beyond == 66);
  // Over a rectangle of inliers both footprints are its box.
  cv::Mat r(16, 16, CV_32F, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
  r.colRange(0, 11).setTo(12.f);
  blocks.clip_diagonals = true;
  const auto rect = fovea::FitBlocks(r, 16, options, blocks, nullptr);
  REQUIRE(rect.size() == 1);
  const fovea::Quad2d box = fovea::BoxQuad(Eigen::Vector4d(-0.5, -0.5, 10.5, 15.5));
  for (int c = 0; c < 4; ++c) CHECK(rect[0].corners[c].isApprox(box[c]));
}

TEST_CASE("erosion at disparity jumps drops the nearer side's edge, whatever NaNs lie near",
          "[fovea][patch]") {
  // A nearer surface (disparity 20) left of x = 20, a farther one (10)
  // right of it, unmatched pixels (NaN) sprinkled over both, and one
  // isolated mismatch (5) inside the nearer surface: every nearer pixel
  // within 3 pixels of the farther surface goes, nothing else does.
  cv::Mat d(24, 40, CV_32F);
  for (int y = 0; y < d.rows; ++y)
    for (int x = 0; x < d.cols; ++x)
      d.at<float>(y, x) = (x * 7 + y * 3) % 5 == 0 ? std::numeric_limits<float>::quiet_NaN()
                                                   : (x < 20 ? 20.f : 10.f);
  d.at<float>(12, 8) = 5.f;
  cv::Mat eroded = d.clone();
  const int n = fovea::ErodeAtDisparityJumps(3, 1.5, &eroded);
  int expected = 0;
  for (int y = 0; y < d.rows; ++y)
    for (int x = 0; x < d.cols; ++x) {
      const float before = d.at<float>(y, x), after = eroded.at<float>(y, x);
      if (std::isnan(before)) {
        CHECK(std::isnan(after));
        continue;
      }
      // The rule written plainly: a farther pixel within the radius that has
      // at least 3 neighbours of its own surface.
      const bool near_jump = ErodedByRule(d, x, y, 3, 1.5);
      expected += near_jump;
      INFO("pixel (" << x << ", " << y << ")");
      CHECK(std::isnan(after) == near_jump);
      CHECK(near_jump == (x >= 17 && x < 20));  // the mismatch at (8, 12) costs nothing
    }
  CHECK(n == expected);
  CHECK(expected > 0);
  // The same data in a corner of a larger, otherwise unmatched level (as a
  // fovea lies in its level's image), near the border or not: the same
  // pixels go.
  for (const cv::Point at : {cv::Point(0, 0), cv::Point(30, 17), cv::Point(60, 36)}) {
    INFO("at " << at);
    cv::Mat large(60, 100, CV_32F, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
    d.copyTo(large(cv::Rect(at, d.size())));
    CHECK(fovea::ErodeAtDisparityJumps(3, 1.5, &large) == n);
    int differ = 0;
    for (int y = 0; y < d.rows; ++y)
      for (int x = 0; x < d.cols; ++x) {
        const float a = large.at<float>(at.y + y, at.x + x), b = eroded.at<float>(y, x);
        differ += !(a == b || (std::isnan(a) && std::isnan(b)));
      }
    CHECK(differ == 0);
  }
}

TEST_CASE("erosion at disparity jumps follows its rule on random disparities of any shape",
          "[fovea][patch]") {
  // Disparities scattered about three surfaces with NaNs among them, on
  // maps one or two pixels wide or tall as well as larger ones, and jumps
  // that a float holds exactly or not: every pixel goes exactly when the
  // rule written plainly says so.
  const float kNaN = std::numeric_limits<float>::quiet_NaN();
  cv::RNG rng(7);
  for (const cv::Size size : {cv::Size(1, 9), cv::Size(2, 9), cv::Size(9, 1), cv::Size(9, 2),
                              cv::Size(3, 3), cv::Size(37, 23)})
    for (const double jump : {1.5, 0.7, 2.3}) {
      INFO("size " << size << ", jump " << jump);
      cv::Mat d(size, CV_32F);
      for (int y = 0; y < d.rows; ++y)
        for (int x = 0; x < d.cols; ++x)
          d.at<float>(y, x) =
              rng.uniform(0.0, 1.0) < 0.2
                  ? kNaN
                  : static_cast<float>(10.0 * rng.uniform(1, 4) + rng.uniform(-1.0, 1.0));
      cv::Mat eroded = d.clone();
      const int n = fovea::ErodeAtDisparityJumps(2, jump, &eroded);
      int expected = 0;
      for (int y = 0; y < d.rows; ++y)
        for (int x = 0; x < d.cols; ++x) {
          const float before = d.at<float>(y, x);
          const bool near_jump = ErodedByRule(d, x, y, 2, jump);
          expected += near_jump;
          INFO("pixel (" << x << ", " << y << ")");
          CHECK(std::isnan(eroded.at<float>(y, x)) == (std::isnan(before) || near_jump));
        }
      CHECK(n == expected);
    }
}

TEST_CASE("matches beside a wide unmatched stretch are found along rows and columns",
          "[fovea][patch]") {
  // A nearer surface (disparity 20) left of x = 20, the farther one
  // unmatched (out of the search band) from there to the map's right side;
  // inside the nearer surface a 4-pixel run of unmatched pixels in row 5 (a
  // speck without texture) and a 12-pixel one in row 15 (x = 2 to 13).
  const float kNaN = std::numeric_limits<float>::quiet_NaN();
  cv::Mat d(24, 40, CV_32F, cv::Scalar(20));
  d.colRange(20, 40).setTo(kNaN);
  d(cv::Rect(4, 5, 4, 1)).setTo(kNaN);
  d(cv::Rect(2, 15, 12, 1)).setTo(kNaN);
  CHECK(cv::countNonZero(fovea::BesideUnmatchedRuns(d, 3, 0)) == 0);
  CHECK(cv::countNonZero(fovea::BesideUnmatchedRuns(d, 0, 7)) == 0);
  const cv::Mat beside = fovea::BesideUnmatchedRuns(d, 3, 7);
  REQUIRE(beside.type() == CV_8U);
  for (int y = 0; y < d.rows; ++y)
    for (int x = 0; x < d.cols; ++x) {
      // Within 3 pixels of the unmatched side, or along row 15 within 3 of
      // its 12-pixel run; the speck and the runs of 1 that row 5 and row 15
      // leave in their columns are shorter than 7.
      const bool expected = (x >= 17 && x < 20) || (y == 15 && (x < 2 || (x >= 14 && x < 17)));
      INFO("pixel (" << x << ", " << y << ")");
      CHECK((beside.at<uchar>(y, x) != 0) == expected);
    }
}

TEST_CASE("a block's matches beside an unmatched stretch count in its fit, not its footprint",
          "[fovea][patch]") {
  // One 16-pixel block: a plane of disparity 20 + 0.05 x over x < 12 (its
  // last 3 columns a window's matches carried over the edge), unmatched
  // beyond. Marked unbounded, the 3 columns still support the fit (all 192
  // matches) but the patch stops at x = 8.
  cv::Mat d(16, 16, CV_32F, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 12; ++x) d.at<float>(y, x) = 20.f + 0.05f * x;
  const cv::Mat beside = fovea::BesideUnmatchedRuns(d, 3, 4);
  fovea::PlaneFitOptions options;
  fovea::BlockOptions blocks;
  const auto plain = fovea::FitBlocks(d, 16, options, blocks, nullptr);
  const auto clipped = fovea::FitBlocks(d, 16, options, blocks, nullptr, beside);
  REQUIRE(plain.size() == 1);
  REQUIRE(clipped.size() == 1);
  CHECK(plain[0].footprint.isApprox(Eigen::Vector4d(-0.5, -0.5, 11.5, 15.5)));
  CHECK(clipped[0].footprint.isApprox(Eigen::Vector4d(-0.5, -0.5, 8.5, 15.5)));
  CHECK(clipped[0].fit.support == 192);
  CHECK(clipped[0].fit.a == Approx(0.05).margin(1e-6));
  CHECK(clipped[0].fit.c == Approx(20).margin(1e-5));
  // A block whose every match lies beside the stretch yields no patch (with
  // every block kept whole and no quadrant rule, it would otherwise).
  cv::Mat sliver(16, 16, CV_32F, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
  sliver.colRange(0, 3).setTo(20);
  options.require_quadrants = false;
  const fovea::BlockOptions whole{0, 4, true};
  CHECK(fovea::FitBlocks(sliver, 16, options, whole, nullptr).size() == 1);
  CHECK(fovea::FitBlocks(sliver, 16, options, whole, nullptr,
                         fovea::BesideUnmatchedRuns(sliver, 3, 4))
            .empty());
}

TEST_CASE("foveal pixels near a depth jump or a hole of the map are marked, no others",
          "[fovea][foveal]") {
  // Rectangles x0..x1 by z -1..1 at depth y, seen by a camera at the origin
  // looking along +y: columns 0-79 show x < 0, columns 80-159 x > 0.
  auto rect = [](double x0, double x1, double y, fovea::PatchLevel level) {
    fovea::Patch p;
    p.corners_W = {Eigen::Vector3d(x0, y, -1), Eigen::Vector3d(x1, y, -1),
                   Eigen::Vector3d(x1, y, 1), Eigen::Vector3d(x0, y, 1)};
    p.level = level;
    return p;
  };
  const rig::CameraView view = ForwardView(160, 120, 150);
  auto marked = [&](const fovea::PatchMap& map, int radius) {
    cv::Mat depth, ids;
    map.Render(view.world_T_camera, view.intrinsics, &depth, &ids);
    return fovea::FovealNearEdges(map, depth, ids, radius);
  };
  using L = fovea::PatchLevel;
  auto row = [](const cv::Mat& m, int lo, int hi, int lo2 = -1, int hi2 = -1) {
    for (int x = 0; x < m.cols; ++x) {
      INFO("column " << x);
      const bool in = (x >= lo && x <= hi) || (x >= lo2 && x <= hi2);
      CHECK(m.at<uchar>(60, x) == (in ? 1 : 0));
    }
  };
  fovea::PatchMap jump;
  jump.Add(rect(-1, 0, 1.0, L::kFoveal));
  jump.Add(rect(0, 1, 1.2, L::kFoveal));
  // The jump lies between columns 79 and 80; the image's border is no edge.
  row(marked(jump, 4), 75, 84);
  CHECK(marked(jump, 0).empty());
  fovea::PatchMap same;  // 1 mm apart: one surface
  same.Add(rect(-1, 0, 1.0, L::kFoveal));
  same.Add(rect(0, 1, 1.001, L::kFoveal));
  row(marked(same, 4), -1, -1);
  fovea::PatchMap peripheral;  // only foveal pixels are marked
  peripheral.Add(rect(-1, 0, 1.0, L::kFoveal));
  peripheral.Add(rect(0, 1, 1.2, L::kPeripheral));
  row(marked(peripheral, 4), 75, 79);
  fovea::PatchMap hole;  // columns 65-79 unmapped, one depth on both sides
  hole.Add(rect(-1, -0.1, 1.0, L::kFoveal));
  hole.Add(rect(0, 1, 1.0, L::kFoveal));
  row(marked(hole, 2), 62, 64, 80, 82);
}
