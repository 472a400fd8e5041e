// Integration: the hierarchical replacement rule, judged in the current view.
#include "fovea/integration.h"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <random>

#include "test_views.h"

namespace {

rig::CameraView View() { return ForwardView(320, 240, 300); }

// A grid of n x n square patches tiling [-h, h]^2 (X, Z) at depth y.
fovea::PatchMap Grid(int n, double h, double y, fovea::PatchLevel level, int resolution = 0) {
  fovea::PatchMap map;
  const double s = 2 * h / n;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      fovea::Patch p;
      const double x0 = -h + i * s, z0 = -h + j * s;
      p.corners_W = {Eigen::Vector3d(x0, y, z0), Eigen::Vector3d(x0 + s, y, z0),
                     Eigen::Vector3d(x0 + s, y, z0 + s), Eigen::Vector3d(x0, y, z0 + s)};
      p.level = level;
      p.resolution_level = resolution;
      map.Add(p);
    }
  return map;
}

}  // namespace

TEST_CASE("foveal patches replace the coarser patches they cover, and only those",
          "[fovea][integration]") {
  const rig::CameraView view = View();
  fovea::PatchMap map = Grid(10, 0.5, 1.0, fovea::PatchLevel::kIdr);  // 10 cm patches
  // Foveal patches over the central 20 x 20 cm: exactly 4 IDR patches.
  const fovea::PatchMap fovea_patches = Grid(8, 0.1, 1.0, fovea::PatchLevel::kFoveal);
  const auto stats = fovea::Integrate(&map, fovea_patches, view);
  CHECK(stats.offered == 64);
  CHECK(stats.added == 64);
  CHECK(stats.replaced[0] == 4);
  CHECK(map.CountByLevel() == std::array<int, 3>{96, 0, 64});
}

TEST_CASE("peripheral data never replaces foveal data", "[fovea][integration]") {
  const rig::CameraView view = View();
  fovea::PatchMap map = Grid(8, 0.1, 1.0, fovea::PatchLevel::kFoveal);
  // Peripheral patches, all inside the view: one 14 cm patch over the fovea,
  // others around it.
  fovea::PatchMap periphery = Grid(5, 0.35, 1.0, fovea::PatchLevel::kPeripheral, 2);
  const auto stats = fovea::Integrate(&map, periphery, view);
  CHECK(stats.dropped_under_finer == 1);  // the one over the fovea
  CHECK(stats.added == 24);
  CHECK(stats.replaced[2] == 0);
  CHECK(map.CountByLevel() == std::array<int, 3>{0, 24, 64});
  // Peripheral replaces peripheral of the same or coarser resolution...
  const auto again =
      fovea::Integrate(&map, Grid(5, 0.35, 1.0, fovea::PatchLevel::kPeripheral, 1), view);
  CHECK(again.replaced[1] == 24);
  CHECK(map.CountByLevel() == std::array<int, 3>{0, 24, 64});
  // ...but a coarser resolution does not replace a finer one.
  const auto coarser =
      fovea::Integrate(&map, Grid(5, 0.35, 1.0, fovea::PatchLevel::kPeripheral, 3), view);
  CHECK(coarser.added == 0);
  CHECK(coarser.dropped_under_finer == 25);
}

TEST_CASE("integration stays exact with thousands of patches", "[fovea][integration]") {
  const rig::CameraView view = View();
  fovea::PatchMap map = Grid(60, 0.6, 1.2, fovea::PatchLevel::kIdr);  // 3600 patches, 2 cm
  const fovea::PatchMap fresh = Grid(40, 0.2, 1.2, fovea::PatchLevel::kFoveal);  // 1600, 1 cm
  const auto stats = fovea::Integrate(&map, fresh, view);
  // The foveal grid covers exactly 20 x 20 of the IDR patches.
  CHECK(stats.replaced[0] == 400);
  CHECK(map.size() == 3600 - 400 + 1600);
}

TEST_CASE("integration options are checked", "[fovea][integration]") {
  fovea::IntegrationOptions o;
  o.overlap_share = 0;
  CHECK_THROWS_WITH(o.Check(), Catch::Contains("overlap_share"));
}

