#include "fovea/geometry.h"

#include <catch2/catch.hpp>
#include <cmath>

#include "rig/kinematics.h"

TEST_CASE("a world point projects where its pixel ray passes", "[fovea][geometry]") {
  const auto k = rig::CameraIntrinsics::FromHorizontalFov(640, 480, 0.5);
  rig::RigGeometry g;
  const Eigen::Isometry3d pose = g.WorldFromCamera(rig::Side::kLeft, {-0.1, 0.05, -0.03});
  const Eigen::Vector3d p_W(0.2, 1.1, -0.05);
  const auto uv = fovea::ProjectWorldPoint(pose, k, p_W);
  REQUIRE(uv);
  const fovea::Ray ray = fovea::PixelRay(pose, k, *uv);
  const Eigen::Vector3d to_p = p_W - ray.origin_W;
  CHECK((to_p.normalized() - ray.direction_W).norm() < 1e-9);
  CHECK_FALSE(fovea::ProjectWorldPoint(pose, k, Eigen::Vector3d(0, -1, 0)));
}

TEST_CASE("a world point projects to the pixel computed by hand", "[fovea][geometry]") {
  // A camera at (0.1, 0, 0.2) looking along world +Y, level: its x is world
  // +X, its y (down) world -Z. The point (0.3, 2.0, 0.1) lies at (0.2, 0.1,
  // 2.0) in the camera: u = cx + fx 0.2 / 2, v = cy + fy 0.1 / 2.
  const auto k = rig::CameraIntrinsics::FromHorizontalFov(640, 480, 0.5);
  Eigen::Isometry3d world_T_camera = Eigen::Isometry3d::Identity();
  world_T_camera.linear().col(0) = Eigen::Vector3d::UnitX();
  world_T_camera.linear().col(1) = -Eigen::Vector3d::UnitZ();
  world_T_camera.linear().col(2) = Eigen::Vector3d::UnitY();
  world_T_camera.translation() = Eigen::Vector3d(0.1, 0, 0.2);
  const double f = 320 / std::tan(0.25);  // 640 px across 0.5 rad
  const auto uv = fovea::ProjectWorldPoint(world_T_camera, k, {0.3, 2.0, 0.1});
  REQUIRE(uv);
  CHECK(uv->x() == Approx(319.5 + f * 0.1).margin(1e-9));
  CHECK(uv->y() == Approx(239.5 + f * 0.05).margin(1e-9));
  // And the ray through that pixel starts at the camera and passes the point.
  const fovea::Ray ray = fovea::PixelRay(world_T_camera, k, *uv);
  CHECK((ray.origin_W - Eigen::Vector3d(0.1, 0, 0.2)).norm() < 1e-12);
  CHECK((ray.direction_W - Eigen::Vector3d(0.2, 2.0, -0.1).normalized()).norm() < 1e-9);
}

TEST_CASE("midpoint triangulation recovers a point seen by two cameras", "[fovea][geometry]") {
  const auto k = rig::CameraIntrinsics::FromHorizontalFov(640, 480, 0.5);
  rig::RigGeometry g;
  const Eigen::Isometry3d left = g.WorldFromCamera(rig::Side::kLeft, {-0.05, -0.02, 0});
  const Eigen::Isometry3d right = g.WorldFromCamera(rig::Side::kRight, {0.05, 0.03, 0.01});
  const Eigen::Vector3d p_W(0.03, 0.9, 0.02);
  const auto a = fovea::PixelRay(left, k, *fovea::ProjectWorldPoint(left, k, p_W));
  const auto b = fovea::PixelRay(right, k, *fovea::ProjectWorldPoint(right, k, p_W));
  const auto t = fovea::TriangulateMidpoint(a, b);
  REQUIRE(t);
  CHECK((t->p_W - p_W).norm() < 1e-9);
  CHECK(t->miss_distance_m < 1e-9);
  // Parallel rays do not meet.
  CHECK_FALSE(fovea::TriangulateMidpoint(
      a, fovea::Ray{a.origin_W + Eigen::Vector3d(0.1, 0, 0), a.direction_W}));
}
