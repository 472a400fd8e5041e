// The full FOVEA run as a user runs it (fovea run): records, summary,
// reproducibility, local suppression, the paper's near-then-far behaviour.
#include "fovea/ddr.h"

#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "experiments/output/run_folder.h"
#include "fovea/geometry.h"

namespace fs = std::filesystem;
namespace run_folder = experiments::run_folder;
using nlohmann::json;

namespace {

fs::path Out(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("fovea_ddr_" + name + "_" + std::to_string(getpid()));
  fs::remove_all(dir);
  return dir;
}

void RunFovea(const std::string& args, const fs::path& out) {
  const std::string cmd =
      std::string(FOVEA_BIN) + " run " + args + " --out " + out.string() + " 2>/dev/null";
  REQUIRE(std::system(cmd.c_str()) == 0);
}

std::vector<json> Records(const fs::path& out) {
  std::ifstream in(out / run_folder::kRecords);
  std::vector<json> r;
  for (std::string line; std::getline(in, line);) r.push_back(json::parse(line));
  return r;
}

json Summary(const fs::path& out) {
  std::ifstream in(out / run_folder::kSummary);
  return json::parse(in);
}

// Leaves out the wall-clock keys, at any depth.
json WithoutWallClock(json j) {
  if (j.is_object()) {
    for (auto it = j.begin(); it != j.end();)
      it = run_folder::IsWallClockKey(it.key()) ? j.erase(it) : std::next(it);
    for (auto& [k, v] : j.items()) v = WithoutWallClock(v);
  }
  return j;
}

std::string Text(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

TEST_CASE("fovea run: the same seed gives the same run, another seed another one",
          "[ddr][slow][outcome]") {
  const fs::path a = Out("a"), b = Out("b"), c = Out("c");
  RunFovea("--scene two_planes --fixations 6 --seed 1", a);
  RunFovea("--scene two_planes --fixations 6 --seed 1", b);
  RunFovea("--scene two_planes --fixations 6 --seed 2", c);
  const auto ra = Records(a), rb = Records(b), rc = Records(c);
  REQUIRE(ra.size() == rb.size());
  for (size_t i = 0; i < ra.size(); ++i) {
    INFO("record " << i);
    CHECK(WithoutWallClock(ra[i]).dump() == WithoutWallClock(rb[i]).dump());
    CHECK(ra[i].contains("motion_time_s"));  // simulated, deterministic: it stays in
  }
  CHECK(WithoutWallClock(Summary(a)).dump() == WithoutWallClock(Summary(b)).dump());
  CHECK(Text(a / "map.ply") == Text(b / "map.ply"));
  std::vector<json> ta, tc;
  for (const auto& r : ra) ta.push_back(r["target_W"]);
  for (const auto& r : rc) tc.push_back(r["target_W"]);
  CHECK(ta != tc);
  for (const auto& d : {a, b, c}) fs::remove_all(d);
}

TEST_CASE(
    "fovea run on two_planes: near plane first, then the far one, with its outputs and summary "
    "keys",
    "[ddr][slow]") {
  const fs::path out = Out("two");
  RunFovea("--scene two_planes", out);
  const auto records = Records(out);
  const json s = Summary(out);
  CHECK(s["fixations"] == 25);
  CHECK(s["scene"].get<std::string>().find("two_planes") != std::string::npos);
  CHECK(s["seed"] == 0);
  CHECK(s["coverage"].get<double>() > 0.9);
  CHECK(s["foveal_coverage"].get<double>() > 0);
  CHECK(s["foveal_coverage"].get<double>() < s["coverage"].get<double>());
  CHECK(s["median_rel_error"].get<double>() < 0.01);
  CHECK(s["median_abs_error_m"].get<double>() > 0);
  CHECK(s["rmse_m"].get<double>() >= s["median_abs_error_m"].get<double>());
  // Simulated motion: IDR's moves and every attempt's, so more than the
  // records' sum alone; wall time covers compute.
  double records_motion_s = 0;
  for (const json& r : records) records_motion_s += r["motion_time_s"].get<double>();
  CHECK(records_motion_s > 0);
  CHECK(s["motion_time_s"].get<double>() > records_motion_s);
  CHECK(s["wall_time_s"].get<double>() > s["compute_time_s"].get<double>());
  std::vector<std::string> files = {run_folder::kMapPly, run_folder::kFixationPath,
                                    run_folder::kConfig, run_folder::kReference,
                                    run_folder::kErrorPicture};
  for (const int k : run_folder::kSnapshotFixations) files.push_back(run_folder::SnapshotName(k));
  for (const std::string& f : files) {
    INFO(f);
    CHECK(fs::file_size(out / f) > 100);
  }
  // Near plane at y = 0.6 m, far plane at 1.3 m. The choice is a draw from
  // the criteria's histogram, so the path varies with the seed and every
  // setting (seed 0: NNNNNNNNNFFFFFFFFFFFFFFFF, seed 1:
  // NNNNNFFFFFFNNNNFFFFFFFFFF): the nearest textured surface first, then
  // both planes get fixations and both end mapped.
  std::vector<bool> near;
  for (const auto& r : records)
    if (r["ok"]) near.push_back(r["fixation_W"][1].get<double>() < 0.95);
  REQUIRE(near.size() == 25);
  CHECK(near[0]);
  CHECK(std::count(near.begin(), near.end(), true) >= 5);
  CHECK(std::count(near.begin(), near.end(), false) >= 5);
  // Each plane ends mapped. Since foveal.edge_hole_px the strips beside the
  // near plane's edge and weakly textured stretches may stay empty: measured
  // 0.993 / 0.997 (near / far) in the release build and 0.934 on the far
  // plane in the sanitizer build, whose floating point takes another path.
  // Since the selection weighs at half resolution (selection.resolution_level
  // 1) seed 0 takes another path, whose fixations 11-19 stay on the far
  // plane's right half: 0.878 on the far plane in the release build, 0.963
  // in the sanitizer build.
  for (const char* plane : {"near_plane", "far_plane"}) {
    INFO(plane);
    CHECK(records.back()["score"]["by_surface"][plane]["coverage"].get<double>() >= 0.85);
  }
  // The map's foveal share grows with fixations; the whole map stays accurate.
  const double f1 = records.front()["score"]["foveal_coverage"],
               f25 = records.back()["score"]["foveal_coverage"];
  CHECK(f25 > f1);
  CHECK(s["median_rel_error"].get<double>() < 0.01);
  // Measured 0.994 (2 levels); since foveal.edge_hole_px 4 the strips along
  // the near plane's edge stay empty rather than wrong: 0.942 in the release
  // build (RMSE 15.5 -> 3.8 mm), 0.945 in the sanitizer build; since
  // foveal.horizontal_disparity_limit_px 64, 0.948 in the release build.
  CHECK(s["coverage"].get<double>() >= 0.93);
  // No IDR patch outlives finer data covering it in the reference view
  // (retired in the IDR view alone, 15 did here).
  CHECK(s["stale_idr_patches"] == 0);
  fs::remove_all(out);
}

TEST_CASE("local suppression: without it, fixations revisit mapped places more",
          "[ddr][slow][outcome]") {
  auto revisits = [](const std::string& suppression) {
    const fs::path out = Out("sup" + suppression);
    RunFovea("--scene cylinder_planes --fixations 12 --set criteria.suppression=" + suppression,
             out);
    std::vector<Eigen::Vector3d> pts;
    for (const auto& r : Records(out))
      if (r["ok"]) pts.emplace_back(r["fixation_W"][0], r["fixation_W"][1], r["fixation_W"][2]);
    fs::remove_all(out);
    int n = 0;
    for (size_t i = 0; i < pts.size(); ++i)
      for (size_t j = 0; j < i; ++j)
        if ((pts[i] - pts[j]).norm() < 0.03) {
          ++n;
          break;
        }
    return n;
  };
  const int with = revisits("true"), without = revisits("false");
  INFO("revisits within 3 cm: with suppression " << with << ", without " << without);
  CHECK(without >= with + 3);
}

TEST_CASE(
    "selection.reference_fallback: a choice of mapped (or foveal) data in the current view, or "
    "mapped data after a stalled fixation, gives way to a hole in the reference view",
    "[ddr][slow][outcome]") {
  // [outcome]: it compares the paths of six whole runs, about three
  // minutes under the sanitizers, a tenth of CI's budget. The three rules
  // share the fallback's code but for the condition that starts it
  // (ChooseTarget in fovea/src/ddr.cc), and the sanitizer pass runs the
  // other end-to-end tests at the default rule.
  // Each run's first fallback comes at its second attempt, where the
  // default's choice is mapped data (random:4 seed 0) and foveal data
  // (random:7 seed 0), in the release and the sanitizer builds alike
  // (measured; two_planes seed 1 falls back in one and not the other).
  // cylinder_planes is nearly whole after a few fixations, so one of them
  // stalls early (seed 3: the first fallback at the fifth attempt, in the
  // release build, since the defaults of 2026-12-07; seed 2, whose first
  // came at the fourth before, has none in its first twelve now); eight
  // leave room for another path in the sanitizer build. The cases were
  // found with the two-camera placements tried first
  // (foveal.left_pair_first=false), whose paths reach them, and with the
  // defaults before 2026-12-08 (foveal.baseline_m 0.06, patches fused
  // within a level only), which the runs keep: the narrower baseline and
  // the fusion across levels move every path.
  struct Case {
    std::string scene, seed, fallback, fixations;
  };
  for (const auto& [scene, seed, fallback, fixations] :
       {Case{"random:4", "0", "mapped", "3"}, Case{"random:7", "0", "foveal", "3"},
        Case{"cylinder_planes", "3", "stalled", "8"}}) {
    INFO(scene << " seed " << seed << ", " << fallback);
    const fs::path with = Out("fallback"), without = Out("nofallback");
    const std::string run = "--scene " + scene + " --seed " + seed + " --fixations " + fixations +
                            " --set foveal.left_pair_first=false --set foveal.baseline_m=0.06"
                            " --set integration.fuse_across_levels=false";
    RunFovea(run + " --set selection.reference_fallback=" + fallback, with);
    RunFovea(run + " --set selection.reference_fallback=none", without);
    const auto rw = Records(with), rn = Records(without);
    int fallbacks = 0;
    for (const auto& r : rw) {
      const json& s = r["selection"];
      if (!s.contains("in_reference")) continue;
      ++fallbacks;
      CHECK(s["in_reference"] == true);
      CHECK(s["in_hole"] == true);  // only a hole replaces the current view's choice
    }
    CHECK(fallbacks >= 1);
    for (const auto& r : rn) CHECK_FALSE(r["selection"].contains("in_reference"));
    // Up to the first fallback the two runs chose alike.
    REQUIRE(rw.size() >= 2);
    CHECK(WithoutWallClock(rw[0]).dump() == WithoutWallClock(rn[0]).dump());
    for (const auto& d : {with, without}) fs::remove_all(d);
  }
}

TEST_CASE("a hole's servo search reaches a margin beyond the farthest depth IDR mapped", "[ddr]") {
  // Two fronto-parallel planes before a camera at the origin looking along
  // world Y: 1.0 m on the left half of the view, 1.6 m on the right.
  rig::CameraView view;
  view.intrinsics = rig::CameraIntrinsics::FromHorizontalFov(160, 120, 30 * M_PI / 180);
  view.world_T_camera.linear() << 1, 0, 0, 0, 0, 1, 0, -1, 0;  // x right, y down, z = world Y
  auto plane = [](double x0, double x1, double y) {
    fovea::Patch p;
    p.corners_W = {Eigen::Vector3d(x0, y, 1), Eigen::Vector3d(x1, y, 1), Eigen::Vector3d(x1, y, -1),
                   Eigen::Vector3d(x0, y, -1)};
    return p;
  };
  fovea::PatchMap map;
  map.Add(plane(-1, 0, 1.0));
  map.Add(plane(0, 2, 1.6));
  fovea::FoveaOptions options;
  options.idr.z_min_m = 0.4;
  options.hole_far_factor = 1.5;
  const fovea::DepthRange r = fovea::HoleDepths(map, view, options);
  CHECK(r.near_m == 0.4);
  CHECK(r.far_m == Approx(1.5 * 1.6).epsilon(0.01));
  options.hole_far_factor = 0;  // to infinity, as before
  CHECK(fovea::HoleDepths(map, view, options).far_m == fovea::kFarDepthM);
  options.hole_far_factor = 1.5;  // an empty map bounds nothing
  CHECK(fovea::HoleDepths(fovea::PatchMap(), view, options).far_m == fovea::kFarDepthM);
}

TEST_CASE(
    "fovea run: patches the reference camera does not see leave the reference view's map, "
    "and the fixations do not change",
    "[ddr][slow][outcome]") {
  // two_planes seed 2: fixation 12 looks at the far plane beside the near
  // plane's edge from 9 mm right of the home pose, and sees a strip of it
  // that the reference view does not (where the near plane's edge is
  // unmapped, that strip showed through with the far depth). At the
  // earlier foveal.edge_hole_px of 7 and foveal.horizontal_disparity_limit_px
  // of 32: with 4, the default since, the same run's fixations add no patch
  // the check marks (measured), and at the default band of 64 the path
  // changes (measured there: edge_bad_share 0.155 -> 0.132); this test is of
  // the check where such a strip arises. The selection passes over the
  // marked patches (loop.stay_in_idr_view), so the check can change the
  // path; on this run no choice fell on one (measured), and only the
  // reference view's map differs. The path is the one of the defaults
  // before 2026-12-08 too (foveal.baseline_m 0.06, patches fused within a
  // level only): the narrower baseline and the fusion across levels move it.
  const fs::path on = Out("seen_on"), off = Out("seen_off");
  const std::string args =
      "--scene two_planes --seed 2 --fixations 12 --set foveal.edge_hole_px=7 "
      "--set foveal.horizontal_disparity_limit_px=32 --set foveal.baseline_m=0.06 "
      "--set integration.fuse_across_levels=false";
  RunFovea(args + " --set integration.reference_min_ncc=0.5", on);
  RunFovea(args + " --set integration.reference_min_ncc=0", off);
  const std::vector<json> a = Records(on), b = Records(off);
  REQUIRE(a.size() == b.size());
  int hidden = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    // The same path: the marked patches stay in the map the run works with.
    CHECK(a[i].value("fixation_W", json()) == b[i].value("fixation_W", json()));
    if (a[i].contains("integration"))
      hidden += a[i]["integration"]["hidden_in_reference"].get<int>();
    if (b[i].contains("integration")) CHECK(b[i]["integration"]["hidden_in_reference"] == 0);
  }
  CHECK(hidden > 0);
  const json s_on = Summary(on), s_off = Summary(off);
  CHECK(s_on["map_patches"] == s_off["map_patches"]);
  // Measured: edge_bad_share 0.214 -> 0.143, bad_share 0.0057 -> 0.0035,
  // good_coverage 0.8265 -> 0.8256 by the quarters alone; with the pooled
  // samples (integration.reference_pooled_min_ncc 0.2, the default since)
  // 0.077, 0.0020 and 0.8247.
  CHECK(s_on["edge_bad_share"].get<double>() < 0.8 * s_off["edge_bad_share"].get<double>());
  CHECK(s_on["bad_share"].get<double>() < s_off["bad_share"].get<double>());
  CHECK(s_on["good_coverage"].get<double>() > s_off["good_coverage"].get<double>() - 0.01);
  fs::remove_all(on);
  fs::remove_all(off);
}
