// The patch map's spatial index: same answers as testing every patch, on
// thousands of patches; removal; level precedence when rendering.
#include <catch2/catch.hpp>
#include <random>

#include "fovea/geometry.h"
#include "fovea/patch.h"

namespace {

fovea::Patch RandomPatch(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> pos(-1, 1), size(0.005, 0.05), angle(-1.2, 1.2);
  const Eigen::Vector3d c(pos(rng), 1.5 + pos(rng), pos(rng));
  const Eigen::Matrix3d r = (Eigen::AngleAxisd(angle(rng), Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(angle(rng), Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  const double s = size(rng);
  fovea::Patch p;
  const double xs[4] = {-s, s, s, -s}, zs[4] = {-s, -s, s, s};
  for (int i = 0; i < 4; ++i) p.corners_W[i] = c + r * Eigen::Vector3d(xs[i], 0, zs[i]);
  p.level = static_cast<fovea::PatchLevel>(rng() % 3);
  return p;
}

fovea::Patch Square(double y, double half, fovea::PatchLevel level) {
  fovea::Patch p;
  p.corners_W = {Eigen::Vector3d(-half, y, -half), Eigen::Vector3d(half, y, -half),
                 Eigen::Vector3d(half, y, half), Eigen::Vector3d(-half, y, half)};
  p.level = level;
  return p;
}

}  // namespace

TEST_CASE("the map's index answers ray queries exactly as testing every patch", "[fovea][patch]") {
  std::mt19937_64 rng(3);
  fovea::PatchMap map;
  for (int i = 0; i < 5000; ++i) map.Add(RandomPatch(rng));
  std::uniform_real_distribution<double> dir(-0.6, 0.6);
  int hits = 0;
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector3d o(0.3 * dir(rng), 0, 0.3 * dir(rng));
    const Eigen::Vector3d d = Eigen::Vector3d(dir(rng), 1, dir(rng)).normalized();
    const auto a = map.CastRay(o, d), b = map.CastRayBruteForce(o, d);
    REQUIRE(a.has_value() == b.has_value());
    if (!a) continue;
    ++hits;
    CHECK(a->patch == b->patch);
    CHECK(a->distance_m == Approx(b->distance_m).margin(1e-12));
  }
  CHECK(hits > 200);  // the test rays do hit the map
  CHECK(map.IndexNodes() > 1000);

  // Removing patches invalidates the index; answers stay exact.
  std::vector<char> drop(map.size(), 0);
  for (size_t i = 0; i < drop.size(); i += 2) drop[i] = 1;
  CHECK(map.Remove(drop) == 2500);
  REQUIRE(map.size() == 2500);
  for (int i = 0; i < 500; ++i) {
    const Eigen::Vector3d d = Eigen::Vector3d(dir(rng), 1, dir(rng)).normalized();
    const auto a = map.CastRay(Eigen::Vector3d::Zero(), d),
               b = map.CastRayBruteForce(Eigen::Vector3d::Zero(), d);
    REQUIRE(a.has_value() == b.has_value());
    if (a) CHECK(a->patch == b->patch);
  }
}

TEST_CASE("rendering shows the finer level where patches of one surface overlap",
          "[fovea][patch]") {
  rig::CameraIntrinsics k;
  k.width_px = 64;
  k.height_px = 48;
  k.fx_px = k.fy_px = 60;
  k.cx_px = 31.5;
  k.cy_px = 23.5;
  // Camera at the origin looking along +Y (world Z up).
  Eigen::Isometry3d world_T_camera = Eigen::Isometry3d::Identity();
  world_T_camera.linear() << 1, 0, 0, 0, 0, 1, 0, -1, 0;
  fovea::PatchMap map;
  map.Add(Square(1.000, 0.5, fovea::PatchLevel::kIdr));     // slightly nearer, coarser
  map.Add(Square(1.005, 0.1, fovea::PatchLevel::kFoveal));  // same surface within 2%
  map.Add(Square(2.000, 0.9, fovea::PatchLevel::kFoveal));  // a different surface behind
  cv::Mat depth, ids;
  map.Render(world_T_camera, k, &depth, &ids);
  CHECK(ids.at<int>(24, 32) == 1);  // centre: the foveal patch wins over the nearer IDR one
  CHECK(depth.at<float>(24, 32) == Approx(1.005).epsilon(1e-4));
  CHECK(ids.at<int>(24, 5) ==
        0);  // outside the small patch: the IDR one, nearer than the far plane
  CHECK(map.CountByLevel() == std::array<int, 3>{1, 0, 2});
}
