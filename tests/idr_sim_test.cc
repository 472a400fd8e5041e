// IDR end to end on the simulated rig, with sensor noise on, scored against
// ground truth. Slow: labelled [slow].
#include <catch2/catch.hpp>

#include "experiments/config/config.h"
#include "experiments/scoring/idr_eval.h"
#include "scenes/catalog.h"

namespace {

struct Run {
  fovea::IdrResult result;
  experiments::IdrScore score;
};

Run RunOn(const std::string& scene, const fovea::IdrOptions& options = {}) {
  sim::SimRigConfig config;
  config.noise.read_noise_sigma_dn = experiments::kExperimentNoiseSigmaDn;
  config.seed = 11;
  auto sim = scenes::LoadScene(scene, config);
  Run r;
  r.result = fovea::RunIdr(sim->rig(), options);
  r.score = experiments::ScoreIdr(r.result, sim->truth());
  return r;
}

}  // namespace

TEST_CASE("IDR on the step scenes: unambiguous start, sub-step depth, no straddling",
          "[idr][slow]") {
  const fovea::IdrOptions options;
  for (const std::string scene : {"fronto_planes", "two_planes", "periodic"}) {
    INFO(scene);
    const Run r = RunOn(scene, options);
    REQUIRE_FALSE(r.result.stages.empty());
    // Measured from the matches at B0, not assumed from the histogram.
    CHECK(r.score.stage0_unambiguous_share >= 0.90);
    CHECK(r.score.patches > 200);
    // Median patch depth error below one quantization step Z^2 / (f B).
    CHECK(r.score.median_error_steps < 1.0);
    // No patch reaches over a depth step by more than the fit tolerance.
    CHECK(r.score.max_straddle_px <= options.plane_fit.fit_tolerance_px);
    CHECK(r.result.has_fixation);
    // Every stage is recorded for the harness.
    for (const auto& s : r.result.stages) {
      CHECK(s.baseline_m > 0);
      CHECK(s.stats.left_crossings > 0);
    }
    CHECK(r.result.stages.back().baseline_m > r.result.stages.front().baseline_m);
  }
}

TEST_CASE("periodic texture: the period rule avoids the wrong matches a fixed baseline makes",
          "[idr][slow]") {
  // Both runs take the nearest candidate when a window is ambiguous, as a
  // classic matcher does: only the baseline rule differs.
  fovea::IdrOptions adaptive;
  adaptive.matching.take_nearest_when_ambiguous = true;
  fovea::IdrOptions fixed = adaptive;
  fixed.fixed_initial_baseline_m = 0.03;  // disparity about two periods at 0.87 m
  const Run a = RunOn("periodic", adaptive), f = RunOn("periodic", fixed);
  INFO("adaptive wrong " << a.score.wrong_matches << "/" << a.score.matches << ", fixed wrong "
                         << f.score.wrong_matches << "/" << f.score.matches);
  REQUIRE(a.score.matches > 1000);
  REQUIRE(f.score.matches > 1000);
  CHECK(a.score.wrong_matches < 0.001 * a.score.matches);
  CHECK(f.score.wrong_matches > 0.5 * f.score.matches);
  CHECK(f.score.median_error_steps > 10);
  // With FOVEA's own policy the fixed baseline is not wrong but useless: its
  // windows are ambiguous.
  fovea::IdrOptions reject;
  reject.fixed_initial_baseline_m = 0.03;
  const Run r = RunOn("periodic", reject);
  CHECK(r.score.stage0_unambiguous_share < 0.1);
}

TEST_CASE("textureless regions get no patches and cause no error", "[idr][slow]") {
  const Run r = RunOn("textureless");
  CHECK(r.score.patches > 50);  // the textured wall
  CHECK(r.score.patches_on_textureless == 0);
}