namespace {

// A grid of patches at depth y + an offset drawn per patch from N(0, sigma),
// each patch knowing its sigma.
fovea::PatchMap NoisyGrid(int n, double h, double y, double sigma, std::mt19937_64* rng) {
  fovea::PatchMap grid = Grid(n, h, y, fovea::PatchLevel::kFoveal);
  std::normal_distribution<double> noise(0, sigma);
  fovea::PatchMap out;
  for (fovea::Patch p : grid.patches()) {
    const double e = noise(*rng);
    for (auto& c : p.corners_W) c.y() += e;
    p.sigma_z_m = sigma;
    out.Add(p);
  }
  return out;
}

// RMS depth error of the map against a plane at depth y, over the pixels it
// covers within `half_px` of the image centre (away from the grids' rims,
// where a patch's footprint depends on its depth).
double RmsError(const fovea::PatchMap& map, const rig::CameraView& view, double y, int half_px) {
  cv::Mat depth;
  map.Render(view.world_T_camera, view.intrinsics, &depth, nullptr);
  const int r0 = depth.rows / 2, c0 = depth.cols / 2;
  double sum = 0;
  long n = 0;
  for (int r = r0 - half_px; r < r0 + half_px; ++r)
    for (int c = c0 - half_px; c < c0 + half_px; ++c)
      if (const float z = depth.at<float>(r, c); z > 0) {
        sum += (z - y) * (z - y);
        ++n;
      }
  return n ? std::sqrt(sum / n) : 0;
}

}  // namespace

TEST_CASE("fusing two noisy observations of a plane divides the error by sqrt 2",
          "[fovea][integration]") {
  // Two independent observations of the plane y = 1, each patch off by
  // N(0, 5 mm): the inverse-variance mean of two is off by 5 / sqrt 2 mm.
  const rig::CameraView view = View();
  const double sigma = 0.005;
  std::mt19937_64 rng(3);
  double before = 0, after = 0;
  const int trials = 10;
  for (int t = 0; t < trials; ++t) {
    fovea::PatchMap map = NoisyGrid(12, 0.3, 1.0, sigma, &rng);
    const fovea::PatchMap second = NoisyGrid(12, 0.3, 1.0, sigma, &rng);
    before += RmsError(map, view, 1.0, 60) / trials;
    const auto stats = fovea::Integrate(&map, second, view);
    // Two observations more than 3 sigma apart (0.3% of pairs) read as two
    // surfaces and are not fused.
    CHECK(stats.fused >= 140);
    CHECK(stats.added == 144);
    // The fused patches replace the old ones, but for a few on the grid's
    // rim whose new footprint is smaller (farther) than the old one.
    CHECK(stats.replaced[2] >= 130);
    after += RmsError(map, view, 1.0, 60) / trials;
    // Every fused patch is more certain than either observation; those with
    // all four corners fused (all but some on the rim, whose corners' rays
    // may miss the old grid) are certain by exactly sqrt 2.
    int surer = 0, halved = 0;
    for (const fovea::Patch& p : map.patches()) {
      surer += p.sigma_z_m < sigma - 1e-12;
      halved += std::abs(p.sigma_z_m - sigma / std::sqrt(2.0)) < 1e-9;
    }
    CHECK(surer == stats.fused);
    CHECK(halved >= 100);
  }
  INFO("RMS error before " << 1e3 * before << " mm, after " << 1e3 * after << " mm");
  CHECK(before == Approx(sigma).epsilon(0.15));
  CHECK(after / before == Approx(1 / std::sqrt(2.0)).epsilon(0.1));
  // Without fusion the new observation replaces the old one: no gain.
  fovea::PatchMap map = NoisyGrid(12, 0.3, 1.0, sigma, &rng);
  fovea::IntegrationOptions paper;
  paper.fuse = false;
  CHECK(fovea::Integrate(&map, NoisyGrid(12, 0.3, 1.0, sigma, &rng), view, paper).fused == 0);
}

