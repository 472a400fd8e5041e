// Visual servoing on the simulated rig, noise on.
#include "fovea/servo.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <memory>
#include <string>

#include "experiments/config/config.h"
#include "fovea/ddr.h"
#include "fovea/foveal.h"
#include "fovea/geometry.h"
#include "fovea/idr.h"
#include "fovea/vergence.h"
#include "scenes/catalog.h"

namespace {

// A catalog scene with sensor noise on (2 grey levels).
std::unique_ptr<sim::Simulation> NoisyScene(const std::string& name) {
  sim::SimRigConfig config;
  config.noise.read_noise_sigma_dn = experiments::kExperimentNoiseSigmaDn;
  return scenes::LoadScene(name, config);
}

// The servo's measured residuals, for a failure's message.
std::string Residuals(const fovea::ServoResult& r) {
  std::string s;
  for (double d : r.residuals_px) s += std::to_string(d) + " ";
  return s;
}

// A point on the left camera's axis as it fixates p_W, `scale` times as far
// from the camera: fixating it points the left camera at p_W again, with the
// depth guessed wrong.
Eigen::Vector3d OnLeftAxis(rig::Rig& rig, const Eigen::Vector3d& p_W, double scale,
                           double baseline_m) {
  const auto sol =
      fovea::Verge(rig.Geometry(), rig.Limits(), rig.Intrinsics(rig::Side::kLeft),
                   rig.Intrinsics(rig::Side::kRight), rig::StageState::Parallel(baseline_m), p_W);
  REQUIRE(sol.ok);
  rig.MoveTo(sol.state);
  const Eigen::Vector3d c = rig.Capture().left.world_T_camera.translation();
  return c + scale * (p_W - c);
}

// Every depth from the scenes' nearest (idr.z_min_m's default) to infinity.
const fovea::DepthRange kEveryDepth{0.4, fovea::kFarDepthM};

}  // namespace

TEST_CASE("servoing converges from 20 px off within 6 steps", "[fovea][servo][slow][outcome]") {
  struct Point {
    std::string scene;
    Eigen::Vector3d p_W;
  };
  const std::vector<Point> points = {
      {"cylinder_planes", {0.0, 0.89, 0.0}},   {"cylinder_planes", {-0.2, 0.93, 0.05}},
      {"cylinder_planes", {0.25, 1.0, -0.05}}, {"three_surfaces", {-0.05, 0.53, -0.055}},
      {"three_surfaces", {0.09, 0.86, 0.05}},  {"three_surfaces", {-0.25, 1.2, 0.1}}};
  for (const Point& pt : points) {
    INFO(pt.scene << " " << pt.p_W.transpose());
    auto sim = NoisyScene(pt.scene);
    rig::Rig& rig = sim->rig();
    const auto sol =
        fovea::Verge(rig.Geometry(), rig.Limits(), rig.Intrinsics(rig::Side::kLeft),
                     rig.Intrinsics(rig::Side::kRight), rig::StageState::Parallel(0.12), pt.p_W);
    REQUIRE(sol.ok);
    rig::StageState start = sol.state;
    const double f = rig.Intrinsics(rig::Side::kRight).fx_px;
    start.right.pan_rad += std::atan(20.0 / f);  // the point 20 px off centre
    const fovea::ServoResult r = fovea::Servo(rig, start, {});
    INFO("residuals: " << Residuals(r));
    REQUIRE_FALSE(r.residuals_px.empty());
    CHECK(std::abs(std::abs(r.residuals_px.front()) - 20) < 2);  // it did start 20 px off
    CHECK(r.converged);
    CHECK(std::abs(r.residual_px) < 0.5);
    CHECK(r.iterations <= 6);
  }
}

