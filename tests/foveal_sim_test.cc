// Foveated vergent stereo at one fixation on the simulated rig, noise on,
// scored against ground truth. Slow: labelled [slow].
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "experiments/config/config.h"
#include "experiments/scoring/foveal_eval.h"
#include "fovea/idr.h"
#include "scenes/catalog.h"
#include "temp_scene.h"

TEST_CASE("foveal and peripheral depth accuracy at three fixations per scene",
          "[foveal][slow][outcome]") {
  struct Point {
    std::string scene;
    Eigen::Vector3d p_W;
  };
  // Cylinder front, left plane, right plane; slanted fabric (two points),
  // plywood behind. Foveal depth within 0.15 of the full-resolution step at
  // these near-level fixations (issue 20: measured 0.064-0.077 in the
  // fixation frame, 0.062-0.103 unrectified; at 0.09 and 0.06 m now
  // 0.047-0.098 and 0.036-0.078).
  const std::vector<Point> points = {
      {"cylinder_planes", {0.0, 0.89, 0.0}},   {"cylinder_planes", {-0.2, 0.93, 0.05}},
      {"cylinder_planes", {0.25, 1.0, -0.05}}, {"three_surfaces", {0.09, 0.86, 0.05}},
      {"three_surfaces", {0.15, 0.91, 0.1}},   {"three_surfaces", {-0.25, 1.2, 0.1}}};
  sim::SimRigConfig config;
  config.noise.read_noise_sigma_dn = experiments::kExperimentNoiseSigmaDn;
  for (const Point& pt : points) {
    auto sim = scenes::LoadScene(pt.scene, config);
    const fovea::IdrResult idr = fovea::RunIdr(sim->rig(), {});
    const fovea::Nl1Matcher matcher;
    // The points lie on the IDR map: the run fixates them at
    // foveal.mapped_baseline_m (0.09 m); a hole's point at foveal.baseline_m
    // (0.06 m).
    fovea::FixationOptions o = fovea::ResolvedFixationOptions({});
    // The two cameras, as measured (the left camera paired with itself,
    // tried first by default, refuses the block's point: no mutual match).
    o.left_pair_first = false;
    for (const double mapped_baseline_m : {o.mapped_baseline_m, 0.0}) {
      o.mapped_baseline_m = mapped_baseline_m;
      const fovea::FixationResult r = fovea::Fixate(sim->rig(), idr.map, pt.p_W, matcher, o);
      INFO(pt.scene << " " << pt.p_W.transpose() << ", baseline " << r.baseline_m);
      REQUIRE(r.ok);
      const experiments::FovealScore s = experiments::ScoreFoveal(r, sim->truth());
      REQUIRE(s.levels.size() >= 2);
      INFO("foveal " << s.levels[0].median_error_steps << " steps over " << s.levels[0].patches
                     << " patches, coverage " << s.fovea_coverage);
      REQUIRE(s.levels[0].patches > 0);
      CHECK(s.levels[0].median_error_steps <= 0.15);
      // Peripheral levels: at most one step of their own level.
      for (size_t k = 1; k < s.levels.size(); ++k)
        if (s.levels[k].patches > 0) CHECK(s.levels[k].median_error_steps <= 1.0);
      // At the wider baseline the slanted fabric (40 degrees) leaves more of
      // the fovea outside the narrower Z_T: measured 0.887 against 0.912 at
      // 0.06 m; the other points 0.96-1.00 at both.
      CHECK(s.fovea_coverage >= (r.baseline_m > 0.06 ? 0.85 : 0.90));
    }
  }
}

