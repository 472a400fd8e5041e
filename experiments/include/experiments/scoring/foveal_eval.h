// A fixation's foveated stereo scored against ground truth (simulation only).
#pragma once

#include <nlohmann/json.hpp>
#include <vector>

#include "fovea/foveal.h"
#include "sim/ground_truth.h"

namespace experiments {

struct LevelScore {
  int level = 0;
  int patches = 0;
  double median_abs_error_m = 0;         ///< patch depth at its centre pixel vs true depth
  double median_error_steps = 0;         ///< in this level's quantization step 2^k Z^2 / (f B)
  double median_disparity_error_px = 0;  ///< per-pixel disparities vs truth, level pixels
  int gross_errors = 0;                  ///< patches off by more than 5% of the true depth
};

struct FovealScore {
  std::vector<LevelScore> levels;
  /// Share of the fovea's textured, unmasked pixels that got a disparity.
  double fovea_coverage = 0;
  double baseline_m = 0;
};

FovealScore ScoreFoveal(const fovea::FixationResult& result, const sim::GroundTruth& truth);

nlohmann::json FixationJson(const fovea::FixationResult& result, const FovealScore& score);

/// The fovea's figures as a record's and fixate.json's "fovea" object
/// (angles in degrees).
nlohmann::json FoveaJson(const fovea::FoveaFigures& fovea);

}  // namespace experiments