TEST_CASE("a guessed depth: the servo searches every depth and finds the surface",
          "[fovea][servo][slow]") {
  auto sim = NoisyScene("three_surfaces");
  rig::Rig& rig = sim->rig();
  const fovea::Nl1Matcher matcher;
  const fovea::PatchMap empty;
  // The left wooden block's face at 0.50 m, guessed at 1.2 m (the plywood's
  // depth, as a hole's nearest mapped neighbour would have it): at a 0.12 m
  // baseline about 170 px of disparity, far beyond the +-40 px of the
  // ordinary search.
  fovea::FixationOptions o = fovea::ResolvedFixationOptions({});  // the run's
  o.baseline_m = 0.12;
  o.mapped_baseline_m = 0;     // the narrow search below at 0.12 m too
  o.choose_placement = false;  // the symmetric carriages OnLeftAxis assumes
  const Eigen::Vector3d block(-0.11, 0.50, -0.055);
  const Eigen::Vector3d guess = OnLeftAxis(rig, block, 2.4, o.baseline_m);
  const fovea::FixationResult wide = fovea::Fixate(rig, empty, guess, matcher, o, 0, kEveryDepth);
  INFO("wide: " << wide.why << " fixated at " << wide.fixation_W.transpose() << ", residuals "
                << Residuals(wide.servo) << ", mutual mismatch "
                << (wide.servo.mutual_mismatch_px ? *wide.servo.mutual_mismatch_px : 99.0));
  REQUIRE(wide.ok);
  CHECK(wide.servo.converged);
  CHECK((wide.fixation_W - block).norm() < 0.02);
  const fovea::FixationResult narrow = fovea::Fixate(rig, empty, guess, matcher, o);
  INFO("narrow: fixated at " << narrow.fixation_W.transpose());
  CHECK((narrow.fixation_W - block).norm() > 0.1);
}

TEST_CASE("a guessed depth on a periodic texture: no unique match, the point is refused",
          "[fovea][servo][slow]") {
  auto sim = NoisyScene("periodic");
  rig::Rig& rig = sim->rig();
  const fovea::Nl1Matcher matcher;
  const fovea::PatchMap empty;
  // The stripes (period about 21 px) at 0.9 m, guessed at 0.6 m: every
  // period in the search matches as well as the true one.
  fovea::FixationOptions o = fovea::ResolvedFixationOptions({});  // the run's
  o.choose_placement = false;  // the symmetric carriages OnLeftAxis assumes
  const Eigen::Vector3d guess = OnLeftAxis(rig, {0.0, 0.9, 0.0}, 2.0 / 3.0, o.baseline_m);
  const fovea::FixationResult r = fovea::Fixate(rig, empty, guess, matcher, o, 0, kEveryDepth);
  CHECK_FALSE(r.ok);
  CHECK(r.why.find("unique") != std::string::npos);
  CHECK(r.foveal.patches.size() == 0);
}

TEST_CASE(
    "a point the right camera cannot see: the servo's match is not mutual, the point is refused",
    "[fovea][servo][slow]") {
  auto sim = NoisyScene("three_surfaces");
  rig::Rig& rig = sim->rig();
  const fovea::Nl1Matcher matcher;
  const fovea::PatchMap empty;
  // Plywood at 1.2 m just left of the slanted fabric's left edge (0.73 m
  // deep): the left camera sees it past the edge, the right camera, 6 cm
  // to the right, sees the fabric in front of it.
  const Eigen::Vector3d hidden(-0.10, 1.2, 0.0);
  fovea::FixationOptions o = fovea::ResolvedFixationOptions({});  // the run's
  o.choose_placement = false;  // symmetric carriages: the right camera's view is blocked
  SECTION("without the check the servo settles on another surface") {
    o.servo.mutual_tolerance_px = 0;
    const fovea::FixationResult r = fovea::Fixate(rig, empty, hidden, matcher, o, 0);
    INFO(r.why << " fixated at " << r.fixation_W.transpose() << ", residuals "
               << Residuals(r.servo));
    CHECK(r.servo.mutual);
    CHECK_FALSE(r.servo.mutual_mismatch_px);
    // The reverse search finds the plywood's window far from the fabric's.
    const auto mismatch = fovea::MutualMismatch(r.servo.frame, o.servo, r.servo.residual_px);
    REQUIRE(mismatch);
    CHECK(std::abs(*mismatch) > 8);
    // A false fixation: far from the plywood point on the left camera's axis.
    if (r.ok) CHECK((r.fixation_W - hidden).norm() > 0.05);
  }
  SECTION("with it the point is refused before any matching") {
    REQUIRE(o.servo.mutual_tolerance_px == 4.0);
    const fovea::FixationResult r = fovea::Fixate(rig, empty, hidden, matcher, o, 0);
    INFO(r.why << " fixated at " << r.fixation_W.transpose() << ", residuals " << Residuals(r.servo)
               << ", mismatch "
               << (r.servo.mutual_mismatch_px ? *r.servo.mutual_mismatch_px : 0.0));
    CHECK_FALSE(r.ok);
    CHECK_FALSE(r.servo.mutual);
    CHECK(r.why.find("mutual") != std::string::npos);
    CHECK(r.foveal.patches.size() == 0);
  }
  SECTION("a visible point on the same plywood passes the check") {
    const Eigen::Vector3d open(-0.25, 1.2, 0.1);
    const fovea::FixationResult r = fovea::Fixate(rig, empty, open, matcher, o, 0);
    INFO(r.why << " fixated at " << r.fixation_W.transpose() << ", residual " << r.servo.residual_px
               << ", mismatch "
               << (r.servo.mutual_mismatch_px ? *r.servo.mutual_mismatch_px : 99.0));
    REQUIRE(r.ok);
    CHECK(r.servo.mutual);
    REQUIRE(r.servo.mutual_mismatch_px);
    CHECK(std::abs(*r.servo.mutual_mismatch_px) < 0.5);
    CHECK((r.fixation_W - open).norm() < 0.02);
  }
}

