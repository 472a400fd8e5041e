#include <catch2/catch.hpp>
#include <cmath>

#include "scenes/catalog.h"
#include "temp_scene.h"

namespace {
// A fronto-parallel plane whose face is 1.0 m from the rail.
const TempScene& PlaneScene() {
  static const TempScene scene(TempScene::PlaneAt(1.0), TempScene::PhotoAsset());
  return scene;
}
}  // namespace

TEST_CASE("rendered depth agrees with exact ray casting on a fronto-parallel plane", "[sim]") {
  auto sim = scenes::LoadScene(PlaneScene().path(), sim::SimRigConfig{});
  const rig::StereoFrame frame = sim->rig().Capture();
  const rig::CameraView& view = frame.left;
  const cv::Mat rendered = sim->truth().Render(view.world_T_camera, view.intrinsics).depth_m;
  cv::Mat ids;
  const cv::Mat cast = sim->truth().RayCastDepth(view.world_T_camera, view.intrinsics, &ids);
  // The plane's front face is at y = 1.0; the level camera's centre at y = 0.03.
  const double expected = 1.0 - view.world_T_camera.translation().y();
  REQUIRE(expected == Approx(0.97));
  double worst_render = 0, worst_cast = 0;
  for (int v = 0; v < rendered.rows; ++v)
    for (int u = 0; u < rendered.cols; ++u) {
      worst_render =
          std::max<double>(worst_render, std::abs(rendered.at<float>(v, u) - cast.at<float>(v, u)));
      worst_cast = std::max<double>(worst_cast, std::abs(cast.at<float>(v, u) - expected));
      REQUIRE(sim->truth().GeomName(ids.at<int>(v, u)) == "plane");
    }
  CHECK(worst_render < 1e-3);  // required: 1 mm at 1 m
  CHECK(worst_cast < 1e-5);    // float storage
}

TEST_CASE("ray casts hit scene geoms only and report distance and point", "[sim]") {
  auto sim = scenes::LoadScene(PlaneScene().path(), sim::SimRigConfig{});
  const Eigen::Vector3d origin(0.1, 0.0, 0.05);
  const auto hit = sim->truth().CastRay(origin, Eigen::Vector3d(0, 2, 0));
  REQUIRE(hit);
  CHECK(hit->distance_m == Approx(1.0).margin(1e-9));
  CHECK((hit->point_W - Eigen::Vector3d(0.1, 1.0, 0.05)).norm() < 1e-9);
  CHECK_FALSE(sim->truth().CastRay(origin, Eigen::Vector3d(0, -1, 0)));
  // A slanted ray: range grows as 1 / cos.
  const auto slanted = sim->truth().CastRay(origin, Eigen::Vector3d(std::tan(0.2), 1, 0));
  REQUIRE(slanted);
  CHECK(slanted->distance_m == Approx(1.0 / std::cos(0.2)).margin(1e-9));
}

TEST_CASE("ray-cast depth works for any intrinsics, rendering refuses what it cannot draw",
          "[sim]") {
  auto sim = scenes::LoadScene(PlaneScene().path(), sim::SimRigConfig{});
  const rig::CameraView view = sim->rig().Capture().left;
  rig::CameraIntrinsics k = view.intrinsics;
  k.width_px = 64;
  k.height_px = 48;
  k.cx_px = 20;
  k.distortion = {-0.1, 0.01, 0, 0};
  const cv::Mat cast = sim->truth().RayCastDepth(view.world_T_camera, k);
  CHECK(cast.at<float>(10, 10) == Approx(0.97).margin(1e-5));
  CHECK_THROWS_AS(sim->truth().Render(view.world_T_camera, k), rig::RigError);
}

TEST_CASE("rendered labels agree with exact ray casting on every pixel of every catalog scene",
          "[sim][slow][outcome]") {
  int total_cast = 0, total_pixels = 0;
  for (const std::string& name : scenes::CatalogNames()) {
    INFO("scene " << name);
    auto sim = scenes::LoadScene(name, sim::SimRigConfig{});
    const rig::CameraView view = sim->rig().Capture().left;
    const sim::GroundTruth::Labels labels =
        sim->truth().RenderLabels(view.world_T_camera, view.intrinsics);
    cv::Mat ids;
    const cv::Mat cast = sim->truth().RayCastDepth(view.world_T_camera, view.intrinsics, &ids);
    double worst = 0;
    int wrong_geom = 0, ties = 0;
    for (int v = 0; v < cast.rows; ++v)
      for (int u = 0; u < cast.cols; ++u) {
        const float z = cast.at<float>(v, u);
        worst = std::max<double>(worst, std::abs(labels.depth_m.at<float>(v, u) - z));
        const int g = labels.geom_ids.at<int>(v, u);
        if (g == ids.at<int>(v, u)) continue;
        // Coplanar faces (the staircase's risers and treads overlap): the
        // geom shown must lie on the exact ray at the exact depth.
        const Eigen::Vector3d ray = view.intrinsics.Ray({u, v});
        const auto d = sim->truth().CastRayAt(g, view.world_T_camera.translation(),
                                              view.world_T_camera.linear() * ray);
        if (d && z > 0 && std::abs(*d / ray.norm() - z) <= 1e-4)
          ++ties;
        else
          ++wrong_geom;
      }
    INFO("ties between coplanar faces " << ties);
    CHECK(worst <= 1e-3);  // 1 mm, every pixel
    CHECK(wrong_geom == 0);
    total_cast += labels.ray_cast;
    total_pixels += cast.rows * cast.cols;
  }
  // Exact rays only where the raster may differ: a small share of the views.
  CHECK(total_cast < 0.1 * total_pixels);
}