TEST_CASE("where the map is silent, a surface outside Z_T gives no false patches",
          "[foveal][slow]") {
  // Fixating the plywood at 1.2 m with nothing mapped: the wooden blocks at
  // 0.50-0.56 m lie far outside Z_T, and the paper's search of the Z_T band
  // takes false matches of their grain for surfaces in the band.
  sim::SimRigConfig config;
  config.noise.read_noise_sigma_dn = experiments::kExperimentNoiseSigmaDn;
  auto gross = [&](double silent_near_m, const std::string& cost) {
    auto sim = scenes::LoadScene("three_surfaces", config);
    fovea::FixationOptions o = fovea::ResolvedFixationOptions({});  // the run's
    o.baseline_m = 0.12;         // Z_T about -0.15 / +0.2 m around 1.2 m: the blocks far outside it
    o.mapped_baseline_m = 0;     // at 0.12 m too (the map is empty, the point is no hole)
    o.choose_placement = false;  // carriages symmetric, as measured
    // The paper's four levels, as measured: the false matches come from the
    // band search of levels 1-3 around the fovea. With the default two
    // levels neither setting gives the fovea a patch off by over 5%.
    o.foveal.tessellation.max_levels = 4;
    // And the paper's band (32 pixels), as measured: at the default 64 the
    // band search alone makes fewer such patches (measured 7 of 185).
    o.foveal.tessellation.horizontal_disparity_limit_px = 32;
    o.foveal.silent_near_m = silent_near_m;
    // Without the limit on oblique planes, which also drops some of the
    // false matches' patches (measured 12 of 191 -> 9 of 187 with the band
    // search alone): this measures the wider search.
    o.foveal.max_view_angle_deg = 0;
    // The verged pair's rows at every level, as measured: matched in the
    // rectified pair, the outermost level takes fewer of the grain's copies
    // (measured: 5 of 144 with the band search alone, none checked).
    o.foveal.rectified_periphery = false;
    fovea::Nl1Options nl1;
    nl1.cost = cost;
    const fovea::Nl1Matcher matcher(nl1);
    const Eigen::Vector3d plywood(-0.25, 1.2, 0.1);
    const fovea::FixationResult r =
        fovea::Fixate(sim->rig(), fovea::PatchMap(), plywood, matcher, o);
    REQUIRE(r.ok);
    REQUIRE((r.fixation_W - plywood).norm() < 0.02);  // the servo held the plywood point
    const experiments::FovealScore s = experiments::ScoreFoveal(r, sim->truth());
    int n = 0, patches = 0;
    for (const auto& l : s.levels) {
      n += l.gross_errors;
      patches += l.patches;
    }
    return std::make_pair(n, patches);
  };
  // The paper's cost (window_mean) takes the blocks' grain for surfaces in
  // the band; the wider search, once per fixation at quarter resolution,
  // removes some (measured 12 -> 5 of 191). The pre-normalized cost, less
  // each image's mean over twice the window, keeps more of the texture's
  // low frequencies out of reach of a copy: its band search alone gives 4,
  // and the check leaves them (they are not copies of the blocks).
  const auto paper = gross(0.0, "window_mean"), paper_checked = gross(0.4, "window_mean");
  const auto ours = gross(0.0, "prenormalized"), ours_checked = gross(0.4, "prenormalized");
  INFO("patches off by over 5%, window_mean: band " << paper.first << " of " << paper.second
                                                    << ", checked " << paper_checked.first);
  INFO("prenormalized: band " << ours.first << " of " << ours.second << ", checked "
                              << ours_checked.first);
  CHECK(paper.first >= 10);
  CHECK(paper_checked.first * 4 <= paper.first * 3);
  CHECK(ours.first * 2 <= paper.first);
  CHECK(ours_checked.first <= ours.first);
  CHECK(ours_checked.second >= ours.second - ours.first);  // the right patches stay
}