TEST_CASE(
    "a servo settled on a false match in empty air is refused when the map knows the surface "
    "behind",
    "[fovea][servo][slow]") {
  // The staircase: nothing nearer than its first riser at 0.62 m. Aimed
  // 0.4 of the way from the left camera to a point on the wall, the servo
  // settles near 0.45 m, in air, on a match that both the search and its
  // mutual check accept (the textures repeat 4 times a face); the IDR
  // map holds the steps behind that point, certain to a few millimetres.
  auto sim = NoisyScene("staircase");
  rig::Rig& rig = sim->rig();
  const fovea::Nl1Matcher matcher;
  const fovea::IdrResult idr = fovea::RunIdr(rig, {});
  REQUIRE(idr.map.size() > 100);
  fovea::FixationOptions o = fovea::ResolvedFixationOptions({});  // the run's
  o.choose_placement = false;  // the symmetric carriages OnLeftAxis assumes
  o.mapped_baseline_m = 0;     // and its baseline, though the map holds the point
  // The false match was found at 0.06 m (the default until 2026-12-08); at
  // 0.04 m the servo settles nearer than idr.z_min_m, refused before the
  // map check.
  o.baseline_m = 0.06;
  const Eigen::Vector3d air = OnLeftAxis(rig, {-0.1, 1.0, 0.0}, 0.4, o.baseline_m);
  o.map_check = false;
  const fovea::FixationResult trusting = fovea::Fixate(rig, idr.map, air, matcher, o);
  INFO("without the check: ok " << trusting.ok << ", " << trusting.why << ", fixated at "
                                << trusting.fixation_W.transpose());
  REQUIRE(trusting.ok);
  CHECK(trusting.fixation_W.y() < 0.55);  // a false fixation, in front of every step
  o.map_check = true;
  const fovea::FixationResult checked = fovea::Fixate(rig, idr.map, air, matcher, o);
  INFO(checked.why);
  CHECK_FALSE(checked.ok);
  CHECK(checked.why.find("in front of the surface the map holds") != std::string::npos);
  CHECK(checked.foveal.patches.size() == 0);
  // A point on a riser itself passes.
  const fovea::FixationResult step = fovea::Fixate(rig, idr.map, {-0.1, 0.805, 0.005}, matcher, o);
  INFO(step.why);
  CHECK(step.ok);
  CHECK((step.fixation_W - Eigen::Vector3d(-0.1, 0.805, 0.005)).norm() < 0.02);
}

