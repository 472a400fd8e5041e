// fovea compare: two sweeps' runs paired by scene and seed, and the figures
// the accuracy benchmark judges a choice by (issue 19), before and after.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace experiments {

/// One finished run of a sweep: its scene (a catalog name, "random:N", or a
/// scene file's stem), seed and method (the sweep's variant: "fovea", or a
/// baseline, "deterministic" or "static_sgbm"), and its summary.json.
struct RunSummary {
  std::string scene, method;
  long long seed = 0;
  nlohmann::json summary;
};

/// The finished runs of sweep folder `dir` (its grid.json; runs without a
/// summary.json are left out, and counted in `unfinished` if given). Throws
/// UsageError when `dir` is not a sweep folder.
std::vector<RunSummary> SweepSummaries(const std::string& dir, int* unfinished = nullptr);

/// The scenes whose coverage issue 19 holds to the catalog's line: the
/// three DDR catalog scenes.
bool IsDdrCatalogScene(const std::string& scene);

/// One summary figure over the pairs: each side's mean, and the mean of the
/// per-pair change (variant - base) with its standard error and how many
/// pairs went up and down. Pairs where either side's figure is null are
/// left out of all of it (`pairs` counts the rest); means are NaN without
/// any.
struct PairedFigure {
  std::string key;
  int pairs = 0;
  double base_mean = 0, variant_mean = 0, change = 0, change_se = 0;
  int up = 0, down = 0;
};

/// Issue 19's lines over one side's paired runs.
struct SetLines {
  int runs_under_good_coverage = 0;  ///< good_coverage < kGoodCoverageFloor
  int catalog_coverage_misses = 0;   ///< catalog runs with coverage < kCatalogCoverage
  int other_coverage_misses = 0;     ///< other runs with coverage < kOtherCoverage
  double max_edge_bad_share = 0, max_catalog_rmse_m = 0, max_median_rel_error = 0,
         max_patch_p90_m = 0;  ///< over the runs that report them (0: none)
  double refused_share = 0;    ///< refused attempts over all attempts
  long long stale_idr_patches = 0;
};
constexpr double kGoodCoverageFloor = 0.80, kCatalogCoverage = 0.95, kOtherCoverage = 0.90;

/// One scene's mean good_coverage over its paired seeds, each side.
struct ScenePair {
  std::string scene;
  int pairs = 0;
  double base_good_coverage = 0, variant_good_coverage = 0;
};

struct Comparison {
  std::string method;
  int pairs = 0;
  int base_only = 0, variant_only = 0;  ///< runs of `method` with no partner
  /// Runs of either sweep's grid without a summary.json (not finished: any
  /// method), set by the caller from SweepSummaries; the text names them.
  int base_unfinished = 0, variant_unfinished = 0;
  std::vector<PairedFigure> figures;
  SetLines base, variant;
  std::vector<ScenePair> scenes;  ///< in the base sweep's order
};

/// Pairs the runs of `method` of the two sweeps by scene and seed. Throws
/// UsageError when either side holds two runs of `method` with the same
/// scene and seed (the pairing would be ambiguous).
Comparison Compare(const std::vector<RunSummary>& base, const std::vector<RunSummary>& variant,
                   const std::string& method);

/// The comparison as text tables (for a terminal) and as one JSON object.
std::string ComparisonText(const Comparison& c);
nlohmann::json ComparisonJson(const Comparison& c);

}  // namespace experiments
