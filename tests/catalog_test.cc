// The scene catalog: every scene loads, renders and has ground truth, and its
// geometry is what the paper describes, measured by ray casting (not by
// reading back the XML). Also the scene rules and the random generator.
#include "scenes/catalog.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <map>
#include <opencv2/imgproc.hpp>
#include <set>

#include "scenes/generated.h"
#include "temp_scene.h"

namespace {

using Eigen::Vector3d;

struct Probe {
  std::unique_ptr<sim::Simulation> sim;
  rig::StereoFrame frame;
  explicit Probe(const std::string& name) : sim(scenes::LoadScene(name, sim::SimRigConfig{})) {
    frame = sim->rig().Capture();
  }
  // Hit of the left camera's ray through pixel (u, v).
  sim::RayHit Hit(double u, double v) const {
    const auto& view = frame.left;
    const Vector3d dir = view.world_T_camera.linear() * view.intrinsics.Ray({u, v});
    const auto hit = sim->truth().CastRay(view.world_T_camera.translation(), dir);
    REQUIRE(hit);
    return *hit;
  }
  std::string Name(const sim::RayHit& h) const { return sim->truth().GeomName(h.geom_id); }
};

// Unit normal of the plane through three points.
Vector3d Normal(const Vector3d& a, const Vector3d& b, const Vector3d& c) {
  return (b - a).cross(c - a).normalized();
}

}  // namespace

TEST_CASE("every catalog scene loads, renders and has ground truth", "[scenes]") {
  for (const std::string& name : scenes::CatalogNames()) {
    INFO(name);
    Probe p(name);
    cv::Scalar mean, stddev;
    cv::meanStdDev(p.frame.left.gray, mean, stddev);
    CHECK(stddev[0] > 10);  // an image with content, not a blank
    cv::Mat ids;
    const cv::Mat depth =
        p.sim->truth().RayCastDepth(p.frame.left.world_T_camera, p.frame.left.intrinsics, &ids);
    CHECK(cv::countNonZero(depth > 0) == int(depth.total()));  // every pixel shows a surface
    double lo = 0, hi = 0;
    cv::minMaxLoc(depth, &lo, &hi);
    CHECK(lo >= 0.4);  // the paper's working range
    CHECK(hi <= 1.55);
  }
}

TEST_CASE("fronto_planes: wood and tile planes 17 cm apart", "[scenes]") {
  Probe p("fronto_planes");
  const auto wood = p.Hit(100, 240), tile = p.Hit(560, 240);
  CHECK(p.Name(wood) == "wood_plane");
  CHECK(p.Name(tile) == "tile_plane");
  CHECK(tile.point_W.y() - wood.point_W.y() == Approx(0.17).margin(1e-9));
  // Both fronto-parallel: normals along -Y.
  CHECK(std::abs(
            Normal(p.Hit(50, 100).point_W, p.Hit(150, 100).point_W, p.Hit(100, 400).point_W).y()) ==
        Approx(1).margin(1e-9));
}

TEST_CASE("cylinder_planes: an 8 cm cylinder cutting two tile planes", "[scenes]") {
  Probe p("cylinder_planes");
  // Points on the cylinder along one image row; fit a circle in the XY plane.
  std::vector<Vector3d> pts;
  for (int u = 0; u < 640; ++u) {
    const auto h = p.Hit(u, 239.5);
    if (p.Name(h) == "cylinder") pts.push_back(h.point_W);
  }
  REQUIRE(pts.size() > 50);
  // Algebraic circle fit: x^2 + y^2 + D x + E y + F = 0.
  Eigen::MatrixXd a(pts.size(), 3);
  Eigen::VectorXd b(pts.size());
  for (size_t i = 0; i < pts.size(); ++i) {
    a.row(i) << pts[i].x(), pts[i].y(), 1;
    b(i) = -(pts[i].x() * pts[i].x() + pts[i].y() * pts[i].y());
  }
  const Eigen::Vector3d s = a.colPivHouseholderQr().solve(b);
  const double cx = -s(0) / 2, cy = -s(1) / 2, r = std::sqrt(cx * cx + cy * cy - s(2));
  CHECK(r == Approx(0.08).margin(1e-4));  // 720 facets: chord error < 1e-6 m
  CHECK(cx == Approx(0.0).margin(1e-4));
  CHECK(cy == Approx(0.97).margin(1e-4));
  // The planes cut the cylinder: each lies within a radius of its axis.
  const auto left = p.Hit(30, 240), right = p.Hit(620, 240);
  CHECK(p.Name(left) == "left_plane");
  CHECK(p.Name(right) == "right_plane");
  CHECK(std::abs(left.point_W.y() - cy) < r);
  CHECK(std::abs(right.point_W.y() - cy) < r);
}

TEST_CASE("two_planes: the near plane covers part of the far one", "[scenes]") {
  Probe p("two_planes");
  const auto near = p.Hit(100, 240), far = p.Hit(600, 240);
  CHECK(p.Name(near) == "near_plane");
  CHECK(p.Name(far) == "far_plane");
  CHECK(far.point_W.y() - near.point_W.y() == Approx(0.70).margin(1e-9));
}