TEST_CASE("a hole's prescreen asks the servo's mutual check of the pair it has", "[fovea][servo]") {
  // A parallel pair 0.1 m apart looking along +z, 320 x 240 px at 30 deg
  // (fx 597 px): depths 0.5-5 m are disparities of 119-12 px. Both images
  // are independent noise but for a 41 x 41 texture T, in the right image at
  // x 140 and in the left at x 200 (1 m away), slightly noisier there.
  rig::StereoFrame f;
  for (rig::CameraView* v : {&f.left, &f.right}) {
    v->intrinsics = rig::CameraIntrinsics::FromHorizontalFov(320, 240, 30 * M_PI / 180);
    v->gray = cv::Mat(240, 320, CV_8U);
  }
  f.right.world_T_camera.translation() = Eigen::Vector3d(0.1, 0, 0);
  cv::RNG rng(7);
  rng.fill(f.left.gray, cv::RNG::UNIFORM, 0, 256);
  rng.fill(f.right.gray, cv::RNG::UNIFORM, 0, 256);
  cv::Mat t(41, 41, CV_8U), noisy;
  rng.fill(t, cv::RNG::UNIFORM, 40, 216);
  cv::Mat noise(41, 41, CV_16S);
  rng.fill(noise, cv::RNG::UNIFORM, -25, 26);
  cv::Mat t16;
  t.convertTo(t16, CV_16S);
  cv::Mat(t16 + noise).convertTo(noisy, CV_8U);
  t.copyTo(f.right.gray(cv::Rect(140 - 20, 100, 41, 41)));
  noisy.copyTo(f.left.gray(cv::Rect(200 - 20, 100, 41, 41)));
  const Eigen::Vector2d pixel(200, 120);
  const fovea::DepthRange depths{0.5, 5.0};
  fovea::ServoOptions o;
  REQUIRE(o.mutual_tolerance_px > 0);
  CHECK(fovea::UniqueAlongRay(f, pixel, depths, o));
  // An exact copy of T in the left image 40 px further right, within the
  // right window's ray: its best match is no longer the pixel asked about.
  // The match forward stays unique (the right image holds T once), so only
  // the mutual check refuses it.
  t.copyTo(f.left.gray(cv::Rect(240 - 20, 100, 41, 41)));
  CHECK_FALSE(fovea::UniqueAlongRay(f, pixel, depths, o));
  o.mutual_tolerance_px = 0;  // no mutual check: unique forward is enough
  CHECK(fovea::UniqueAlongRay(f, pixel, depths, o));
}

TEST_CASE("a point the map holds verges at foveal.mapped_baseline_m, a hole's at foveal.baseline_m",
          "[fovea][servo]") {
  auto sim = NoisyScene("two_planes");
  const fovea::Nl1Matcher matcher;
  fovea::FixationOptions o = fovea::ResolvedFixationOptions({});  // the run's
  REQUIRE(o.mapped_baseline_m > o.baseline_m);
  o.choose_placement = false;  // symmetric carriages: their gap is the baseline
  const Eigen::Vector3d near_plane(-0.15, 0.6, 0.02);  // its face: x -0.48 to 0.02, y 0.6
  auto gap = [](const fovea::FixationResult& r) {
    return r.vergence.state.right.carriage_m - r.vergence.state.left.carriage_m;
  };
  // Its depth known (no guessed depths): the wider baseline.
  const fovea::FixationResult mapped =
      fovea::Fixate(sim->rig(), fovea::PatchMap(), near_plane, matcher, o);
  REQUIRE(mapped.ok);
  CHECK(mapped.baseline_m == o.mapped_baseline_m);
  CHECK(gap(mapped) == Approx(o.mapped_baseline_m).margin(1e-4));
  CHECK((mapped.fixation_W - near_plane).norm() < 0.01);
  // A hole's guessed depth: the narrow one, whose Z_T is wider.
  const fovea::FixationResult hole = fovea::Fixate(sim->rig(), fovea::PatchMap(), near_plane,
                                                   matcher, o, 0, fovea::DepthRange{0.4, 2.0});
  REQUIRE(hole.ok);
  CHECK(hole.baseline_m == o.baseline_m);
  CHECK(gap(hole) == Approx(o.baseline_m).margin(1e-4));
  // The wider pair's foveal depth band is narrower, as its depth step is.
  const double band_mapped =
                   mapped.foveal.tessellation.z_t_far_m - mapped.foveal.tessellation.z_t_near_m,
               band_hole = hole.foveal.tessellation.z_t_far_m - hole.foveal.tessellation.z_t_near_m;
  CHECK(band_mapped < band_hole);
  // 0: every point at baseline_m.
  o.mapped_baseline_m = 0;
  const fovea::FixationResult same =
      fovea::Fixate(sim->rig(), fovea::PatchMap(), near_plane, matcher, o);
  CHECK(same.baseline_m == o.baseline_m);
}
