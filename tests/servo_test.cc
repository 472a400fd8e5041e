// Visual servoing on the simulated rig, noise on.
#include <catch2/catch.hpp>
#include <cmath>

#include "fovea/servo.h"
#include "fovea/vergence.h"
#include "scenes/catalog.h"

TEST_CASE("servoing converges from 20 px off within 6 steps", "[fovea][servo][slow]") {
  sim::SimRigConfig config;
  config.noise.read_noise_sigma_dn = 2.0;
  struct Point {
    std::string scene;
    Eigen::Vector3d p_W;
  };
  const std::vector<Point> points = {{"cylinder_planes", {0.0, 0.89, 0.0}},
                                     {"cylinder_planes", {-0.2, 0.93, 0.05}},
                                     {"cylinder_planes", {0.25, 1.0, -0.05}},
                                     {"three_surfaces", {-0.05, 0.53, -0.055}},
                                     {"three_surfaces", {0.09, 0.86, 0.05}},
                                     {"three_surfaces", {-0.25, 1.2, 0.1}}};
  for (const Point& pt : points) {
    INFO(pt.scene << " " << pt.p_W.transpose());
    auto sim = scenes::LoadScene(pt.scene, config);
    rig::Rig& rig = sim->rig();
    const auto sol = fovea::Verge(rig.Geometry(), rig.Limits(), rig.Intrinsics(rig::Side::kLeft),
                                  rig.Intrinsics(rig::Side::kRight), rig::StageState::Parallel(0.12), pt.p_W);
    REQUIRE(sol.ok);
    rig::StageState start = sol.state;
    const double f = rig.Intrinsics(rig::Side::kRight).fx_px;
    start.right.pan_rad += std::atan(20.0 / f);  // the point 20 px off centre
    const fovea::ServoResult r = fovea::Servo(rig, start, {});
    INFO("residuals: " << [&] { std::string s; for (double d : r.residuals_px) s += std::to_string(d) + " "; return s; }());
    REQUIRE_FALSE(r.residuals_px.empty());
    CHECK(std::abs(std::abs(r.residuals_px.front()) - 20) < 2);  // it did start 20 px off
    CHECK(r.converged);
    CHECK(std::abs(r.residual_px) < 0.5);
    CHECK(r.iterations <= 6);
  }
}