TEST_CASE("a surface outside Z_T the map is silent on is searched about the wide match",
          "[foveal][slow]") {
  // Fixating the plywood at 1.2 m with nothing mapped, at the run's
  // defaults but for the baseline: the wooden blocks at 0.50-0.56 m lie far
  // outside Z_T. The band's matches there are dropped by the wide search;
  // with foveal.silent_outside_seed the blocks are searched about its match
  // and mapped, right.
  sim::SimRigConfig config;
  config.noise.read_noise_sigma_dn = experiments::kExperimentNoiseSigmaDn;
  struct Figures {
    int near = 0, near_gross = 0;
  };
  auto fixate = [&](bool seed) {
    auto sim = scenes::LoadScene("three_surfaces", config);
    fovea::FixationOptions o = fovea::ResolvedFixationOptions({});  // the run's
    o.baseline_m = 0.12;  // Z_T about -0.15 / +0.2 m around 1.2 m
    o.mapped_baseline_m = 0;
    o.foveal.silent_near_m = 0.4;  // as the run sets it (idr.z_min_m)
    o.foveal.silent_outside_seed = seed;
    const fovea::Nl1Matcher matcher;
    const Eigen::Vector3d plywood(-0.25, 1.2, 0.1);
    const fovea::FixationResult r =
        fovea::Fixate(sim->rig(), fovea::PatchMap(), plywood, matcher, o);
    REQUIRE(r.ok);
    const Eigen::Vector3d eye = r.servo.frame.left.world_T_camera.translation();
    Figures f;
    for (const fovea::Patch& p : r.foveal.patches.patches()) {
      const Eigen::Vector3d ray = p.Centre() - eye;
      if (ray.norm() > 0.8) continue;  // the plywood's, and the band's
      const auto hit = sim->truth().CastRay(eye, ray);
      ++f.near;
      f.near_gross += !hit || std::abs(hit->distance_m - ray.norm()) > 0.05 * ray.norm();
    }
    return f;
  };
  const Figures band = fixate(false), seeded = fixate(true);
  INFO("patches nearer than 0.8 m: band " << band.near << " (" << band.near_gross
                                          << " off by over 5%), seeded " << seeded.near << " ("
                                          << seeded.near_gross << ")");
  CHECK(band.near <= 2);
  CHECK(seeded.near >= 20);
  CHECK(seeded.near_gross * 10 <= seeded.near);
}

TEST_CASE("peripheral blocks are not split below the matching window beside depth edges",
          "[foveal][slow]") {
  // A fixation on the near wooden block's face: its edges against the
  // plywood 0.65 m behind cross the periphery.
  sim::SimRigConfig config;
  config.noise.read_noise_sigma_dn = experiments::kExperimentNoiseSigmaDn;
  struct Figures {
    int patches = 0, gross = 0, least_support = 1 << 30;
  };
  auto fixate = [&](int periphery_min_block_px) {
    auto sim = scenes::LoadScene("three_surfaces", config);
    const fovea::IdrResult idr = fovea::RunIdr(sim->rig(), {});
    fovea::FixationOptions o = fovea::ResolvedFixationOptions({});  // the run's
    o.foveal.periphery_min_block_px = periphery_min_block_px;
    // Whole blocks or quarters only: the halves that extend a whole
    // neighbour (on by default since 2026-12-07) have their own test in
    // tests/patch_test.cc.
    o.foveal.periphery_half_agreement = 0;
    // The two cameras, as measured (the left camera paired with itself
    // finds no mutual match at this point and refuses it).
    o.left_pair_first = false;
    // In the verged pair's rows, as measured: in the rectified pair the
    // quarters are mostly right too (measured 7 of 231 off by over 5%).
    o.foveal.rectified_periphery = false;
    // The paper's band (32 pixels), as measured (at the default 64: 9 of
    // 373 split quarters off by over 5%, 0 of 54 whole blocks).
    o.foveal.tessellation.horizontal_disparity_limit_px = 32;
    const fovea::Nl1Matcher matcher;
    const fovea::FixationResult r =
        fovea::Fixate(sim->rig(), idr.map, {0.09, 0.86, 0.05}, matcher, o);
    REQUIRE(r.ok);
    Figures f;
    for (const fovea::Patch& p : r.foveal.patches.patches())
      if (p.resolution_level > 0) {
        ++f.patches;
        f.least_support = std::min(f.least_support, p.support);
      }
    const experiments::FovealScore s = experiments::ScoreFoveal(r, sim->truth());
    for (size_t k = 1; k < s.levels.size(); ++k) f.gross += s.levels[k].gross_errors;
    return f;
  };
  const Figures whole = fixate(16), split = fixate(4);
  INFO("peripheral patches: whole blocks "
       << whole.patches << " (" << whole.gross << " off by over 5%, least support "
       << whole.least_support << "), split to 4 px " << split.patches << " (" << split.gross << ", "
       << split.least_support << ")");
  REQUIRE(whole.patches > 0);
  // The default's 16-pixel blocks are whole: half their pixels are inliers.
  CHECK(whole.least_support >= 128);
  // Split to 4 pixels, the edges' quarters (16 pixels at most) become patches.
  CHECK(split.patches > whole.patches);
  CHECK(split.least_support < 128);
  // Those quarters are where the wrong depth was (measured: 53 of 306
  // patches off by over 5% split, 0 of 99 whole).
  CHECK(split.gross >= 10);
  CHECK(whole.gross * 5 <= split.gross);
}

