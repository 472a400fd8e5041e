#include "rig/kinematics.h"

#include <catch2/catch.hpp>
#include <cmath>

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
