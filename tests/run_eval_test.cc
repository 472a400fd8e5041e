// Ground-truth scoring's reference view.
#include "experiments/scoring/run_eval.h"

#include <catch2/catch.hpp>

#include "fovea/patch.h"
#include "scenes/catalog.h"
#include "test_views.h"

TEST_CASE("reference view: the strip past a near left edge is out of every right camera's sight",
          "[experiments][scoring][slow]") {
  auto sim = scenes::LoadScene("three_surfaces", {});
  const experiments::ReferenceView ref = experiments::MakeReferenceView(sim->rig(), *sim);
  REQUIRE(ref.textured_pixels > 0);
  CHECK(cv::countNonZero(ref.stereo_visible & ~ref.textured) == 0);
  const double share = double(ref.stereo_visible_pixels) / ref.textured_pixels;
  INFO("stereo-visible share " << share);
  CHECK(share > 0.85);  // measured 0.936
  CHECK(share < 0.97);

  // Along a row through the left block: the plywood right before the block's
  // first pixel lies in the strip (the home pose's left camera is 5 cm left
  // of the nearest right camera: tens of pixels at 0.5 m against 1.2 m), the
  // plywood at the image's left edge and the block itself do not.
  int block = -1;
  for (int id = 0; id < 64 && block < 0; ++id)
    if (sim->truth().GeomName(id) == "block_1") block = id;
  REQUIRE(block >= 0);
  const int y = ref.geom_ids.rows * 3 / 4;
  int edge = -1;
  for (int x = 0; x < ref.geom_ids.cols && edge < 0; ++x)
    if (ref.geom_ids.at<int>(y, x) == block) edge = x;
  REQUIRE(edge > 30);
  CHECK(ref.stereo_visible.at<uchar>(y, edge - 3) == 0);
  CHECK(ref.stereo_visible.at<uchar>(y, edge - 15) == 0);
  CHECK(ref.stereo_visible.at<uchar>(y, 5) == 255);
  CHECK(ref.stereo_visible.at<uchar>(y, edge + 5) == 255);
}

TEST_CASE("reference view: with no near edge to hide behind, every textured pixel is in sight",
          "[experiments][scoring][slow]") {
  auto sim = scenes::LoadScene("fronto_planes", {});
  const experiments::ReferenceView ref = experiments::MakeReferenceView(sim->rig(), *sim);
  REQUIRE(ref.textured_pixels > 0);
  CHECK(ref.stereo_visible_pixels >= 0.99 * ref.textured_pixels);
}