namespace {

// A photo-textured plane facing the rig's centre from `distance_m` at
// `elevation_deg` (fronto-parallel to cameras that look there).
std::string FacingPlane(double distance_m, double elevation_deg) {
  const double e = elevation_deg * M_PI / 180, c = std::cos(e), s = std::sin(e);
  const double d = distance_m + 0.005;
  char geom[300];
  std::snprintf(geom, sizeof geom,
                "<geom name=\"plane\" type=\"box\" size=\"0.8 0.6 0.005\" pos=\"0 %.6f %.6f\" "
                "zaxis=\"0 %.6f %.6f\" material=\"photo\"/>",
                d * c, d * s, -c, -s);
  return geom;
}

struct ElevationFigures {
  int area = 0, unrectified_area = 0;
  double error_steps = 0;
};

ElevationFigures FixateAtElevation(double distance_m, double elevation_deg) {
  const TempScene scene(FacingPlane(distance_m, elevation_deg), TempScene::PhotoAsset());
  sim::SimRigConfig config;
  config.noise.read_noise_sigma_dn = experiments::kExperimentNoiseSigmaDn;
  auto sim = scenes::LoadScene(scene.path(), config);
  const double e = elevation_deg * M_PI / 180;
  const Eigen::Vector3d p_W(0, distance_m * std::cos(e), distance_m * std::sin(e));
  const fovea::FixationOptions o = fovea::ResolvedFixationOptions({});  // the run's
  const fovea::Nl1Matcher matcher;
  const fovea::PatchMap map;  // silent: the fovea is the geometry's alone
  const fovea::FixationResult r = fovea::Fixate(sim->rig(), map, p_W, matcher, o);
  REQUIRE(r.ok);
  ElevationFigures f;
  f.area = r.foveal.tessellation.rects.at(0).area();
  f.unrectified_area = fovea::Tessellate(r.servo.frame.left, r.servo.frame.right, r.fixation_W, map,
                                         o.foveal.tessellation)
                           .rects.at(0)
                           .area();
  const experiments::FovealScore s = experiments::ScoreFoveal(r, sim->truth());
  REQUIRE(s.levels.at(0).patches > 0);
  f.error_steps = s.levels[0].median_error_steps;
  return f;
}

}  // namespace

TEST_CASE("fixations beside a cylinder's limb give no patch seen more obliquely than the limit",
          "[foveal][slow][outcome]") {
  sim::SimRigConfig config;
  config.noise.read_noise_sigma_dn = experiments::kExperimentNoiseSigmaDn;
  auto sim = scenes::LoadScene("cylinder_planes", config);
  const fovea::IdrResult idr = fovea::RunIdr(sim->rig(), {});
  const fovea::Nl1Matcher matcher;
  fovea::FixationOptions o = fovea::ResolvedFixationOptions({});
  REQUIRE(o.foveal.max_view_angle_deg == 70);
  struct Count {
    int oblique = 0, all = 0;
  };
  // Points on the cylinder (radius 0.08 m, axis at y = 0.97 m) 60, 75 and
  // 80 degrees round from its front towards its right limb; the patches
  // seen more obliquely than 60 degrees from the left camera.
  auto fixate = [&](double max_view_angle_deg) {
    o.foveal.max_view_angle_deg = max_view_angle_deg;
    Count c;
    for (const double round_deg : {60.0, 75.0, 80.0}) {
      const double round = round_deg * M_PI / 180;
      const Eigen::Vector3d p_W(0.08 * std::sin(round), 0.97 - 0.08 * std::cos(round), 0);
      const fovea::FixationResult r = fovea::Fixate(sim->rig(), idr.map, p_W, matcher, o);
      REQUIRE(r.ok);
      const Eigen::Vector3d eye_W = r.foveal.frame.views.left.world_T_camera.translation();
      for (const fovea::Patch& p : r.foveal.patches.patches()) {
        ++c.all;
        c.oblique += p.ViewAngleRad(eye_W) > 60 * M_PI / 180;
      }
    }
    return c;
  };
  const Count any = fixate(0), limited = fixate(60);
  INFO("patches beyond 60 degrees: " << any.oblique << " of " << any.all << " without a limit, "
                                     << limited.oblique << " of " << limited.all << " with it");
  // Measured 22 of 674 without: the limb's blocks; with the limit none, and
  // the rest stay.
  CHECK(any.oblique >= 10);
  CHECK(limited.oblique == 0);
  CHECK(limited.all >= any.all - any.oblique - 20);
}

