// Integration: the hierarchical replacement rule, judged in the current view.
#include "fovea/integration.h"

#include <catch2/catch.hpp>

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
  // Peripheral patches: one 20 cm patch over the fovea, others around it.
  fovea::PatchMap periphery = Grid(5, 0.5, 1.0, fovea::PatchLevel::kPeripheral, 2);
  const auto stats = fovea::Integrate(&map, periphery, view);
  CHECK(stats.dropped_under_finer == 1);  // the one over the fovea
  CHECK(stats.added == 24);
  CHECK(stats.replaced[2] == 0);
  CHECK(map.CountByLevel() == std::array<int, 3>{0, 24, 64});
  // Peripheral replaces peripheral of the same or coarser resolution...
  const auto again =
      fovea::Integrate(&map, Grid(5, 0.5, 1.0, fovea::PatchLevel::kPeripheral, 1), view);
  CHECK(again.replaced[1] == 24);
  CHECK(map.CountByLevel() == std::array<int, 3>{0, 24, 64});
  // ...but a coarser resolution does not replace a finer one.
  const auto coarser =
      fovea::Integrate(&map, Grid(5, 0.5, 1.0, fovea::PatchLevel::kPeripheral, 3), view);
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
