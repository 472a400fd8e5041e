#include <catch2/catch.hpp>
#include <cmath>

#include "rig/types.h"

using rig::Axis;

TEST_CASE("intrinsics from a horizontal field of view", "[rig]") {
  const auto k = rig::CameraIntrinsics::FromHorizontalFov(640, 480, 30 * M_PI / 180);
  // tan(15 deg) = (640 / 2) / f.
  CHECK(k.fx_px == Approx(320 / std::tan(15 * M_PI / 180)).epsilon(1e-12));
  CHECK(k.fy_px == k.fx_px);
  CHECK(k.cx_px == 319.5);
  CHECK(k.cy_px == 239.5);
  // The image edges (pixel borders at -0.5 and W - 0.5) subtend the field.
  const Eigen::Vector3d left = k.Ray({-0.5, 239.5}), right = k.Ray({639.5, 239.5});
  CHECK(std::atan2(right.x(), 1) - std::atan2(left.x(), 1) == Approx(30 * M_PI / 180));
  CHECK(k.VerticalFovRad() == Approx(2 * std::atan(240 / k.fy_px)));
  CHECK_THROWS_AS(rig::CameraIntrinsics::FromHorizontalFov(0, 480, 0.5), rig::RigError);
  CHECK_THROWS_AS(rig::CameraIntrinsics::FromHorizontalFov(640, 480, 4.0), rig::RigError);
}

TEST_CASE("projection and back-projection are inverse, with and without distortion", "[rig]") {
  auto k = rig::CameraIntrinsics::FromHorizontalFov(640, 480, 0.6);
  for (bool distorted : {false, true}) {
    if (distorted) k.distortion = {-0.12, 0.05, 0.001, -0.0005, 0.0};
    for (const Eigen::Vector3d& p : {Eigen::Vector3d(0.1, -0.05, 1.2),
                                     Eigen::Vector3d(-0.2, 0.1, 0.8), Eigen::Vector3d(0, 0, 2)}) {
      const Eigen::Vector2d uv = k.Project(p);
      const Eigen::Vector3d ray = k.Ray(uv);
      CHECK((ray * p.z() - p).norm() < 1e-9);
    }
  }
  k.distortion = {1, 2, 3};
  CHECK_THROWS_AS(k.Check(), rig::RigError);
}

TEST_CASE("stage state helpers", "[rig]") {
  const auto s = rig::StageState::Parallel(0.12);
  CHECK(s.left.carriage_m == Approx(-0.06));
  CHECK(s.right.carriage_m == Approx(0.06));
  CHECK(s.BaselineM() == Approx(0.12));
  const std::array<double, 6> v = {-0.1, 0.2, -0.3, 0.15, -0.05, 0.01};
  CHECK(rig::StageState::FromArray(v).ToArray() == v);
  CHECK(rig::StageState::FromArray(v)[rig::Side::kRight].pan_rad == -0.05);
}

TEST_CASE("limits: quantization to whole steps and range checks", "[rig]") {
  rig::RigLimits limits;
  const double per_rad = 6400 * 180 / M_PI, per_m = 400e3;
  for (int i = 0; i < rig::kNumAxes; ++i) {
    const bool linear = i % 3 == 0;
    limits.axes[i] = linear ? rig::AxisLimit{-0.3, 0.3, per_m} : rig::AxisLimit{-1, 1, per_rad};
  }
  rig::StageState s;
  s.left.pan_rad = 0.1234567 * M_PI / 180;  // 790.12 steps
  s.right.carriage_m = 0.0123456;           // 4938.24 steps
  const rig::StageState q = limits.Quantize(s);
  CHECK(q.left.pan_rad * per_rad == Approx(790).margin(1e-9));
  CHECK(q.right.carriage_m * per_m == Approx(4938).margin(1e-9));
  const auto steps = limits.ToSteps(s);
  CHECK(steps[1] == 790);
  CHECK(steps[3] == 4938);
  // Quantization never moves an axis by more than half a step.
  CHECK(std::abs(q.left.pan_rad - s.left.pan_rad) <= 0.5 / per_rad);

  CHECK(limits.Violation(s).empty());
  s.right.tilt_rad = 1.5;
  const std::string why = limits.Violation(s);
  CHECK(why.find("right tilt") != std::string::npos);
  CHECK(why.find("outside") != std::string::npos);
  s.right.tilt_rad = std::nan("");
  CHECK_FALSE(limits.Violation(s).empty());
}
