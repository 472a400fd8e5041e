#include "experiments/output/report.h"

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "experiments/config/config.h"
#include "experiments/config/sweep.h"
#include "experiments/output/output.h"
#include "experiments/output/run_folder.h"

namespace experiments {
namespace fs = std::filesystem;

double SummaryNumber(const nlohmann::json& summary, const std::string& dotted) {
  const nlohmann::json* p = &summary;
  std::stringstream ss(dotted);
  std::string part;
  while (std::getline(ss, part, '.')) {
    if (!p->is_object() || !p->contains(part)) return std::nan("");
    p = &(*p)[part];
  }
  return p->is_number() ? p->get<double>() : std::nan("");
}

namespace {

std::string Base64(const std::string& bytes) {
  static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const unsigned v = (unsigned char)bytes[i] << 16 | (unsigned char)bytes[i + 1] << 8 |
                       (unsigned char)bytes[i + 2];
    out += {k[v >> 18], k[(v >> 12) & 63], k[(v >> 6) & 63], k[v & 63]};
  }
  if (i + 1 == bytes.size()) {
    const unsigned v = (unsigned char)bytes[i] << 16;
    out += {k[v >> 18], k[(v >> 12) & 63], '=', '='};
  } else if (i + 2 == bytes.size()) {
    const unsigned v = (unsigned char)bytes[i] << 16 | (unsigned char)bytes[i + 1] << 8;
    out += {k[v >> 18], k[(v >> 12) & 63], k[(v >> 6) & 63], '='};
  }
  return out;
}

std::string Html(const std::string& s) {
  std::string o;
  for (const char c : s) {
    if (c == '<')
      o += "&lt;";
    else if (c == '>')
      o += "&gt;";
    else if (c == '&')
      o += "&amp;";
    else
      o += c;
  }
  return o;
}

// gnuplot strings are single-quoted: double any quote.
std::string Quoted(const std::string& s) {
  std::string o = "'";
  for (const char c : s) o += c == '\'' ? std::string("''") : std::string(1, c);
  return o + "'";
}

std::string Img(const std::string& path, const std::string& alt) {
  return "<figure><img src=\"data:image/png;base64," + Base64(ReadFile(path)) + "\" alt=\"" +
         Html(alt) + "\"><figcaption>" + Html(alt) + "</figcaption></figure>\n";
}

std::string Fmt(double v, const char* f = "%.4g") {
  char buf[48];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

const char* kStyle =
    "<style>body{font-family:sans-serif;margin:2em;max-width:1400px;color:#222}"
    "table{border-collapse:collapse;font-size:13px}td,th{border:1px solid #ccc;padding:3px "
    "8px;text-align:right}"
    "th{background:#f0f0f0}td.l,th.l{text-align:left}img{max-width:100%}figure{margin:1em 0}"
    "figcaption{font-size:13px;color:#555}.plots{display:flex;flex-wrap:wrap;gap:1em}"
    "h2{border-bottom:1px solid #ddd;padding-bottom:4px}</style>\n";

// A figure per row of `rows` (summary key, label) that the summary holds.
std::string FigureTable(const nlohmann::json& s,
                        const std::vector<std::pair<std::string, std::string>>& rows) {
  std::string h = "<table>";
  for (const auto& [key, label] : rows) {
    const double v = SummaryNumber(s, key);
    if (std::isfinite(v))
      h += "<tr><th class=l>" + Html(label) + "</th><td>" + Fmt(v) + "</td></tr>";
  }
  return h + "</table>\n";
}

// The run's figures by resolution level and by surface.
std::string LevelAndSurfaceTables(const nlohmann::json& s) {
  std::string h;
  if (s.contains("by_level")) {
    h += "<h3>By level</h3><table><tr><th class=l>level</th><th>share</th><th>median error, "
         "m</th><th>median "
         "error, steps</th><th>RMSE, m</th></tr>";
    for (auto it = s["by_level"].begin(); it != s["by_level"].end(); ++it)
      h += "<tr><td class=l>" + it.key() + "</td><td>" + Fmt(SummaryNumber(it.value(), "share")) +
           "</td><td>" + Fmt(SummaryNumber(it.value(), "median_abs_error_m")) + "</td><td>" +
           Fmt(SummaryNumber(it.value(), "median_error_steps")) + "</td><td>" +
           Fmt(SummaryNumber(it.value(), "rmse_m")) + "</td></tr>";
    h += "</table>\n";
  }
  if (s.contains("by_surface")) {
    h += "<h3>By surface</h3><table><tr><th "
         "class=l>surface</th><th>pixels</th><th>coverage</th><th>foveal</th>"
         "<th>median error, m</th></tr>";
    for (auto it = s["by_surface"].begin(); it != s["by_surface"].end(); ++it)
      h += "<tr><td class=l>" + Html(it.key()) + "</td><td>" +
           Fmt(SummaryNumber(it.value(), "pixels"), "%.0f") + "</td><td>" +
           Fmt(SummaryNumber(it.value(), "coverage")) + "</td><td>" +
           Fmt(SummaryNumber(it.value(), "foveal_coverage")) + "</td><td>" +
           Fmt(SummaryNumber(it.value(), "median_abs_error_m")) + "</td></tr>";
    h += "</table>\n";
  }
  return h;
}

// Curves against fixation count, from the per-fixation records.
std::string FixationCurves(const std::string& dir) {
  Series cov{"coverage"}, fov{"foveal coverage"}, med{"median |error|"}, rmse{"RMSE"};
  std::ifstream in(dir + "/" + run_folder::kRecords);
  for (std::string line; std::getline(in, line);) {
    if (line.empty()) continue;
    const nlohmann::json r = nlohmann::json::parse(line);
    if (!r.value("ok", false)) continue;
    const double f = r.at("fixation").get<double>();
    const nlohmann::json& sc = r.at("score");
    cov.x.push_back(f), cov.y.push_back(SummaryNumber(sc, "coverage"));
    fov.x.push_back(f), fov.y.push_back(SummaryNumber(sc, "foveal_coverage"));
    med.x.push_back(f), med.y.push_back(1e3 * SummaryNumber(sc, "median_abs_error_m"));
    rmse.x.push_back(f), rmse.y.push_back(1e3 * SummaryNumber(sc, "rmse_m"));
  }
  if (cov.x.empty()) return "";
  return "<h2>Against fixation count</h2><div class=plots>" +
         GnuplotSvg("Coverage of the reference view", "fixation",
                    "share of visible textured pixels", {cov, fov}) +
         GnuplotSvg("Depth error", "fixation", "mm", {med, rmse}, true) + "</div>\n";
}

std::string RunPictures(const std::string& dir) {
  std::string h = "<h2>Pictures</h2>\n";
  for (const int k : run_folder::kSnapshotFixations) {
    const std::string name = dir + "/" + run_folder::SnapshotName(k);
    if (fs::exists(name)) h += Img(name, "the map after fixation " + std::to_string(k));
  }
  const std::pair<const char*, const char*> more[] = {
      {run_folder::kMapPicture, "the map"},
      {run_folder::kFixationPath, "the fixation path"},
      {run_folder::kErrorPicture,
       "where the map is right (green), too near (red) and too far (magenta)"}};
  for (const auto& [file, alt] : more)
    if (fs::exists(dir + "/" + file)) h += Img(dir + "/" + file, alt);
  return h;
}

std::string RunReport(const std::string& dir) {
  const nlohmann::json s = ReadJson(dir + "/" + run_folder::kSummary);
  std::string h =
      "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>FOVEA run: " + Html(dir) +
      "</title>" + kStyle + "</head><body>\n";
  h += "<h1>FOVEA run</h1><p>Folder <code>" + Html(dir) + "</code>, scene <code>" +
       Html(s.value("scene", std::string())) + "</code>, seed " +
       s.value("seed", nlohmann::json(0)).dump() + ", method " +
       Html(s.value("method", std::string("fovea"))) + ".</p>\n";
  h += "<h2>Figures</h2>" +
       FigureTable(s, {{"fixations", "fixations done"},
                       {"coverage", "coverage of visible textured pixels"},
                       {"foveal_coverage", "share mapped at foveal resolution"},
                       {"median_abs_error_m", "median |depth error|, m"},
                       {"median_rel_error", "median relative error"},
                       {"median_error_steps", "median error, disparity steps"},
                       {"rmse_m", "RMSE, m"},
                       {"within_1pct", "share within 1% of depth"},
                       {"patch_3d_error.median_m", "median per-patch 3D error, m"},
                       {"motion_time_s", "simulated motion time, s"},
                       {"compute_time_s", "compute time, s"},
                       {"wall_time_s", "wall time, s"}});
  h += LevelAndSurfaceTables(s) + FixationCurves(dir) + RunPictures(dir);
  return h + "</body></html>\n";
}

}  // namespace

std::vector<SweepRow> SweepRows(const std::string& dir, const nlohmann::json& grid, int* missing) {
  std::vector<SweepRow> rows;
  for (const auto& run : grid.at("runs")) {
    const std::string id = run.at("id").get<std::string>();
    const std::string summary = dir + "/runs/" + id + "/" + run_folder::kSummary;
    if (!fs::exists(summary)) {
      ++*missing;
      continue;
    }
    SweepRow r{id, run.at("variant").get<std::string>(), "", {}, ReadJson(summary)};
    for (auto it = run.at("point").begin(); it != run.at("point").end(); ++it)
      r.point[it.key()] = it.value();
    for (const auto& p : run.at("config"))
      if (p.at(0) == "scene") r.scene = p.at(1).get<std::string>();
    rows.push_back(r);
  }
  return rows;
}

namespace {

// The figures a sweep report plots and tabulates.
const std::vector<std::pair<std::string, std::string>>& SweepFigures() {
  static const std::vector<std::pair<std::string, std::string>> kFigures = {
      {"coverage", "coverage"},
      {"good_coverage", "good coverage"},
      {"edge_bad_share", "bad share near edges"},
      {"foveal_coverage", "foveal coverage"},
      {"fovea.image_share.median", "fovea's image share (median)"},
      {"median_abs_error_m", "median |depth error|, m"},
      {"median_rel_error", "median relative error"},
      {"rmse_m", "RMSE, m"},
      {"motion_time_s", "simulated motion time, s"},
      {"wall_time_s", "wall time, s"}};
  return kFigures;
}

// One figure against a numeric axis: a line per scene and variant (the mean
// over the other axes, bars from smallest to largest), dashed lines for the
// runs that do not depend on the axis.
std::vector<Series> FigureSeries(const std::vector<SweepRow>& rows, const std::string& path,
                                 const std::string& key, double x_min, double x_max) {
  std::map<std::pair<std::string, std::string>, std::map<double, std::vector<double>>> groups;
  std::map<std::pair<std::string, std::string>, std::vector<double>> flat;
  for (const SweepRow& r : rows) {
    const double v = SummaryNumber(r.summary, key);
    if (!std::isfinite(v)) continue;
    const auto it = r.point.find(path);
    if (it != r.point.end())
      groups[{r.scene, r.variant}][std::strtod(it->second.c_str(), nullptr)].push_back(v);
    else
      flat[{r.scene, r.variant}].push_back(v);
  }
  auto mean = [](const std::vector<double>& vs) {
    double sum = 0;
    for (const double v : vs) sum += v;
    return sum / vs.size();
  };
  std::vector<Series> series;
  for (const auto& [g, by_x] : groups) {
    Series s{g.first + ", " + g.second};
    for (const auto& [x, vs] : by_x) {
      s.x.push_back(x);
      s.y.push_back(mean(vs));
      s.y_lo.push_back(*std::min_element(vs.begin(), vs.end()));
      s.y_hi.push_back(*std::max_element(vs.begin(), vs.end()));
    }
    series.push_back(s);
  }
  for (const auto& [g, vs] : flat) {
    Series s{g.first + ", " + g.second};
    s.x = {x_min, x_max};
    s.y = {mean(vs), mean(vs)};
    s.dashed = true;
    series.push_back(s);
  }
  return series;
}

// Every figure against every numeric axis but scene and seed.
std::string AxisPlots(const nlohmann::json& grid, const std::vector<SweepRow>& rows) {
  std::string h;
  for (const auto& a : grid.at("axes")) {
    const std::string path = a.at("path").get<std::string>();
    if (path == "scene" || path == "seed") continue;
    std::vector<double> xs;
    for (const auto& v : a.at("values")) {
      const std::optional<double> x = ParseNumber(v.get<std::string>());
      if (!x) break;
      xs.push_back(*x);
    }
    if (xs.size() < 2 || xs.size() != a.at("values").size()) continue;
    const double x_min = *std::min_element(xs.begin(), xs.end()),
                 x_max = *std::max_element(xs.begin(), xs.end());
    h += "<h2>Against <code>" + Html(path) +
         "</code></h2><p>A line per scene and variant: the mean over the other axes (seeds, ...), "
         "bars from the "
         "smallest to the largest value. Baselines that do not depend on this parameter are dashed "
         "horizontal "
         "lines.</p><div class=plots>\n";
    for (const auto& [key, label] : SweepFigures()) {
      const std::vector<Series> series = FigureSeries(rows, path, key, x_min, x_max);
      if (!series.empty()) h += GnuplotSvg(label, path, label, series);
    }
    h += "</div>\n";
  }
  return h;
}

std::string RunsTable(const nlohmann::json& grid, const std::vector<SweepRow>& rows) {
  std::string h = "<h2>Runs</h2><table><tr><th class=l>run</th><th class=l>variant</th>";
  for (const auto& a : grid.at("axes"))
    h += "<th class=l>" + Html(a.at("path").get<std::string>()) + "</th>";
  for (const auto& [key, label] : SweepFigures()) h += "<th>" + Html(label) + "</th>";
  h += "</tr>\n";
  for (const SweepRow& r : rows) {
    h += "<tr><td class=l><a href=\"runs/" + r.id + "/\">" + r.id + "</a></td><td class=l>" +
         r.variant + "</td>";
    for (const auto& a : grid.at("axes")) {
      const auto it = r.point.find(a.at("path").get<std::string>());
      h += "<td class=l>" + (it == r.point.end() ? std::string("(base)") : Html(it->second)) +
           "</td>";
    }
    for (const auto& [key, label] : SweepFigures())
      h += "<td>" + Fmt(SummaryNumber(r.summary, key)) + "</td>";
    h += "</tr>\n";
  }
  return h + "</table>";
}

// The trust figures per scene: each variant's mean over its runs (seeds and
// any other axes), FOVEA and the static pair side by side, and the
// comparison on the pixels both map.
std::string SceneTable(const std::vector<SweepRow>& rows) {
  static const std::vector<std::pair<std::string, std::string>> kColumns = {
      {"coverage", "coverage"},
      {"good_coverage", "good coverage (within 1%)"},
      {"bad_share", "bad share"},
      {"edge_bad_share", "bad share near edges"},
      {"edge_good_coverage", "good coverage near edges"},
      {"median_abs_error_m", "median |error|, mm"},
      {"median_rel_error", "median rel. error, %"},
      {"rmse_m", "RMSE, mm"},
      {"patch_3d_error.p90_m", "patch 3D error p90, mm"},
      {"stale_idr_patches", "stale IDR patches"},
      {"foveal_coverage", "foveal coverage"},
      {"fovea.image_share.median", "fovea's image share (median)"},
      {"fovea.under_32px", "foveas under 32 px"},
      {"refused_share", "refused share of attempts"},
      {"vs_static.fovea_median_abs_error_m", "common pixels: FOVEA median, mm"},
      {"vs_static.static_median_abs_error_m", "common pixels: static median, mm"}};
  auto value = [](const nlohmann::json& s, const std::string& key) {
    if (key == "refused_share")
      return SummaryNumber(s, "refused") / std::max(1.0, SummaryNumber(s, "attempts"));
    const double v = SummaryNumber(s, key);
    const bool metres = key.size() > 2 && key.compare(key.size() - 2, 2, "_m") == 0;
    return key == "median_rel_error" ? 100 * v : metres ? 1000 * v : v;
  };
  std::map<std::string, std::map<std::string, std::vector<const SweepRow*>>> by_scene;
  std::vector<std::string> scenes;
  for (const SweepRow& r : rows) {
    if (!by_scene.count(r.scene)) scenes.push_back(r.scene);
    by_scene[r.scene][r.variant].push_back(&r);
  }
  std::string h =
      "<h2>By scene</h2><p>Each variant's mean over its runs. Good coverage: the share of the "
      "reference view's visible textured pixels mapped within 1% of their true depth; bad share: "
      "of the mapped pixels, those off by more; near edges: within 8 px of a true depth jump of "
      "more than 2 cm. The last two columns compare the FOVEA map with the static pair's on the "
      "pixels both map.</p><table><tr><th class=l>scene</th><th class=l>variant</th><th>runs</th>";
  for (const auto& [key, label] : kColumns) h += "<th>" + Html(label) + "</th>";
  h += "</tr>\n";
  int wins = 0, compared = 0;
  for (const std::string& scene : scenes)
    for (const auto& [variant, runs] : by_scene[scene]) {
      h += "<tr><td class=l>" + Html(fs::path(scene).stem().string()) + "</td><td class=l>" +
           Html(variant) + "</td><td>" + std::to_string(runs.size()) + "</td>";
      std::map<std::string, double> mean;
      for (const auto& [key, label] : kColumns) {
        double sum = 0;
        int n = 0;
        for (const SweepRow* r : runs)
          if (const double v = value(r->summary, key); std::isfinite(v)) sum += v, ++n;
        mean[key] = n ? sum / n : std::nan("");
        h += "<td>" + (n ? Fmt(mean[key]) : std::string("-")) + "</td>";
      }
      h += "</tr>\n";
      const double f = mean["vs_static.fovea_median_abs_error_m"],
                   st = mean["vs_static.static_median_abs_error_m"];
      if (std::isfinite(f) && std::isfinite(st)) ++compared, wins += f <= st;
    }
  h += "</table>";
  if (compared)
    h += "<p>FOVEA's median error is at most the static pair's on the pixels both map on " +
         std::to_string(wins) + " of " + std::to_string(compared) + " scene rows.</p>";
  return h + "\n";
}

// ---- Strategies: coverage against fixations and motion --------------------

// One run's map after each attempt: fixations done, the loop's cumulative
// simulated motion, coverage and good coverage; the first point is IDR's map
// before any fixation.
struct CurvePoint {
  int fixations;
  double motion_s, coverage, good;
};

std::vector<CurvePoint> RunCurve(const std::string& run_dir, const nlohmann::json& summary) {
  std::vector<CurvePoint> c = {
      {0, 0, SummaryNumber(summary, "idr.coverage"), SummaryNumber(summary, "idr.good_coverage")}};
  std::ifstream in(run_dir + "/" + run_folder::kRecords);
  int done = 0;
  double motion = 0;
  for (std::string line; std::getline(in, line);) {
    if (line.empty()) continue;
    const nlohmann::json r = nlohmann::json::parse(line);
    motion += SummaryNumber(r, "motion_time_s");
    if (r.value("ok", false)) ++done;
    c.push_back({done, motion, SummaryNumber(r.at("score"), "coverage"),
                 SummaryNumber(r.at("score"), "good_coverage")});
  }
  return c;
}

// The map's figure (coverage or good) as it stood when `x` (fixations, or
// motion seconds) was reached: the last point at or before it.
double CurveAt(const std::vector<CurvePoint>& c, double x, bool by_motion, bool good) {
  double v = std::nan("");
  for (const CurvePoint& p : c) {
    if ((by_motion ? p.motion_s : p.fixations) > x) break;
    v = good ? p.good : p.coverage;
  }
  return v;
}

// Fixations (or motion seconds) when the figure first reached `level`; NaN if never.
double Reached(const std::vector<CurvePoint>& c, double level, bool by_motion, bool good) {
  for (const CurvePoint& p : c)
    if ((good ? p.good : p.coverage) >= level) return by_motion ? p.motion_s : p.fixations;
  return std::nan("");
}

struct Spread {
  double mean = std::nan(""), sd = std::nan("");
  int n = 0;
};

Spread SpreadOf(const std::vector<double>& v) {
  Spread s;
  double sum = 0, sum2 = 0;
  for (const double x : v)
    if (std::isfinite(x)) sum += x, sum2 += x * x, ++s.n;
  if (s.n == 0) return s;
  s.mean = sum / s.n;
  s.sd = s.n > 1 ? std::sqrt(std::max(0.0, (sum2 - s.n * s.mean * s.mean) / (s.n - 1))) : 0.0;
  return s;
}

// A strategy's runs.
struct StrategyRuns {
  std::vector<const SweepRow*> rows;
  std::vector<std::vector<CurvePoint>> curves;
};

std::string StrategySection(const std::string& dir, const std::vector<SweepRow>& rows) {
  static const char* kAxis = "selection.strategy";
  std::map<std::string, StrategyRuns> by;
  std::vector<std::string> order;
  int max_fixations = 0;
  double max_motion = 0;
  for (const SweepRow& r : rows) {
    const auto it = r.point.find(kAxis);
    if (it == r.point.end() || r.variant != "fovea") continue;
    if (!by.count(it->second)) order.push_back(it->second);
    StrategyRuns& s = by[it->second];
    s.rows.push_back(&r);
    s.curves.push_back(RunCurve(dir + "/runs/" + r.id, r.summary));
    max_fixations = std::max(max_fixations, s.curves.back().back().fixations);
    max_motion = std::max(max_motion, s.curves.back().back().motion_s);
  }
  if (order.empty()) return "";
  // Mean curves with a band of one standard deviation over the runs.
  auto curves = [&](bool by_motion, bool good) {
    std::vector<Series> series;
    const int steps = 20;
    const double x_max = by_motion ? max_motion : max_fixations;
    for (const std::string& name : order) {
      Series s{name};
      for (int k = 0; k <= steps; ++k) {
        const double x = x_max * k / steps;
        std::vector<double> v;
        for (const auto& c : by[name].curves) v.push_back(CurveAt(c, x, by_motion, good));
        const Spread sp = SpreadOf(v);
        s.x.push_back(x);
        s.y.push_back(sp.mean);
        s.y_lo.push_back(sp.mean - sp.sd);
        s.y_hi.push_back(sp.mean + sp.sd);
      }
      series.push_back(s);
    }
    return series;
  };
  std::string plots;
  const struct {
    bool by_motion, good;
    const char *file, *title, *xlabel;
  } kPlots[] = {{false, false, "strategies_coverage_vs_fixations.png", "Coverage against fixations",
                 "fixations"},
                {false, true, "strategies_good_vs_fixations.png", "Good coverage against fixations",
                 "fixations"},
                {true, false, "strategies_coverage_vs_motion.png", "Coverage against motion time",
                 "simulated motion of the fixation loop, s"},
                {true, true, "strategies_good_vs_motion.png", "Good coverage against motion time",
                 "simulated motion of the fixation loop, s"}};
  for (const auto& p : kPlots) {
    const std::vector<Series> series = curves(p.by_motion, p.good);
    const std::string ylabel = p.good ? "good coverage" : "coverage";
    plots += GnuplotSvg(p.title, p.xlabel, ylabel, series);
    // Also a picture of its own, for pages that show pictures (the README).
    GnuplotPng(dir + "/" + p.file, p.title, p.xlabel, ylabel, series);
  }
  // The table: a row per strategy, means over its runs.
  struct Column {
    std::string label;
    std::function<double(const SweepRow&, const std::vector<CurvePoint>&)> value;
  };
  std::vector<Column> columns;
  constexpr size_t kReachColumns = 8;  // the first columns: when a level was reached
  for (const bool good : {false, true})
    for (const double level : {0.90, 0.95})
      for (const bool by_motion : {false, true})
        columns.push_back({std::string(by_motion ? "motion s" : "fixations") + " to " +
                               Fmt(100 * level, "%.0f") + "% " +
                               (good ? "good coverage" : "coverage"),
                           [=](const SweepRow&, const std::vector<CurvePoint>& c) {
                             return Reached(c, level, by_motion, good);
                           }});
  columns.push_back({"final coverage", [](const SweepRow& r, const std::vector<CurvePoint>&) {
                       return SummaryNumber(r.summary, "coverage");
                     }});
  columns.push_back({"final good coverage", [](const SweepRow& r, const std::vector<CurvePoint>&) {
                       return SummaryNumber(r.summary, "good_coverage");
                     }});
  columns.push_back({"fixations done", [](const SweepRow& r, const std::vector<CurvePoint>&) {
                       return SummaryNumber(r.summary, "fixations");
                     }});
  columns.push_back({"refused share", [](const SweepRow& r, const std::vector<CurvePoint>&) {
                       return SummaryNumber(r.summary, "refused") /
                              std::max(1.0, SummaryNumber(r.summary, "attempts"));
                     }});
  columns.push_back(
      {"motion s per fixation", [](const SweepRow& r, const std::vector<CurvePoint>&) {
         return SummaryNumber(r.summary, "travel.motion_time_s") /
                std::max(1.0, SummaryNumber(r.summary, "fixations"));
       }});
  columns.push_back({"pan deg per fixation", [](const SweepRow& r, const std::vector<CurvePoint>&) {
                       return SummaryNumber(r.summary, "travel.pan_deg") /
                              std::max(1.0, SummaryNumber(r.summary, "fixations"));
                     }});
  columns.push_back(
      {"tilt deg per fixation", [](const SweepRow& r, const std::vector<CurvePoint>&) {
         return SummaryNumber(r.summary, "travel.tilt_deg") /
                std::max(1.0, SummaryNumber(r.summary, "fixations"));
       }});
  columns.push_back(
      {"carriage mm per fixation", [](const SweepRow& r, const std::vector<CurvePoint>&) {
         return 1e3 * SummaryNumber(r.summary, "travel.carriage_m") /
                std::max(1.0, SummaryNumber(r.summary, "fixations"));
       }});
  columns.push_back(
      {"selection ms per fixation", [](const SweepRow& r, const std::vector<CurvePoint>&) {
         return 1e3 * SummaryNumber(r.summary, "time_s.select") /
                std::max(1.0, SummaryNumber(r.summary, "fixations"));
       }});
  std::string html =
      "<h2>Strategies</h2><p>Means over each strategy's runs (every scene and seed); for the "
      "figures to reach a level, the median over all its runs (a run that never reached the "
      "level counts as beyond the end: \"never\" when half of them did not), and how many "
      "reached it. Motion "
      "is the fixation loop's simulated motion (IDR's, the same for every strategy, left out). "
      "Curves: the mean with a band of one standard deviation over the runs.</p><table><tr><th "
      "class=l>strategy</th><th>runs</th>";
  std::string md = "| strategy | runs |";
  std::string md_rule = "|---|---|";
  for (const Column& c : columns) {
    html += "<th>" + Html(c.label) + "</th>";
    md += " " + c.label + " |";
    md_rule += "---|";
  }
  html += "</tr>\n";
  md += "\n" + md_rule + "\n";
  for (const std::string& name : order) {
    const StrategyRuns& s = by[name];
    const std::string n = std::to_string(s.rows.size());
    html += "<tr><td class=l>" + Html(name) + "</td><td>" + n + "</td>";
    md += "| " + name + " | " + n + " |";
    for (size_t k = 0; k < columns.size(); ++k) {
      std::vector<double> v;
      for (size_t i = 0; i < s.rows.size(); ++i)
        v.push_back(columns[k].value(*s.rows[i], s.curves[i]));
      const Spread sp = SpreadOf(v);
      std::string cell = sp.n ? Fmt(sp.mean, "%.3g") : std::string("-");
      if (k < kReachColumns) {
        // The median over every run, a run that never reached the level
        // counting as beyond the end (a mean over the runs that reached it
        // would favour a strategy that reaches it rarely).
        for (double& x : v)
          if (!std::isfinite(x)) x = std::numeric_limits<double>::infinity();
        std::sort(v.begin(), v.end());
        const double median = v.empty() ? std::nan("") : v[(v.size() - 1) / 2];
        cell = (std::isfinite(median) ? Fmt(median, "%.3g") : std::string("never")) + " (" +
               std::to_string(sp.n) + "/" + n + ")";
      }
      html += "<td>" + Html(cell) + "</td>";
      md += " " + cell + " |";
    }
    html += "</tr>\n";
    md += "\n";
  }
  html += "</table>\n";
  // Seed-to-seed spread against the difference between strategies, per scene:
  // each scene's standard deviation over seeds, averaged over scenes.
  std::string spread =
      "<h3>Seed-to-seed spread</h3><p>Per scene: the mean and the standard deviation over seeds; "
      "averaged over scenes. A difference between two strategies smaller than the spread is "
      "not one.</p><table><tr><th class=l>strategy</th><th>final coverage</th><th>sd over "
      "seeds</th><th>final good coverage</th><th>sd over seeds</th><th>fixations to 95% "
      "coverage (runs that reached it)</th><th>sd over seeds</th></tr>\n";
  std::string md_spread =
      "\n| strategy | final coverage | sd over seeds | final good coverage | sd over seeds | "
      "fixations to 95% coverage | sd over seeds |\n|---|---|---|---|---|---|---|\n";
  for (const std::string& name : order) {
    const StrategyRuns& s = by[name];
    std::map<std::string, std::array<std::vector<double>, 3>> per_scene;
    for (size_t i = 0; i < s.rows.size(); ++i) {
      auto& v = per_scene[s.rows[i]->scene];
      v[0].push_back(SummaryNumber(s.rows[i]->summary, "coverage"));
      v[1].push_back(SummaryNumber(s.rows[i]->summary, "good_coverage"));
      v[2].push_back(Reached(s.curves[i], 0.95, false, false));
    }
    std::array<std::vector<double>, 3> means, sds;
    for (const auto& [scene, v] : per_scene)
      for (int k = 0; k < 3; ++k) {
        const Spread sp = SpreadOf(v[k]);
        means[k].push_back(sp.mean);
        if (sp.n > 1) sds[k].push_back(sp.sd);
      }
    spread += "<tr><td class=l>" + Html(name) + "</td>";
    md_spread += "| " + name + " |";
    for (int k = 0; k < 3; ++k) {
      auto text = [](const Spread& sp) { return sp.n ? Fmt(sp.mean, "%.3g") : std::string("-"); };
      const std::string m = text(SpreadOf(means[k])), sd = text(SpreadOf(sds[k]));
      spread += "<td>" + m + "</td><td>" + sd + "</td>";
      md_spread += " " + m + " | " + sd + " |";
    }
    spread += "</tr>\n";
    md_spread += "\n";
  }
  spread += "</table>\n";
  WriteTextAtomic(dir + "/strategies.md", md + md_spread);
  return html + spread + "<div class=plots>" + plots + "</div>\n";
}

std::string SweepReport(const std::string& dir) {
  const nlohmann::json grid = ReadGridJson(dir);
  int missing = 0;
  const std::vector<SweepRow> rows = SweepRows(dir, grid, &missing);
  std::string h =
      "<!DOCTYPE html><html><head><meta charset=\"utf-8\"><title>FOVEA sweep: " + Html(dir) +
      "</title>" + kStyle + "</head><body>\n<h1>FOVEA sweep</h1>\n";
  h += "<p>Folder <code>" + Html(dir) + "</code>: " + std::to_string(rows.size()) +
       " runs with results" +
       (missing ? ", " + std::to_string(missing) + " without" : std::string()) +
       ". Data: <code>results.csv</code> (a row per run). Axes:</p><ul>";
  for (const auto& a : grid.at("axes")) {
    std::string values;
    for (const auto& v : a.at("values"))
      values += (values.empty() ? "" : ", ") + v.get<std::string>();
    h +=
        "<li><code>" + Html(a.at("path").get<std::string>()) + "</code>: " + Html(values) + "</li>";
  }
  std::string baselines;
  for (const auto& b : grid.at("baselines"))
    baselines += (baselines.empty() ? "" : ", ") + b.get<std::string>();
  h += "</ul><p>Baselines: " + (baselines.empty() ? std::string("none") : Html(baselines)) +
       " (static_sgbm: StereoSGBM on the static parallel pair; deterministic: always the "
       "composite's "
       "maximum).</p>\n";
  return h + StrategySection(dir, rows) + SceneTable(rows) + AxisPlots(grid, rows) +
         RunsTable(grid, rows) + "</body></html>\n";
}

}  // namespace

namespace {

// Runs gnuplot on the plot, drawn by `terminal` into `output`; throws with
// gnuplot's first line of complaint.
void RunGnuplot(const std::string& terminal, const std::string& output, const std::string& title,
                const std::string& xlabel, const std::string& ylabel,
                const std::vector<Series>& series, bool log_y) {
  const std::string base =
      (fs::temp_directory_path() / ("fovea_plot_" + std::to_string(getpid()))).string();
  std::ostringstream gp;
  gp << "set terminal " << terminal << "\n"
     << "set output " << Quoted(output) << "\n"
     << "set title " << Quoted(title) << "\nset xlabel " << Quoted(xlabel) << "\nset ylabel "
     << Quoted(ylabel)
     << "\nset key outside below\nset grid\nset offsets graph 0.03, graph 0.03, graph 0.05, graph "
        "0.05\n";
  if (log_y) gp << "set logscale y\n";
  std::string plot = "plot ";
  for (size_t i = 0; i < series.size(); ++i) {
    const Series& s = series[i];
    const bool bars = !s.y_lo.empty();
    plot += std::string(i ? ", " : "") + "'-' using 1:2" +
            (bars ? ":3:4 with yerrorlines" : " with linespoints") + " lw 1.5 pt 7 ps 0.6" +
            (s.dashed ? " dt 2" : "") + " title " + Quoted(s.title);
  }
  gp << plot << "\n";
  for (const Series& s : series) {
    for (size_t k = 0; k < s.x.size(); ++k) {
      if (!std::isfinite(s.y[k]) || (log_y && s.y[k] <= 0)) continue;
      gp << Fmt(s.x[k], "%.10g") << " " << Fmt(s.y[k], "%.10g");
      if (!s.y_lo.empty()) gp << " " << Fmt(s.y_lo[k], "%.10g") << " " << Fmt(s.y_hi[k], "%.10g");
      gp << "\n";
    }
    gp << "e\n";
  }
  {
    std::ofstream out(base + ".gp");
    out << gp.str();
  }
  const std::string cmd = "gnuplot " + base + ".gp 2>" + base + ".err";
  const int status = std::system(cmd.c_str());
  const std::string err = ReadFile(base + ".err");
  std::error_code ec;
  for (const char* ext : {".gp", ".err"}) fs::remove(base + ext, ec);
  if (status != 0 || !fs::exists(output) || fs::file_size(output, ec) == 0)
    throw std::runtime_error("gnuplot failed (is it installed? apt-get install gnuplot-nox): " +
                             err.substr(0, err.find('\n')));
}

}  // namespace

std::string GnuplotSvg(const std::string& title, const std::string& xlabel,
                       const std::string& ylabel, const std::vector<Series>& series, bool log_y) {
  const std::string svg_path =
      (fs::temp_directory_path() / ("fovea_plot_" + std::to_string(getpid()) + ".svg")).string();
  std::error_code ec;
  fs::remove(svg_path, ec);
  try {
    RunGnuplot("svg size 560,380 fixed noenhanced font 'sans,11' background rgb 'white'", svg_path,
               title, xlabel, ylabel, series, log_y);
  } catch (...) {
    fs::remove(svg_path, ec);
    throw;
  }
  const std::string svg = ReadFile(svg_path);
  fs::remove(svg_path, ec);
  const size_t start = svg.find("<svg");
  return "<div>" + (start == std::string::npos ? svg : svg.substr(start)) + "</div>\n";
}

void GnuplotPng(const std::string& path, const std::string& title, const std::string& xlabel,
                const std::string& ylabel, const std::vector<Series>& series, bool log_y) {
  // Drawn beside the target, then renamed: a whole picture or none.
  const std::string part = path + ".part.png";
  try {
    RunGnuplot("pngcairo size 720,480 noenhanced font 'sans,10' background rgb 'white'", part,
               title, xlabel, ylabel, series, log_y);
    fs::rename(part, path);
  } catch (...) {
    std::error_code ec;
    fs::remove(part, ec);
    throw;
  }
}

std::string WriteReport(const std::string& dir) {
  std::string page;
  if (fs::exists(dir + "/grid.json"))
    page = SweepReport(dir);
  else if (fs::exists(dir + "/summary.json"))
    page = RunReport(dir);
  else
    throw UsageError("'" + dir +
                     "' is neither a run folder (summary.json) nor a sweep folder (grid.json)");
  WriteTextAtomic(dir + "/report.html", page);
  return dir + "/report.html";
}

}  // namespace experiments
