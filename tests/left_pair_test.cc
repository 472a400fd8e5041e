// The left camera paired with itself at two carriage positions, on the
// simulated rig (noise off).
#include "rig/left_pair.h"

#include <catch2/catch.hpp>
#include <opencv2/core.hpp>

#include "scenes/catalog.h"

TEST_CASE("left camera pair: two grabs of the left camera, the right camera left alone",
          "[rig][left_pair][slow]") {
  auto sim = scenes::LoadScene("fronto_planes", {});
  rig::Rig& rig = sim->rig();
  rig::LeftCameraPair pair(rig);
  CHECK_THROWS_AS(pair.Capture(), rig::RigError);  // nothing grabbed yet

  const rig::StageState before = rig.State();
  rig::StageState target;
  target.left = {-0.11, 0.02, 0.01};
  target.right = {-0.05, -0.01, 0.0};
  // The real right carriage cannot reach -0.05 m; the pair's limits allow it.
  CHECK_FALSE(rig.Limits().Violation(target).empty());
  CHECK(pair.Limits().Violation(target).empty());
  const rig::MoveResult m = pair.MoveTo(target);
  CHECK(m.motion_time_s > 0);
  const rig::StereoFrame f = pair.Capture();

  // Each view was taken by the left head at its stage.
  for (rig::Side side : {rig::Side::kLeft, rig::Side::kRight}) {
    const Eigen::Isometry3d expected =
        rig.Geometry().WorldFromCamera(rig::Side::kLeft, target[side]);
    CHECK((f[side].world_T_camera.translation() - expected.translation()).norm() < 1e-4);
    CHECK(f.state[side].carriage_m == Approx(target[side].carriage_m).margin(1e-5));
  }
  CHECK(rig.State().left.carriage_m == Approx(-0.11).margin(1e-5));
  CHECK(rig.State().right.carriage_m == Approx(before.right.carriage_m).margin(1e-5));
  CHECK(pair.Geometry().right.optical_centre_H == rig.Geometry().left.optical_centre_H);

  // The "right" image is what the left camera sees from there.
  rig::StageState there = rig.Limits().Quantize(rig.State());
  there.left = target.right;
  rig.MoveTo(there);
  const cv::Mat direct = rig.Capture().left.gray;
  CHECK(cv::norm(direct, f.right.gray, cv::NORM_L1) / double(direct.total()) < 0.5);
  CHECK(cv::norm(f.left.gray, f.right.gray, cv::NORM_L1) / double(direct.total()) >
        5);  // 6 cm of parallax

  // A stage the left carriage cannot reach is refused before anything moves.
  rig::StageState bad = target;
  bad.right.carriage_m = 0.05;
  const rig::StageState still = rig.State();
  CHECK_THROWS_AS(pair.MoveTo(bad), rig::RigError);
  CHECK(rig.State().left.carriage_m == Approx(still.left.carriage_m).margin(1e-6));
  CHECK_THROWS_AS(pair.Capture({true}), rig::RigError);
}