TEST_CASE("a foveal patch is fused with the peripheral patch under it, weighed by their sigmas",
          "[fovea][integration]") {
  // The plane y = 1 seen by the periphery (20 cm patches, 1 mm too far,
  // sigma 2 mm) and then by a fovea (5 cm patches, 3 mm too near, sigma 6
  // mm): the inverse-variance mean is 0.6 mm too far, with sigma
  // 1 / sqrt(1 / 2^2 + 1 / 6^2) mm.
  const rig::CameraView view = View();
  auto shifted = [](fovea::PatchMap grid, double dy, double sigma) {
    fovea::PatchMap out;
    for (fovea::Patch p : grid.patches()) {
      for (auto& c : p.corners_W) c.y() += dy;
      p.sigma_z_m = sigma;
      out.Add(p);
    }
    return out;
  };
  const fovea::PatchMap periphery =
      shifted(Grid(3, 0.3, 1.0, fovea::PatchLevel::kPeripheral, 1), 0.001, 0.002);
  const fovea::PatchMap fovea_patches =
      shifted(Grid(12, 0.3, 1.0, fovea::PatchLevel::kFoveal), -0.003, 0.006);
  fovea::PatchMap map = periphery;
  const auto stats = fovea::Integrate(&map, fovea_patches, view);
  CHECK(stats.fused == 144);
  CHECK(stats.replaced[1] == 9);  // the foveal patches, fused, replace the peripheral ones
  CHECK(RmsError(map, view, 1.0, 60) == Approx(0.0006).epsilon(0.02));
  const double fused_sigma = 1 / std::sqrt(1 / (0.002 * 0.002) + 1 / (0.006 * 0.006));
  for (const fovea::Patch& p : map.patches()) CHECK(p.sigma_z_m == Approx(fused_sigma));
  // The paper's hierarchy alone: the finer level replaces the coarser one
  // as it is, 3 mm off.
  fovea::IntegrationOptions hierarchy;
  hierarchy.fuse_across_levels = false;
  map = periphery;
  CHECK(fovea::Integrate(&map, fovea_patches, view, hierarchy).fused == 0);
  CHECK(RmsError(map, view, 1.0, 60) == Approx(0.003).epsilon(0.02));
  // IDR's coarse guesses are never fused into finer patches.
  map = shifted(Grid(3, 0.3, 1.0, fovea::PatchLevel::kIdr), 0.001, 0.002);
  CHECK(fovea::Integrate(&map, fovea_patches, view).fused == 0);
  CHECK(RmsError(map, view, 1.0, 60) == Approx(0.003).epsilon(0.02));
}

TEST_CASE("a coarse patch that certain data contradicts goes, whichever came first",
          "[fovea][integration]") {
  const rig::CameraView view = View();
  // A peripheral patch 20 cm in front of a surface foveal data sees at 1 m:
  // the camera that saw the surface saw through it.
  fovea::PatchMap map = Grid(1, 0.1, 0.8, fovea::PatchLevel::kPeripheral, 1);
  fovea::Patch coarse = map[0];
  coarse.sigma_z_m = 0.01;
  map = fovea::PatchMap();
  map.Add(coarse);
  fovea::PatchMap fine;
  const fovea::PatchMap grid = Grid(4, 0.1, 1.0, fovea::PatchLevel::kFoveal);
  for (fovea::Patch p : grid.patches()) {
    p.sigma_z_m = 0.001;
    fine.Add(p);
  }
  const auto stats = fovea::Integrate(&map, fine, view);
  CHECK(stats.removed_contradicted[1] == 1);
  CHECK(stats.added == 16);
  CHECK(map.CountByLevel() == std::array<int, 3>{0, 0, 16});
  // The other way round: the coarse patch arrives after the fine data and is
  // dropped.
  const auto late = fovea::Integrate(
      &map,
      [&] {
        fovea::PatchMap m;
        m.Add(coarse);
        return m;
      }(),
      view);
  CHECK(late.dropped_contradicted == 1);
  CHECK(map.CountByLevel() == std::array<int, 3>{0, 0, 16});
  // With contradictions off (the paper's rule) the coarse patch stays.
  fovea::IntegrationOptions paper;
  paper.contradiction_share = 1;
  CHECK(fovea::Integrate(
            &map,
            [&] {
              fovea::PatchMap m;
              m.Add(coarse);
              return m;
            }(),
            view, paper)
            .added == 1);
}

