// IDR scored against ground truth (simulation only).
#pragma once

#include <nlohmann/json.hpp>

#include "fovea/idr.h"
#include "sim/ground_truth.h"

namespace experiments {

struct IdrScore {
  int patches = 0;
  double median_abs_error_m = 0;  ///< patch depth at its centre pixel vs true depth
  double median_error_steps = 0;  ///< same, in disparity-quantization steps Z^2 / (f B)
  /// Worst deviation, in px of disparity, of a patch's plane from the true
  /// surface at pixels of its footprint (a 5 x 5 grid) that show another
  /// surface than its centre does: how far patches straddle depth steps.
  double max_straddle_px = 0;
  int straddling_patches = 0;  ///< patches whose footprint covers two surfaces
  Eigen::Vector2d worst_straddle_uv = Eigen::Vector2d::Zero();  ///< where (left view pixel)
  /// Worst deviation over all footprint pixels (fit error included).
  double max_plane_deviation_px = 0;
  int patches_on_textureless = 0;  ///< patches whose centre shows an untextured surface
  int matches = 0;                 ///< final-stage crossing matches
  int wrong_matches = 0;           ///< off the true disparity by more than 1 px
  double stage0_unambiguous_share = 0;
};

/// Scores the final stage of an IDR run.
IdrScore ScoreIdr(const fovea::IdrResult& result, const sim::GroundTruth& truth);

nlohmann::json IdrJson(const fovea::IdrResult& result, const IdrScore& score);

}  // namespace experiments
