#include "experiments/output/compare.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <utility>

#include "experiments/config/sweep.h"
#include "experiments/output/report.h"
#include "experiments/output/run_folder.h"
#include "experiments/usage_error.h"
#include "rig/input_file.h"

namespace experiments {
namespace fs = std::filesystem;

namespace {

// A summary's scene as the sweeps name it: a catalog scene's file stem,
// "random:N" as it is.
std::string SceneName(const std::string& scene) {
  if (scene.rfind("random:", 0) == 0) return scene;
  return fs::path(scene).stem().string();
}

// The figures compared pair by pair: summary keys, wrong_share (the mapped
// pixels off by more than 1% as a share of the view's visible textured
// pixels: coverage x bad_share) and refused_share (refused over attempts).
const std::vector<std::string>& FigureKeys() {
  static const std::vector<std::string> kKeys = {
      "good_coverage",        "coverage",         "bad_share",        "wrong_share",
      "edge_bad_share",       "mean_abs_error_m", "median_rel_error", "rmse_m",
      "patch_3d_error.p90_m", "refused_share",    "stale_idr_patches"};
  return kKeys;
}

double Figure(const nlohmann::json& summary, const std::string& key) {
  if (key == "wrong_share")
    return SummaryNumber(summary, "coverage") * SummaryNumber(summary, "bad_share");
  if (key == "refused_share") {
    const double attempts = SummaryNumber(summary, "attempts");
    return attempts > 0 ? SummaryNumber(summary, "refused") / attempts : std::nan("");
  }
  return SummaryNumber(summary, key);
}

using PairKey = std::pair<std::string, long long>;  // scene, seed

// The runs of `method`, by scene and seed, and the scenes in first-seen order.
std::map<PairKey, const RunSummary*> ByKey(const std::vector<RunSummary>& runs,
                                           const std::string& method, const char* side,
                                           std::vector<std::string>* scenes) {
  std::map<PairKey, const RunSummary*> out;
  for (const RunSummary& r : runs) {
    if (r.method != method) continue;
    if (!out.emplace(PairKey{r.scene, r.seed}, &r).second)
      throw UsageError(std::string("the ") + side + " sweep holds two " + method +
                       " runs of scene '" + rig::ClipForMessage(r.scene) + "' seed " +
                       std::to_string(r.seed) + ": compare pairs one run per scene and seed");
    if (scenes && std::find(scenes->begin(), scenes->end(), r.scene) == scenes->end())
      scenes->push_back(r.scene);
  }
  return out;
}

SetLines Lines(const std::vector<const nlohmann::json*>& runs,
               const std::vector<std::string>& scenes) {
  SetLines l;
  double refused = 0, attempts = 0;
  for (size_t i = 0; i < runs.size(); ++i) {
    const nlohmann::json& s = *runs[i];
    const bool catalog = IsDdrCatalogScene(scenes[i]);
    if (SummaryNumber(s, "good_coverage") < kGoodCoverageFloor) ++l.runs_under_good_coverage;
    const double coverage = SummaryNumber(s, "coverage");
    if (catalog && coverage < kCatalogCoverage) ++l.catalog_coverage_misses;
    if (!catalog && coverage < kOtherCoverage) ++l.other_coverage_misses;
    auto raise = [&s](double* to, const char* key) {
      if (const double v = SummaryNumber(s, key); std::isfinite(v)) *to = std::max(*to, v);
    };
    raise(&l.max_edge_bad_share, "edge_bad_share");
    if (catalog) raise(&l.max_catalog_rmse_m, "rmse_m");
    raise(&l.max_median_rel_error, "median_rel_error");
    raise(&l.max_patch_p90_m, "patch_3d_error.p90_m");
    if (const double v = SummaryNumber(s, "refused"); std::isfinite(v)) refused += v;
    if (const double v = SummaryNumber(s, "attempts"); std::isfinite(v)) attempts += v;
    if (const double v = SummaryNumber(s, "stale_idr_patches"); std::isfinite(v))
      l.stale_idr_patches += static_cast<long long>(v);
  }
  l.refused_share = attempts > 0 ? refused / attempts : 0;
  return l;
}

std::string Fmt(double v, const char* format = "%.4f") {
  if (!std::isfinite(v)) return "-";
  char b[64];
  std::snprintf(b, sizeof b, format, v);
  return b;
}

nlohmann::json Number(double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(); }

nlohmann::json LinesJson(const SetLines& l) {
  return {{"runs_under_good_coverage", l.runs_under_good_coverage},
          {"catalog_coverage_misses", l.catalog_coverage_misses},
          {"other_coverage_misses", l.other_coverage_misses},
          {"max_edge_bad_share", l.max_edge_bad_share},
          {"max_catalog_rmse_m", l.max_catalog_rmse_m},
          {"max_median_rel_error", l.max_median_rel_error},
          {"max_patch_p90_m", l.max_patch_p90_m},
          {"refused_share", l.refused_share},
          {"stale_idr_patches", l.stale_idr_patches}};
}

}  // namespace

bool IsDdrCatalogScene(const std::string& scene) {
  return scene == "cylinder_planes" || scene == "two_planes" || scene == "three_surfaces";
}

std::vector<RunSummary> SweepSummaries(const std::string& dir, int* unfinished) {
  if (!fs::is_regular_file(dir + "/grid.json"))
    throw UsageError("'" + rig::ClipForMessage(dir) + "' is not a sweep folder (no grid.json)");
  int missing = 0;
  std::vector<RunSummary> runs;
  for (SweepRow& row : SweepRows(dir, ReadGridJson(dir), &missing)) {
    const nlohmann::json& s = row.summary;
    const double seed = SummaryNumber(s, "seed");
    if (!s.contains("scene") || !s["scene"].is_string() || !std::isfinite(seed))
      throw std::runtime_error(dir + "/runs/" + row.id + "/" + run_folder::kSummary +
                               ": no scene or seed");
    // The grid's variant, not the summary's method: a `deterministic`
    // baseline's runs are method fovea too.
    runs.push_back({SceneName(s["scene"].get<std::string>()), row.variant,
                    static_cast<long long>(seed), std::move(row.summary)});
  }
  if (unfinished) *unfinished = missing;
  return runs;
}

Comparison Compare(const std::vector<RunSummary>& base, const std::vector<RunSummary>& variant,
                   const std::string& method) {
  Comparison c;
  c.method = method;
  std::vector<std::string> scene_order;
  const auto b = ByKey(base, method, "base", &scene_order);
  const auto v = ByKey(variant, method, "variant", nullptr);
  std::vector<std::string> pair_scenes;
  std::vector<const nlohmann::json*> base_side, variant_side;
  // Pairs in the base sweep's scene order, then by seed.
  for (const std::string& scene : scene_order)
    for (const auto& [key, run] : b) {
      if (key.first != scene) continue;
      const auto it = v.find(key);
      if (it == v.end()) continue;
      base_side.push_back(&run->summary);
      variant_side.push_back(&it->second->summary);
      pair_scenes.push_back(scene);
    }
  c.pairs = static_cast<int>(base_side.size());
  c.base_only = static_cast<int>(b.size()) - c.pairs;
  c.variant_only = static_cast<int>(v.size()) - c.pairs;
  for (const std::string& key : FigureKeys()) {
    PairedFigure f;
    f.key = key;
    std::vector<double> change;
    double sum_b = 0, sum_v = 0;
    for (size_t i = 0; i < base_side.size(); ++i) {
      const double x = Figure(*base_side[i], key), y = Figure(*variant_side[i], key);
      if (!std::isfinite(x) || !std::isfinite(y)) continue;
      sum_b += x;
      sum_v += y;
      change.push_back(y - x);
      f.up += y > x;
      f.down += y < x;
    }
    f.pairs = static_cast<int>(change.size());
    const double n = f.pairs;
    f.base_mean = n > 0 ? sum_b / n : std::nan("");
    f.variant_mean = n > 0 ? sum_v / n : std::nan("");
    double mean = 0;
    for (const double d : change) mean += d;
    f.change = n > 0 ? mean / n : std::nan("");
    double ss = 0;
    for (const double d : change) ss += (d - f.change) * (d - f.change);
    f.change_se = n > 1 ? std::sqrt(ss / (n - 1) / n) : std::nan("");
    c.figures.push_back(f);
  }
  c.base = Lines(base_side, pair_scenes);
  c.variant = Lines(variant_side, pair_scenes);
  for (const std::string& scene : scene_order) {
    ScenePair s;
    s.scene = scene;
    for (size_t i = 0; i < pair_scenes.size(); ++i) {
      if (pair_scenes[i] != scene) continue;
      ++s.pairs;
      s.base_good_coverage += SummaryNumber(*base_side[i], "good_coverage");
      s.variant_good_coverage += SummaryNumber(*variant_side[i], "good_coverage");
    }
    if (s.pairs == 0) continue;
    s.base_good_coverage /= s.pairs;
    s.variant_good_coverage /= s.pairs;
    c.scenes.push_back(s);
  }
  return c;
}

std::string ComparisonText(const Comparison& c) {
  std::string t;
  char line[256];
  std::snprintf(line, sizeof line,
                "%d pair%s of %s runs by scene and seed (unpaired: %d in base, %d in variant)\n",
                c.pairs, c.pairs == 1 ? "" : "s", c.method.c_str(), c.base_only, c.variant_only);
  t += line;
  if (c.base_unfinished > 0 || c.variant_unfinished > 0) {
    std::snprintf(line, sizeof line,
                  "runs not finished (no summary.json), left out: %d in base, %d in variant\n",
                  c.base_unfinished, c.variant_unfinished);
    t += line;
  }
  t += "\n";
  std::snprintf(line, sizeof line, "%-22s %10s %10s %10s %8s %5s %9s\n", "figure (mean)", "base",
                "variant", "change", "se", "pairs", "up / down");
  t += line;
  for (const PairedFigure& f : c.figures) {
    std::snprintf(line, sizeof line, "%-22s %10s %10s %10s %8s %5d %4d / %d\n", f.key.c_str(),
                  Fmt(f.base_mean, "%.4g").c_str(), Fmt(f.variant_mean, "%.4g").c_str(),
                  Fmt(f.change, "%+.3g").c_str(), Fmt(f.change_se, "%.3g").c_str(), f.pairs, f.up,
                  f.down);
    t += line;
  }
  t += "\nissue 19's lines over the paired runs\n";
  std::snprintf(line, sizeof line, "%-44s %10s %10s\n", "", "base", "variant");
  t += line;
  auto row = [&](const char* label, const std::string& x, const std::string& y) {
    std::snprintf(line, sizeof line, "%-44s %10s %10s\n", label, x.c_str(), y.c_str());
    t += line;
  };
  auto count = [](long long n) { return std::to_string(n); };
  row("runs with good_coverage under 0.80", count(c.base.runs_under_good_coverage),
      count(c.variant.runs_under_good_coverage));
  row("catalog runs with coverage under 0.95", count(c.base.catalog_coverage_misses),
      count(c.variant.catalog_coverage_misses));
  row("other runs with coverage under 0.90", count(c.base.other_coverage_misses),
      count(c.variant.other_coverage_misses));
  row("largest edge_bad_share", Fmt(c.base.max_edge_bad_share, "%.3f"),
      Fmt(c.variant.max_edge_bad_share, "%.3f"));
  row("largest catalog RMSE, mm", Fmt(1e3 * c.base.max_catalog_rmse_m, "%.1f"),
      Fmt(1e3 * c.variant.max_catalog_rmse_m, "%.1f"));
  row("largest median relative error, %", Fmt(100 * c.base.max_median_rel_error, "%.3f"),
      Fmt(100 * c.variant.max_median_rel_error, "%.3f"));
  row("largest per-patch 3D error p90, mm", Fmt(1e3 * c.base.max_patch_p90_m, "%.1f"),
      Fmt(1e3 * c.variant.max_patch_p90_m, "%.1f"));
  row("refused attempts, % of attempts", Fmt(100 * c.base.refused_share, "%.1f"),
      Fmt(100 * c.variant.refused_share, "%.1f"));
  row("stale IDR patches", count(c.base.stale_idr_patches), count(c.variant.stale_idr_patches));
  t += "\ngood_coverage by scene (mean over the paired seeds)\n";
  std::snprintf(line, sizeof line, "%-22s %5s %10s %10s %10s\n", "scene", "pairs", "base",
                "variant", "change");
  t += line;
  for (const ScenePair& s : c.scenes) {
    std::snprintf(line, sizeof line, "%-22s %5d %10s %10s %10s\n", s.scene.c_str(), s.pairs,
                  Fmt(s.base_good_coverage).c_str(), Fmt(s.variant_good_coverage).c_str(),
                  Fmt(s.variant_good_coverage - s.base_good_coverage, "%+.4f").c_str());
    t += line;
  }
  return t;
}

nlohmann::json ComparisonJson(const Comparison& c) {
  nlohmann::json figures = nlohmann::json::object();
  for (const PairedFigure& f : c.figures)
    figures[f.key] = {{"pairs", f.pairs},
                      {"base_mean", Number(f.base_mean)},
                      {"variant_mean", Number(f.variant_mean)},
                      {"change", Number(f.change)},
                      {"change_se", Number(f.change_se)},
                      {"up", f.up},
                      {"down", f.down}};
  nlohmann::json scenes = nlohmann::json::array();
  for (const ScenePair& s : c.scenes)
    scenes.push_back({{"scene", s.scene},
                      {"pairs", s.pairs},
                      {"base_good_coverage", s.base_good_coverage},
                      {"variant_good_coverage", s.variant_good_coverage}});
  return {{"method", c.method},
          {"pairs", c.pairs},
          {"base_only", c.base_only},
          {"variant_only", c.variant_only},
          {"base_unfinished", c.base_unfinished},
          {"variant_unfinished", c.variant_unfinished},
          {"figures", figures},
          {"lines", {{"base", LinesJson(c.base)}, {"variant", LinesJson(c.variant)}}},
          {"scenes", scenes}};
}

}  // namespace experiments