TEST_CASE("a patch mostly outside the view is not replaced by what covers its sliver in it",
          "[fovea][integration]") {
  const rig::CameraView view = View();  // sees x in [-0.53, 0.53] m at 1 m
  // An IDR patch from x = 0.4 to 0.8 m: a third of it inside the view.
  fovea::PatchMap map;
  fovea::Patch idr;
  idr.corners_W = {Eigen::Vector3d(0.4, 1.0, -0.1), Eigen::Vector3d(0.8, 1.0, -0.1),
                   Eigen::Vector3d(0.8, 1.0, 0.1), Eigen::Vector3d(0.4, 1.0, 0.1)};
  idr.level = fovea::PatchLevel::kIdr;
  map.Add(idr);
  // Foveal patches over x in [0.3, 0.7]: all of the sliver the view shows.
  fovea::PatchMap fine;
  for (int i = 0; i < 4; ++i) {
    fovea::Patch p = idr;
    p.level = fovea::PatchLevel::kFoveal;
    const double x0 = 0.3 + 0.1 * i;
    p.corners_W = {Eigen::Vector3d(x0, 1.0, -0.1), Eigen::Vector3d(x0 + 0.1, 1.0, -0.1),
                   Eigen::Vector3d(x0 + 0.1, 1.0, 0.1), Eigen::Vector3d(x0, 1.0, 0.1)};
    fine.Add(p);
  }
  const auto stats = fovea::Integrate(&map, fine, view);
  CHECK(stats.replaced[0] == 0);
  CHECK(map.CountByLevel() == std::array<int, 3>{1, 0, 4});
  // Moved into the view, the same patch is replaced by the same cover.
  fovea::PatchMap inside;
  fovea::Patch idr_in = idr;
  for (auto& c : idr_in.corners_W) c.x() -= 0.3;  // x from 0.1 to 0.5
  inside.Add(idr_in);
  fovea::PatchMap cover;
  for (fovea::Patch p : fine.patches()) {
    for (auto& c : p.corners_W) c.x() -= 0.2;  // x from 0.1 to 0.5
    cover.Add(p);
  }
  CHECK(fovea::Integrate(&inside, cover, view).replaced[0] == 1);
}

TEST_CASE("IDR patches are retired where finer patches of several fixations cover them",
          "[fovea][integration]") {
  const rig::CameraView view = View();
  fovea::PatchMap map = Grid(10, 0.5, 1.0, fovea::PatchLevel::kIdr);  // 10 cm cells at 1 m
  // A peripheral patch at depth y whose footprint in the view is the
  // square [x0, x0 + w] x [z0, z0 + h] of the plane at 1 m.
  auto square = [](double x0, double z0, double w, double h, double y = 1.0) {
    fovea::Patch p;
    p.corners_W = {Eigen::Vector3d(x0, 1.0, z0), Eigen::Vector3d(x0 + w, 1.0, z0),
                   Eigen::Vector3d(x0 + w, 1.0, z0 + h), Eigen::Vector3d(x0, 1.0, z0 + h)};
    for (auto& c : p.corners_W) c *= y;
    p.level = fovea::PatchLevel::kPeripheral;
    p.resolution_level = 1;
    return p;
  };
  // IDR cell 55 spans x, z in [0, 0.1]: covered by two halves (two fixations'
  // patches); cell 45 (x in [-0.1, 0]) only on its left half. Cell 65 (x in
  // [0.1, 0.2]) has a whole patch behind it, at 1.6 m: the farther surface
  // seen past its edge, which does not cover it; cell 75 (x in [0.2, 0.3])
  // one in front of it, at 0.8 m, which does.
  map.Add(square(0.0, 0.0, 0.1, 0.05));
  map.Add(square(0.0, 0.05, 0.1, 0.05));
  map.Add(square(-0.1, 0.0, 0.05, 0.1));
  map.Add(square(0.1, 0.0, 0.1, 0.1, 1.6));
  map.Add(square(0.2, 0.0, 0.1, 0.1, 0.8));
  const std::vector<char> covered = fovea::CoveredIdrPatches(map, {view}, 0.9);
  REQUIRE(covered.size() == map.size());
  CHECK(std::count(covered.begin(), covered.end(), 1) == 2);
  CHECK(covered[55] == 1);
  CHECK(covered[65] == 0);
  CHECK(covered[75] == 1);
  const std::vector<char> half = fovea::CoveredIdrPatches(map, {view}, 0.4);
  CHECK(std::count(half.begin(), half.end(), 1) == 3);
  CHECK(half[45] == 1);
  CHECK(half[65] == 0);
  CHECK(std::count(half.begin() + 100, half.end(), 1) == 0);  // finer patches never
  // Without finer patches nothing is covered.
  const std::vector<char> none =
      fovea::CoveredIdrPatches(Grid(10, 0.5, 1.0, fovea::PatchLevel::kIdr), {view}, 0.0);
  CHECK(std::count(none.begin(), none.end(), 1) == 0);
}