TEST_CASE("at a near fixation the rectified periphery maps what the verged pair's rows miss",
          "[foveal][slow][outcome]") {
  // random:5's fabric-covered column at 0.62 m, fixated from the IDR map:
  // the verged pair's vertical disparity passes a level-1 pixel a little
  // beyond the fovea and the row-wise matcher misses the fine weave there.
  sim::SimRigConfig config;
  config.noise.read_noise_sigma_dn = experiments::kExperimentNoiseSigmaDn;
  auto sim = scenes::LoadScene("random:5", config);
  const fovea::IdrResult idr = fovea::RunIdr(sim->rig(), {});
  const fovea::Nl1Matcher matcher;
  fovea::FixationOptions o = fovea::ResolvedFixationOptions({});
  o.left_pair_first = false;  // the verged pair of the two cameras, as measured
  const Eigen::Vector3d p_W(0.0331, 0.6222, -0.0089);
  struct Level1 {
    int patches = 0;
    experiments::LevelScore score;
    cv::Size rectified_size;  ///< the rectified periphery's disparity map
  };
  auto fixate = [&](bool rectified, bool full_resolution) {
    o.foveal.rectified_periphery = rectified;
    o.foveal.rectified_periphery_full_resolution = full_resolution;
    const fovea::FixationResult r = fovea::Fixate(sim->rig(), idr.map, p_W, matcher, o);
    REQUIRE(r.ok);
    REQUIRE(r.foveal.levels.size() == 2);
    CHECK(r.foveal.rectified_periphery_px.empty() != rectified);
    const experiments::FovealScore s = experiments::ScoreFoveal(r, sim->truth());
    return Level1{r.foveal.levels[1].patches, s.levels[1], r.foveal.rectified_periphery_px.size()};
  };
  const Level1 rows = fixate(false, false), rectified = fixate(true, false),
               full = fixate(true, true);
  auto describe = [](const Level1& l) {
    std::ostringstream s;
    s << l.patches << " patches, median error " << l.score.median_abs_error_m * 1e3 << " mm ("
      << l.score.median_error_steps << " steps), " << l.score.gross_errors << " gross";
    return s.str();
  };
  INFO("peripheral patches: verged pair's rows " << describe(rows) << "; rectified "
                                                 << describe(rectified) << "; at full resolution "
                                                 << describe(full));
  // Measured 7 against 35, at 0.05 steps and no gross error.
  CHECK(rectified.patches >= 2 * rows.patches);
  CHECK(rectified.score.median_error_steps <= 0.25);
  CHECK(rectified.score.gross_errors == 0);
  // At full resolution (the default; FovealOptions::
  // rectified_periphery_full_resolution): every pixel of the image, blocks
  // a quarter of the area. Measured 173 patches against 35, median error
  // 0.10 mm against 0.30 mm, one gross error.
  const rig::CameraIntrinsics k = sim->rig().Intrinsics(rig::Side::kLeft);
  const cv::Size image(k.width_px, k.height_px);
  CHECK(full.rectified_size == image);
  CHECK(rectified.rectified_size == cv::Size(image.width / 2, image.height / 2));
  CHECK(full.patches >= 3 * rectified.patches);
  CHECK(full.score.median_abs_error_m <= 0.5 * rectified.score.median_abs_error_m);
  CHECK(full.score.gross_errors <= 2);
}

