#include "rig/kinematics.h"

#include <catch2/catch.hpp>
#include <cmath>

#include "rig/undistort.h"

namespace {
rig::RigGeometry Geometry() {
  rig::RigGeometry g;
  g.left.optical_centre_H = g.right.optical_centre_H = {0.0, 0.03, 0.01};
  return g;
}
}  // namespace

TEST_CASE("forward kinematics matches the hand-derived camera pose", "[rig]") {
  const rig::RigGeometry g = Geometry();
  const double p = 0.3, t = -0.2, s = 0.07;
  const Eigen::Isometry3d pose = g.WorldFromCamera(rig::Side::kRight, {s, p, t});
  // Centre: rail position plus Rz(p) Rx(t) (0, 0.03, 0.01).
  const double oy = 0.03 * std::cos(t) - 0.01 * std::sin(t);
  const double oz = 0.03 * std::sin(t) + 0.01 * std::cos(t);
  const Eigen::Vector3d centre(s - std::sin(p) * oy, std::cos(p) * oy, oz);
  CHECK((pose.translation() - centre).norm() < 1e-12);
  // Optical axis (camera z): Rz(p) Rx(t) (0, 1, 0).
  const Eigen::Vector3d axis(-std::sin(p) * std::cos(t), std::cos(p) * std::cos(t), std::sin(t));
  CHECK((pose.linear().col(2) - axis).norm() < 1e-12);
  // Camera x stays horizontal (no roll): Rz(p) (1, 0, 0).
  CHECK((pose.linear().col(0) - Eigen::Vector3d(std::cos(p), std::sin(p), 0)).norm() < 1e-12);
  // Camera y points down when level.
  const Eigen::Isometry3d level = g.WorldFromCamera(rig::Side::kLeft, {-0.05, 0, 0});
  CHECK((level.linear().col(1) - Eigen::Vector3d(0, 0, -1)).norm() < 1e-12);
  CHECK((level.translation() - Eigen::Vector3d(-0.05, 0.03, 0.01)).norm() < 1e-12);
}

TEST_CASE("positive pan turns the camera to its left, positive tilt looks up", "[rig]") {
  const rig::RigGeometry g = Geometry();
  const Eigen::Vector3d panned = g.WorldFromCamera(rig::Side::kLeft, {0, 0.1, 0}).linear().col(2);
  CHECK(panned.x() < 0);
  const Eigen::Vector3d tilted = g.WorldFromCamera(rig::Side::kLeft, {0, 0, 0.1}).linear().col(2);
  CHECK(tilted.z() > 0);
}

TEST_CASE("encoder zeros and the mount turn the camera; the tilt zero folds into the mount",
          "[rig]") {
  rig::RigGeometry g = Geometry();
  rig::HeadGeometry& head = g.left;
  head.optical_centre_H = {0.02, 0.08, 0.02};
  head.mount_rpy_rad = {0.026, -0.02, 0.03};
  head.pan_zero_rad = 0.0017;
  head.tilt_zero_rad = -0.0017;
  const rig::CameraStage stage{-0.1, 0.3, -0.2};
  // A pan zero is a pan: the reading plus the zero.
  rig::RigGeometry no_zero = g;
  no_zero.left.pan_zero_rad = 0;
  const Eigen::Isometry3d a = g.WorldFromCamera(rig::Side::kLeft, stage);
  const Eigen::Isometry3d b = no_zero.WorldFromCamera(
      rig::Side::kLeft, {stage.carriage_m, stage.pan_rad + 0.0017, stage.tilt_rad});
  CHECK((a.matrix() - b.matrix()).norm() < 1e-12);
  // The mount's roll turns the image about the optical axis.
  rig::RigGeometry ideal = Geometry();
  rig::RigGeometry rolled = ideal;
  rolled.left.mount_rpy_rad = {0.1, 0, 0};
  const Eigen::Matrix3d r0 = ideal.WorldFromCamera(rig::Side::kLeft, {0, 0, 0}).linear();
  const Eigen::Matrix3d r1 = rolled.WorldFromCamera(rig::Side::kLeft, {0, 0, 0}).linear();
  CHECK((r0.col(2) - r1.col(2)).norm() < 1e-12);
  CHECK(std::acos(r0.col(0).dot(r1.col(0))) == Approx(0.1).margin(1e-12));
  // Folding the tilt zero into the mount changes no camera pose, anywhere.
  rig::RigGeometry folded = g;
  folded.left = head.FoldTiltZero();
  CHECK(folded.left.tilt_zero_rad == 0);
  for (const double tilt : {-0.4, 0.0, 0.35}) {
    const rig::CameraStage s{-0.2, -0.5, tilt};
    CHECK((g.WorldFromCamera(rig::Side::kLeft, s).matrix() -
           folded.WorldFromCamera(rig::Side::kLeft, s).matrix())
              .norm() < 1e-12);
  }
  // Mount angles survive the round trip through the rotation.
  CHECK((rig::MountRpyFromRotation(head.MountRotation()) - head.mount_rpy_rad).norm() < 1e-12);
}