TEST_CASE("three_surfaces: blocks 3 cm apart in depth, a 40 degree slant, a plane behind",
          "[scenes]") {
  Probe p("three_surfaces");
  // Block front faces along the lower part of the view: fronto-parallel, so
  // many hits share one y (the blocks' sides give scattered values).
  std::map<long, int> counts;  // y in 0.1 mm bins
  for (int u = 0; u < 640; ++u) {
    const auto h = p.Hit(u, 380);
    if (p.Name(h).rfind("block_", 0) == 0) ++counts[std::lround(h.point_W.y() * 1e4)];
  }
  std::vector<double> faces;
  for (const auto& [bin, n] : counts)
    if (n >= 10) faces.push_back(bin * 1e-4);
  REQUIRE(faces.size() == 3);
  CHECK(faces[1] - faces[0] == Approx(0.03).margin(1e-4));  // bin width
  CHECK(faces[2] - faces[1] == Approx(0.03).margin(1e-4));
  // The slanted plane's normal is 40 degrees from the Y axis, in the
  // horizontal plane.
  const auto a = p.Hit(450, 100), b = p.Hit(560, 100), c = p.Hit(500, 220);
  REQUIRE(p.Name(a) == "slanted_plane");
  REQUIRE(p.Name(b) == "slanted_plane");
  REQUIRE(p.Name(c) == "slanted_plane");
  const Vector3d n = Normal(a.point_W, b.point_W, c.point_W);
  CHECK(std::acos(std::abs(n.y())) * 180 / M_PI == Approx(40).margin(1e-6));
  CHECK(std::abs(n.z()) < 1e-9);
  CHECK(p.Name(p.Hit(20, 100)) == "back_plane");
}

TEST_CASE("periodic: the image repeats with the texture's period", "[scenes]") {
  Probe p("periodic");
  const double depth = p.Hit(319.5, 239.5).distance_m;
  const double expected_px =
      p.frame.left.intrinsics.fx_px * 0.5 / 32 / depth;  // 0.5 m per 32 texels
  // Autocorrelation of the middle row: the first peak after zero lag.
  cv::Mat row;
  p.frame.left.gray.row(240).convertTo(row, CV_64F);
  row -= cv::mean(row)[0];
  int best = 0;
  double best_c = -1e300;
  for (int lag = 10; lag < 40; ++lag) {
    const double c = row.colRange(0, 640 - lag).dot(row.colRange(lag, 640));
    if (c > best_c) best_c = c, best = lag;
  }
  CHECK(std::abs(best - expected_px) <= 1.0);
}

TEST_CASE("textureless: uniform surfaces are marked untextured in the ground truth", "[scenes]") {
  Probe p("textureless");
  cv::Mat ids;
  p.sim->truth().RayCastDepth(p.frame.left.world_T_camera, p.frame.left.intrinsics, &ids);
  const cv::Mat textured = p.sim->truth().TexturedMask(ids);
  for (int v = 0; v < ids.rows; v += 7)
    for (int u = 0; u < ids.cols; u += 7) {
      const std::string name = p.sim->truth().GeomName(ids.at<int>(v, u));
      CHECK((textured.at<uchar>(v, u) != 0) == (name == "photo_wall"));
    }
  const double share = cv::countNonZero(textured) / double(textured.total());
  CHECK(share > 0.2);
  CHECK(share < 0.8);
}

TEST_CASE("random scenes: deterministic from the seed, and in view", "[scenes]") {
  const auto spec = scenes::ParseRandomSceneName("random:7:10");
  REQUIRE(spec);
  CHECK(spec->seed == 7);
  CHECK(spec->objects == 10);
  CHECK(scenes::RandomSceneXml(*spec) == scenes::RandomSceneXml(*spec));
  CHECK(scenes::RandomSceneXml(*spec) != scenes::RandomSceneXml({8, 10}));
  CHECK_THROWS_AS(scenes::ParseRandomSceneName("random:x"), sim::SceneError);
  CHECK_THROWS_AS(scenes::ParseRandomSceneName("random:1:99"), sim::SceneError);
  for (uint64_t seed : {1, 2, 3}) {
    Probe p("random:" + std::to_string(seed) + ":8");
    cv::Mat ids;
    p.sim->truth().RayCastDepth(p.frame.left.world_T_camera, p.frame.left.intrinsics, &ids);
    std::set<int> seen(ids.begin<int>(), ids.end<int>());
    CHECK(seen.size() >= 2);  // objects besides the back wall
  }
}

TEST_CASE("scene rules: nothing may drive the rig or reach into its workspace", "[scenes]") {
  auto expect_error = [](const TempScene& scene, const std::string& words) {
    try {
      scenes::LoadScene(scene.path(), sim::SimRigConfig{});
      FAIL("scene loaded: " << words);
    } catch (const sim::SceneError& e) {
      const std::string msg = e.what();
      INFO(msg);
      CHECK(msg.find(words) != std::string::npos);
      CHECK(msg.find('\n') == std::string::npos);
    }
  };
  const std::string wall = TempScene::PlaneAt(1.0);
  expect_error(TempScene(wall + "<geom type=\"sphere\" size=\"0.02\" pos=\"0.1 0.05 0\"/>",
                         TempScene::PhotoAsset()),
               "workspace");
  expect_error(TempScene(wall + "<geom type=\"plane\" size=\"2 2 0.1\" pos=\"0 0 -0.05\"/>",
                         TempScene::PhotoAsset()),
               "workspace");
  expect_error(TempScene(wall, TempScene::PhotoAsset(),
                         "<actuator><motor joint=\"tavt_left_pan\"/></actuator>"),
               "may not move the rig");
  expect_error(
      TempScene(wall, TempScene::PhotoAsset(),
                "<equality><joint joint1=\"tavt_left_pan\" joint2=\"tavt_right_pan\"/></equality>"),
      "may not move the rig");
  // A floor well below the rig and a wall in front are fine.
  TempScene fine(wall + "<geom type=\"plane\" size=\"2 2 0.1\" pos=\"0 0 -0.5\"/>",
                 TempScene::PhotoAsset());
  CHECK_NOTHROW(scenes::LoadScene(fine.path(), sim::SimRigConfig{}));
}
