// fovea report: one self-contained HTML page (pictures embedded, plots drawn
// by gnuplot as inline SVG) for a run folder or a sweep folder.
#pragma once

#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

namespace experiments {

/// One curve of a plot: a title and its points.
struct Series {
  explicit Series(std::string title_) : title(std::move(title_)) {}
  std::string title;
  std::vector<double> x, y;
  std::vector<double> y_lo, y_hi;  ///< optional error bars (same length as y)
  bool dashed = false;
};

/// A plot drawn by gnuplot (`gnuplot` on the PATH) as SVG text. Throws
/// std::runtime_error when gnuplot is missing or fails.
std::string GnuplotSvg(const std::string& title, const std::string& xlabel,
                       const std::string& ylabel, const std::vector<Series>& series,
                       bool log_y = false);

/// The same plot as a PNG picture at `path` (written whole or not at all).
void GnuplotPng(const std::string& path, const std::string& title, const std::string& xlabel,
                const std::string& ylabel, const std::vector<Series>& series, bool log_y = false);

/// The number at a dotted path of a summary.json ("patch_3d_error.p90_m");
/// NaN where the path is missing or its value is not a number (null).
double SummaryNumber(const nlohmann::json& summary, const std::string& dotted);

/// One finished run of a sweep folder: its id, the sweep's variant ("fovea"
/// or a baseline), its scene as the run's configuration gives it, its point
/// of the grid (axis -> value) and its summary.json.
struct SweepRow {
  std::string id, variant, scene;
  std::map<std::string, std::string> point;
  nlohmann::json summary;
};

/// The finished runs of sweep folder `dir`, in the order of its grid.json
/// (`grid`, read); the runs without a summary.json are counted in `missing`.
std::vector<SweepRow> SweepRows(const std::string& dir, const nlohmann::json& grid, int* missing);

/// Writes DIR/report.html for a run folder (summary.json) or a sweep folder
/// (grid.json and results.csv); returns its path. Throws UsageError when DIR
/// is neither.
std::string WriteReport(const std::string& dir);

}  // namespace experiments