TEST_CASE("a delivered pair: one K, no distortion, cameras turned to their heads", "[rig]") {
  rig::RigCalibration c;
  c.left = rig::CameraIntrinsics::FromHorizontalFov(640, 480, 0.5);
  c.right = c.left;
  c.right.fx_px *= 1.001;
  c.right.cx_px += 0.8;
  c.left.distortion = {-0.2, 0.05, 0.0002, -0.0001, 0};
  c.right.distortion = {-0.18, 0.03, 0, 0, 0};
  c.left_head.optical_centre_H = c.right_head.optical_centre_H = {0.02, 0.08, 0.02};
  c.left_head.mount_rpy_rad = {0.026, 0.026, 0.026};
  c.right_head.mount_rpy_rad = {-0.026, 0.026, -0.026};
  c.left_head.pan_zero_rad = 0.0017;
  c.right_head.tilt_zero_rad = 0.0017;
  const rig::DeliveredPair d(c);
  CHECK(d.intrinsics.distortion.empty());
  CHECK(d.intrinsics.fx_px == c.left.fx_px);
  CHECK(d.intrinsics.cx_px == c.left.cx_px);
  const rig::RigGeometry raw = c.Geometry();
  for (const rig::Side side : {rig::Side::kLeft, rig::Side::kRight}) {
    const int s = static_cast<int>(side);
    CHECK(d.geometry[side].mount_rpy_rad.isZero(0));
    CHECK(d.geometry[side].optical_centre_H == raw[side].optical_centre_H);
    CHECK(d.geometry[side].pan_zero_rad == raw[side].pan_zero_rad);
    CHECK(d.geometry[side].tilt_zero_rad == raw[side].tilt_zero_rad);
    REQUIRE(d.undistort[s].Active());
    // A delivered pixel samples the raw pixel that shows the same ray: the
    // ray of the delivered camera, imaged by the raw one (its mount and lens).
    const rig::CameraStage stage{0.1, -0.2, 0.15};
    const Eigen::Isometry3d delivered = d.geometry.WorldFromCamera(side, stage);
    const Eigen::Isometry3d camera = raw.WorldFromCamera(side, stage);
    CHECK((delivered.translation() - camera.translation()).norm() < 1e-12);
    CHECK(Eigen::AngleAxisd(d.delivered_R_raw[s] * camera.linear().transpose() * delivered.linear())
              .angle() < 1e-12);
    double worst = 0;
    for (const int u : {40, 320, 600})
      for (const int v : {30, 240, 450}) {
        const Eigen::Vector3d p_W = delivered * (0.9 * d.intrinsics.Ray(Eigen::Vector2d(u, v)));
        const Eigen::Vector2d uv_raw = c.Intrinsics(side).Project(camera.inverse() * p_W);
        const Eigen::Vector2d sampled(d.undistort[s].MapX().at<float>(v, u),
                                      d.undistort[s].MapY().at<float>(v, u));
        worst = std::max(worst, (uv_raw - sampled).norm());
      }
    INFO("side " << s << ": worst " << worst << " px");
    CHECK(worst < 0.01);
  }
  // An ideal pair is delivered as it is captured.
  rig::RigCalibration ideal;
  ideal.left = ideal.right = rig::CameraIntrinsics::FromHorizontalFov(640, 480, 0.5);
  const rig::DeliveredPair same(ideal);
  CHECK_FALSE(same.undistort[0].Active());
  CHECK_FALSE(same.undistort[1].Active());
}

TEST_CASE("FacingStage allows for the encoders' zeros", "[rig]") {
  rig::RigGeometry g;
  g.right.pan_zero_rad = 0.01;
  g.right.tilt_zero_rad = -0.02;
  const Eigen::Vector3d p_W(0.3, 1.2, 0.2);
  const rig::CameraStage s = g.FacingStage(rig::Side::kRight, 0.05, p_W);
  const Eigen::Isometry3d pose = g.WorldFromCamera(rig::Side::kRight, s);
  const Eigen::Vector3d to_p = (p_W - pose.translation()).normalized();
  CHECK((pose.linear().col(2) - to_p).norm() < 1e-12);
}

TEST_CASE("ParallelStage points any head's camera straight ahead", "[rig]") {
  rig::RigGeometry g;
  CHECK(g.ParallelStage(rig::Side::kLeft, -0.1).pan_rad == 0);
  CHECK(g.ParallelStage(rig::Side::kLeft, -0.1).tilt_rad == 0);
  g.right.optical_centre_H = {0.02, 0.08, 0.02};
  g.right.mount_rpy_rad = {0.026, 0.028, -0.026};
  g.right.pan_zero_rad = -0.0017;
  g.right.tilt_zero_rad = 0.0017;
  const rig::CameraStage s = g.ParallelStage(rig::Side::kRight, 0.12);
  const Eigen::Vector3d axis = g.WorldFromCamera(rig::Side::kRight, s).linear().col(2);
  CHECK((axis - Eigen::Vector3d::UnitY()).norm() < 1e-12);
}