TEST_CASE("map score: the pixels near edges are split by the source of the patch seen",
          "[experiments][scoring][slow]") {
  auto sim = scenes::LoadScene("three_surfaces", {});
  const experiments::ReferenceView ref = experiments::MakeReferenceView(sim->rig(), *sim);
  const rig::CameraIntrinsics& k = ref.view.intrinsics;
  // A fronto-parallel quad over image columns [u0, u1), all rows, at depth z.
  auto quad = [&](double u0, double u1, double z, fovea::PatchLevel level, int resolution) {
    fovea::Patch p;
    p.level = level;
    p.resolution_level = resolution;
    const double us[4] = {u0, u1, u1, u0},
                 vs[4] = {-0.5, -0.5, k.height_px - 0.5, k.height_px - 0.5};
    for (int c = 0; c < 4; ++c)
      p.corners_W[c] =
          ref.view.world_T_camera *
          Eigen::Vector3d((us[c] - k.cx_px) / k.fx_px * z, (vs[c] - k.cy_px) / k.fy_px * z, z);
    return p;
  };
  // IDR over the whole view at the back plane's depth, a peripheral patch
  // (resolution 1) in front of it over the left third, a foveal one nearer
  // still over the middle third: each is the nearest where it lies.
  const double w = k.width_px;
  fovea::PatchMap map;
  map.Add(quad(-0.5, w - 0.5, 1.2, fovea::PatchLevel::kIdr, 0));
  map.Add(quad(-0.5, w / 3, 0.9, fovea::PatchLevel::kPeripheral, 1));
  map.Add(quad(w / 3, 2 * w / 3, 0.55, fovea::PatchLevel::kFoveal, 0));
  const experiments::MapScore score = experiments::ScoreMap(map, 0, ref, sim->truth(), 0.06, false);
  const nlohmann::json j = experiments::ScoreJson(score);
  const long edge_pixels = j["edge_pixels"];
  REQUIRE(edge_pixels > 0);
  long pixels = 0;
  double bad = 0, bad_nearer = 0;
  for (const char* source : {"idr", "0", "1"}) {
    INFO("source " << source);
    REQUIRE(j["edge_by_source"].contains(source));
    const nlohmann::json& e = j["edge_by_source"][source];
    const long n = e["pixels"];
    CHECK(n > 0);  // the blocks' edges lie in all three thirds
    pixels += n;
    bad += n * e["bad_share"].get<double>();
    if (!e["bad_nearer_share"].is_null())
      bad_nearer += n * e["bad_share"].get<double>() * e["bad_nearer_share"].get<double>();
  }
  CHECK(pixels == edge_pixels);
  CHECK(bad == Approx(edge_pixels * j["edge_bad_share"].get<double>()).epsilon(1e-9));
  // The IDR quad lies at the back plane's depth: where it is wrong (over
  // the slanted plane and the blocks, all nearer), it is too far.
  REQUIRE(j["edge_by_source"]["idr"]["bad_share"].get<double>() > 0);
  CHECK(j["edge_by_source"]["idr"]["bad_nearer_share"].get<double>() == 0);
  CHECK(j["by_level"]["idr"]["bad_nearer_share"].get<double>() == 0);
  // The split adds up over the sources.
  CHECK(bad_nearer == Approx(edge_pixels * j["edge_bad_share"].get<double>() *
                             j["edge_bad_nearer_share"].get<double>())
                          .epsilon(1e-9));
  CHECK(j["edge_bad_nearer_share"].get<double>() > 0);  // the quads before the back plane

  // Coverage beside the edges: of the textured pixels near an edge, those
  // mapped (the IDR quad spans the view: all of them), and those mapped
  // right.
  const long edge_visible = cv::countNonZero(ref.near_edge & ref.textured);
  REQUIRE(edge_visible > 0);
  CHECK(j["edge_visible_pixels"].get<long>() == edge_visible);
  CHECK(j["edge_coverage"].get<double>() == Approx(double(edge_pixels) / edge_visible));
  CHECK(j["edge_coverage"].get<double>() > 0.99);
  CHECK(j["edge_good_coverage"].get<double>() ==
        Approx(edge_pixels * (1 - j["edge_bad_share"].get<double>()) / edge_visible));
  CHECK(j["edge_good_coverage"].get<double>() < j["edge_coverage"].get<double>());
  // An empty map covers none of them; a view with no edge has no such share.
  const nlohmann::json empty = experiments::ScoreJson(
      experiments::ScoreMap(fovea::PatchMap(), 0, ref, sim->truth(), 0.06, false));
  CHECK(empty["edge_visible_pixels"].get<long>() == edge_visible);
  CHECK(empty["edge_coverage"].get<double>() == 0);
  CHECK(empty["edge_good_coverage"].get<double>() == 0);
  CHECK(empty["edge_bad_share"].is_null());
  const nlohmann::json flat = experiments::ScoreJson(experiments::MapScore());
  CHECK(flat["edge_coverage"].is_null());
  CHECK(flat["edge_good_coverage"].is_null());
}

