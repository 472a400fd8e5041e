// Parameter sweeps: a sweep file (a base config and axes) expands to a grid
// of runs, each named by the hash of its full configuration; results are
// gathered into one tidy CSV.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "experiments/config/config.h"

namespace experiments {

/// One swept parameter and its values, as text (as in the YAML file).
struct SweepAxis {
  std::string path;
  std::vector<std::string> values;
};

/// One run of the grid.
struct SweepRun {
  std::string id;       ///< ConfigHash of `config`: the run's folder name
  std::string variant;  ///< "fovea", or a baseline: "deterministic", "static_sgbm"
  RunConfig config;
  std::vector<std::pair<std::string, std::string>> point;  ///< axis path -> value
};

struct Sweep {
  std::string file;
  std::vector<SweepAxis> axes;
  std::vector<std::string> baselines;
  int jobs = 0;                ///< 0 = every local core
  std::vector<SweepRun> runs;  ///< grid order (last axis fastest), then baselines; no two alike
};

/// The most runs one sweep may hold, baselines included: a grid past it is
/// refused (split it). Setting it up takes about a second per thousand runs.
constexpr long kMaxSweepRuns = 10000;

/// Reads and checks a sweep file: every run's configuration is built and
/// checked, so nothing starts unless all are valid. Throws UsageError
/// ("sweep FILE: ...") naming the key.
Sweep LoadSweep(const std::string& path);

/// The same for the text of a sweep file at `path` (a base config named in
/// it is read relative to the folder of `path`).
Sweep ParseSweep(const std::string& text, const std::string& path);

/// The grid as written to DIR/grid.json: axes, and per run its id, variant,
/// point and every parameter's value. Identical for every shard.
nlohmann::json GridJson(const Sweep& sweep);

/// Names of the summary.json figures that are wall-clock times (they differ
/// between otherwise identical runs): wall_time_s, compute_time_s, time_s.*.
bool IsWallClockColumn(const std::string& column);

/// The tidy CSV of a sweep folder: a row per finished run in grid order
/// (run_id, variant, every parameter, every figure of its summary.json).
/// Runs without a result are listed in `*missing`.
std::string ResultsCsv(const std::string& dir, const nlohmann::json& grid,
                       std::vector<std::string>* missing);

/// Parses "I/N" (1 <= I <= N); throws UsageError.
std::pair<int, int> ParseShard(const std::string& text);

/// Reads a whole JSON file; throws std::runtime_error naming it.
nlohmann::json ReadJson(const std::string& path);

/// Reads DIR/grid.json and checks that it has the shape GridJson writes
/// (axes, baselines, at least one run, each with an id that names a folder
/// inside DIR/runs, a variant, a point and its parameters), so that what
/// reads it meets no surprise; throws std::runtime_error naming the file and
/// the first thing wrong.
nlohmann::json ReadGridJson(const std::string& dir);

}  // namespace experiments
