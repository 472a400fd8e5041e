#include "fovea/vergence.h"

#include <catch2/catch.hpp>
#include <cmath>

#include "fovea/geometry.h"
#include "test_rig.h"

TEST_CASE("vergence puts the point on both optical axes despite the centre offset",
          "[fovea][vergence]") {
  const auto g = TestGeometry();
  const auto k = rig::CameraIntrinsics::FromHorizontalFov(640, 480, 30 * M_PI / 180);
  const rig::StageState base = rig::StageState::Parallel(0.12);
  for (const Eigen::Vector3d& p :
       {Eigen::Vector3d(0, 1, 0), Eigen::Vector3d(0.2, 0.6, -0.1), Eigen::Vector3d(-0.3, 1.4, 0.2),
        Eigen::Vector3d(0.05, 0.45, 0.05)}) {
    INFO(p.transpose());
    const auto sol = fovea::Verge(g, TestLimits(), k, k, base, p);
    REQUIRE(sol.ok);
    for (rig::Side side : {rig::Side::kLeft, rig::Side::kRight}) {
      const auto uv = fovea::ProjectWorldPoint(g.WorldFromCamera(side, sol.state[side]), k, p);
      REQUIRE(uv);
      CHECK((*uv - Eigen::Vector2d(k.cx_px, k.cy_px)).norm() < 0.01);
      CHECK(sol.state[side].carriage_m == base[side].carriage_m);
    }
    // The naive atan2 (offset ignored) would miss by pixels: the Newton
    // steps matter.
    const Eigen::Vector3d v = p - g.WorldFromHead(rig::Side::kLeft, base.left).translation();
    rig::CameraStage naive = base.left;
    naive.pan_rad = std::atan2(-v.x(), v.y());
    naive.tilt_rad = std::atan2(v.z(), std::hypot(v.x(), v.y()));
    const auto uv = fovea::ProjectWorldPoint(g.WorldFromCamera(rig::Side::kLeft, naive), k, p);
    CHECK((*uv - Eigen::Vector2d(k.cx_px, k.cy_px)).norm() > 1.0);
  }
}

TEST_CASE("points that cannot be fixated are reported, not clamped", "[fovea][vergence]") {
  const auto g = TestGeometry();
  const auto k = rig::CameraIntrinsics::FromHorizontalFov(640, 480, 30 * M_PI / 180);
  const rig::StageState base = rig::StageState::Parallel(0.12);
  const auto beside =
      fovea::Verge(g, TestLimits(), k, k, base, Eigen::Vector3d(2.0, 0.5, 0));  // 76 deg pan
  CHECK_FALSE(beside.ok);
  CHECK(beside.why.find("limits") != std::string::npos);
  const auto above =
      fovea::Verge(g, TestLimits(), k, k, base, Eigen::Vector3d(0, 0.5, 0.5));  // 45 deg tilt
  CHECK_FALSE(above.ok);
  const auto near = fovea::Verge(g, TestLimits(), k, k, base, Eigen::Vector3d(0, 0.1, 0));
  CHECK_FALSE(near.ok);
  CHECK(near.why.find("nearer") != std::string::npos);
}