TEST_CASE("foveal.fovea_edge_erosion_px erodes the fovea's level only", "[foveal][slow]") {
  // A fixation on three_surfaces' slanted fabric, a depth edge in the
  // fovea, with the run's options: once with one erosion (3 pixels) at
  // every level, once with a wider one (5) at the fovea's level. The matches
  // before erosion are the same, so the wider erosion drops a superset of
  // the fovea's matches (measured 23 against 2) and leaves the peripheral
  // levels as they were.
  sim::SimRigConfig config;
  config.noise.read_noise_sigma_dn = experiments::kExperimentNoiseSigmaDn;
  const fovea::Nl1Matcher matcher;
  auto fixate = [&](int fovea_erosion_px) {
    // A fresh scene each time: the same noise, so the same matches before
    // erosion.
    auto sim = scenes::LoadScene("three_surfaces", config);
    const fovea::IdrResult idr = fovea::RunIdr(sim->rig(), {});
    fovea::FixationOptions o = fovea::ResolvedFixationOptions({});
    o.foveal.fovea_edge_erosion_px = fovea_erosion_px;
    o.left_pair_first = false;  // the two cameras, as the tests above
    const fovea::FixationResult r =
        fovea::Fixate(sim->rig(), idr.map, {0.15, 0.91, 0.1}, matcher, o);
    REQUIRE(r.ok);
    return r.foveal;
  };
  const fovea::FovealResult same = fixate(-1), wider = fixate(5);
  REQUIRE(same.levels.size() == wider.levels.size());
  REQUIRE(same.levels.size() >= 2);
  INFO("level 0 eroded: " << same.levels[0].eroded << " at 3 pixels, " << wider.levels[0].eroded
                          << " at 5");
  CHECK(same.levels[0].eroded > 0);
  CHECK(wider.levels[0].eroded > same.levels[0].eroded);
  const cv::Mat &d3 = same.disparity_px[0], &d5 = wider.disparity_px[0];
  REQUIRE(d3.size() == d5.size());
  int kept_only_wider = 0;
  for (int y = 0; y < d3.rows; ++y)
    for (int x = 0; x < d3.cols; ++x)
      kept_only_wider += std::isfinite(d5.at<float>(y, x)) && !std::isfinite(d3.at<float>(y, x));
  CHECK(kept_only_wider == 0);
  for (size_t k = 1; k < same.levels.size(); ++k) {
    INFO("level " << k);
    CHECK(wider.levels[k].eroded == same.levels[k].eroded);
    CHECK(wider.levels[k].patches == same.levels[k].patches);
  }
}

TEST_CASE("the fovea keeps its size at any elevation the heads reach", "[foveal][slow][outcome]") {
  // Issue 20: tilted verged heads twist their rows against each other; in
  // the fixation frame the fovea stays the level fixation's (measured 0.99 to
  // 1.02 of it, against 0.04-0.17 unrectified beyond 10 degrees), and foveal
  // depth stays within 0.11 steps. The map is left silent: the fovea is the
  // geometry's alone (Z_max 0). Five elevations: both signs, the heads'
  // extremes, and either side of 10 degrees, where unrectified foveae
  // shrink.
  for (const double distance : {0.6, 0.9, 1.2}) {
    const ElevationFigures level = FixateAtElevation(distance, 0);
    for (const int elevation : {-20, -10, 0, 15, 20}) {
      const ElevationFigures f = elevation == 0 ? level : FixateAtElevation(distance, elevation);
      std::printf(
          "plane at %.1f m, elevation %+3d deg: fovea %6d px (%.2f of level), "
          "unrectified %6d px (%.2f), foveal error %.3f steps\n",
          distance, elevation, f.area, double(f.area) / level.area, f.unrectified_area,
          double(f.unrectified_area) / level.area, f.error_steps);
      INFO("distance " << distance << " elevation " << elevation);
      CHECK(f.area >= 0.8 * level.area);
      CHECK(f.area >= 32 * 32);
      if (std::abs(elevation) <= 15) CHECK(f.error_steps <= 0.25);
    }
    CHECK(level.error_steps <= 0.15);
  }
}