TEST_CASE("error picture: right pixels green, too near red, too far magenta, true edges blue",
          "[experiments][scoring]") {
  // A synthetic reference view: a wall at 1 m over the left half, a block at
  // 0.5 m over the right half, every pixel textured.
  experiments::ReferenceView ref;
  const rig::CameraIntrinsics k = rig::CameraIntrinsics::FromHorizontalFov(64, 48, 1.0);
  ref.view.intrinsics = k;
  ref.view.gray = cv::Mat(48, 64, CV_8U, cv::Scalar(100));
  ref.depth_m = cv::Mat(48, 64, CV_32F, cv::Scalar(1.0f));
  ref.depth_m.colRange(32, 64).setTo(0.5f);
  ref.depth_edges = experiments::DepthEdges(ref.depth_m);
  ref.textured = cv::Mat(48, 64, CV_8U, cv::Scalar(255));
  ref.textured.rowRange(40, 48).setTo(0);  // not scored: left grey
  // Fronto-parallel quads over columns [u0, u1) and rows [v0, v1) at depth z.
  auto quad = [&](double u0, double u1, double v0, double v1, double z) {
    fovea::Patch p;
    const double us[4] = {u0, u1, u1, u0}, vs[4] = {v0, v0, v1, v1};
    for (int c = 0; c < 4; ++c)
      p.corners_W[c] =
          Eigen::Vector3d((us[c] - k.cx_px) / k.fx_px * z, (vs[c] - k.cy_px) / k.fy_px * z, z);
    return p;
  };
  fovea::PatchMap map;
  map.Add(quad(-0.5, 31.5, -0.5, 47.5, 1.003));  // the wall, 0.3% off: right
  map.Add(quad(31.5, 63.5, -0.5, 15.5, 0.45));   // the block's top, 10% too near
  map.Add(quad(31.5, 63.5, 15.5, 47.5, 0.53));   // the rest, 6% too far
  const cv::Mat pic = experiments::ErrorPicture(map, 0, ref);
  REQUIRE(pic.size() == ref.depth_m.size());
  REQUIRE(pic.type() == CV_8UC3);
  auto at = [&](int x, int y) { return pic.at<cv::Vec3b>(y, x); };  // B, G, R
  const cv::Vec3b right = at(10, 10), near = at(50, 5), far = at(50, 30), grey = at(10, 44);
  CHECK(right[1] > 150);
  CHECK(right[1] > right[0] + 100);
  CHECK(right[1] > right[2] + 100);
  CHECK(near == cv::Vec3b(16, 16, 255));  // saturated: more than 5% off
  CHECK(far == cv::Vec3b(255, 16, 255));
  CHECK(grey == cv::Vec3b(50, 50, 50));  // mapped, but not scored
  // Both sides of the true jump between columns 31 and 32 are drawn.
  CHECK(at(31, 20) == cv::Vec3b(255, 80, 0));
  CHECK(at(32, 20) == cv::Vec3b(255, 80, 0));
  CHECK(at(30, 20) == right);
}

TEST_CASE("stale IDR patches: finer data at their surface over their whole footprint",
          "[experiments][scoring]") {
  const rig::CameraView view = ForwardView(320, 240, 300);  // at 1 m: x in +-0.533
  // A square over x in [x0, x0 + s], z in [z0, z0 + s] at depth y.
  auto square = [](double x0, double z0, double s, double y, fovea::PatchLevel level) {
    fovea::Patch p;
    p.corners_W = {Eigen::Vector3d(x0, y, z0), Eigen::Vector3d(x0 + s, y, z0),
                   Eigen::Vector3d(x0 + s, y, z0 + s), Eigen::Vector3d(x0, y, z0 + s)};
    p.level = level;
    p.resolution_level = level == fovea::PatchLevel::kFoveal ? 0 : 1;
    return p;
  };
  using L = fovea::PatchLevel;
  fovea::PatchMap map;
  map.Add(square(-0.3, 0.0, 0.1, 1.0, L::kIdr));  // 0: covered by two halves
  map.Add(square(0.45, 0.0, 0.2, 1.0, L::kIdr));  // 1: 42% in view, all of that covered
  map.Add(square(-0.1, 0.0, 0.1, 1.0, L::kIdr));  // 2: a nearer surface in front of it
  map.Add(square(0.1, 0.0, 0.1, 1.0, L::kIdr));   // 3: a farther one behind it
  map.Add(square(-0.3, 0.0, 0.05, 1.0, L::kFoveal));
  map.Add(square(-0.25, 0.0, 0.05, 1.0, L::kFoveal));
  map.Add(square(-0.3, 0.05, 0.1, 1.0, L::kPeripheral));
  map.Add(square(0.4, -0.05, 0.3, 1.0, L::kPeripheral));
  map.Add(square(-0.12, -0.02, 0.14, 0.8, L::kPeripheral));
  map.Add(square(0.1, -0.05, 0.3, 1.6, L::kPeripheral));
  std::vector<char> off(map.size(), 0);
  CHECK(experiments::StaleIdrPatches(map, view, off) == 1);
  // Off its own surface, the IDR patch under nearer finer data is stale too;
  // finer data behind one never covers it.
  off[2] = off[3] = 1;
  CHECK(experiments::StaleIdrPatches(map, view, off) == 2);
  // Moved wholly into view with its cover, the patch at the border is stale.
  fovea::PatchMap inside;
  for (size_t i = 0; i < map.size(); ++i) {
    fovea::Patch p = map[i];
    if (i == 1 || i == 7)
      for (auto& c : p.corners_W) c.x() -= 0.15;
    inside.Add(p);
  }
  CHECK(experiments::StaleIdrPatches(inside, view, off) == 3);
  // Without finer patches nothing is stale.
  fovea::PatchMap idr_only;
  for (size_t i = 0; i < 4; ++i) idr_only.Add(map[i]);
  CHECK(experiments::StaleIdrPatches(idr_only, view, {1, 1, 1, 1}) == 0);
}
