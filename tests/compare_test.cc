// fovea compare (experiments/output/compare.h): two sweeps' runs paired by
// scene and seed, each figure's paired change and issue 19's lines.
#include "experiments/output/compare.h"

#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "experiments/usage_error.h"

namespace {

using experiments::RunSummary;

RunSummary Run(const std::string& scene, long long seed, double good_coverage,
               double coverage = 0.95, const std::string& method = "fovea") {
  nlohmann::json s = {{"good_coverage", good_coverage},
                      {"coverage", coverage},
                      {"bad_share", 0.01},
                      {"edge_bad_share", 0.05},
                      {"rmse_m", 0.010},
                      {"median_rel_error", 0.001},
                      {"patch_3d_error", {{"p90_m", 0.003}}},
                      {"refused", 1},
                      {"attempts", 26},
                      {"stale_idr_patches", 0}};
  return {scene, method, seed, s};
}

const experiments::PairedFigure& FigureOf(const experiments::Comparison& c,
                                          const std::string& key) {
  const auto it = std::find_if(c.figures.begin(), c.figures.end(),
                               [&key](const experiments::PairedFigure& f) { return f.key == key; });
  REQUIRE(it != c.figures.end());
  return *it;
}

}  // namespace

TEST_CASE("compare pairs runs by scene and seed and reports the paired change", "[compare]") {
  // Three pairs whose good_coverage changes by +0.01, +0.03 and -0.01: mean
  // +0.01, standard deviation 0.02, standard error 0.02 / sqrt(3). A run
  // with no partner on either side, and a baseline's run, are not paired.
  const std::vector<RunSummary> base = {Run("two_planes", 0, 0.90), Run("two_planes", 1, 0.80),
                                        Run("random:2", 0, 0.70), Run("random:3", 0, 0.5),
                                        Run("two_planes", 0, 0.1, 0.1, "static_sgbm")};
  const std::vector<RunSummary> variant = {Run("random:2", 0, 0.69), Run("two_planes", 1, 0.83),
                                           Run("two_planes", 0, 0.91), Run("random:4", 0, 0.5)};
  const experiments::Comparison c = experiments::Compare(base, variant, "fovea");
  CHECK(c.pairs == 3);
  CHECK(c.base_only == 1);
  CHECK(c.variant_only == 1);
  const experiments::PairedFigure& g = FigureOf(c, "good_coverage");
  CHECK(g.pairs == 3);
  CHECK(g.base_mean == Approx((0.90 + 0.80 + 0.70) / 3));
  CHECK(g.variant_mean == Approx((0.91 + 0.83 + 0.69) / 3));
  CHECK(g.change == Approx(0.01));
  CHECK(g.change_se == Approx(0.02 / std::sqrt(3.0)));
  CHECK(g.up == 2);
  CHECK(g.down == 1);
  // Unchanged figures: no change, no pair up or down.
  const experiments::PairedFigure& b = FigureOf(c, "bad_share");
  CHECK(b.change == Approx(0).margin(1e-15));
  CHECK(b.up + b.down == 0);
  CHECK(FigureOf(c, "refused_share").base_mean == Approx(1.0 / 26));
  CHECK(FigureOf(c, "wrong_share").base_mean == Approx(0.95 * 0.01));  // coverage x bad_share
  // Scenes in the base sweep's order, each over its paired seeds.
  REQUIRE(c.scenes.size() == 2);
  CHECK(c.scenes[0].scene == "two_planes");
  CHECK(c.scenes[0].pairs == 2);
  CHECK(c.scenes[0].variant_good_coverage == Approx((0.91 + 0.83) / 2));
  CHECK(c.scenes[1].scene == "random:2");
  // The baselines pair among themselves only.
  CHECK(experiments::Compare(base, variant, "static_sgbm").pairs == 0);
}

TEST_CASE("compare leaves a null figure's pair out of that figure only", "[compare]") {
  std::vector<RunSummary> base = {Run("two_planes", 0, 0.9), Run("two_planes", 1, 0.9)};
  std::vector<RunSummary> variant = base;
  base[0].summary["edge_bad_share"] = nullptr;  // a run with nothing mapped beside an edge
  variant[1].summary["edge_bad_share"] = 0.25;
  const experiments::Comparison c = experiments::Compare(base, variant, "fovea");
  const experiments::PairedFigure& e = FigureOf(c, "edge_bad_share");
  CHECK(e.pairs == 1);
  CHECK(e.change == Approx(0.20));
  CHECK(std::isnan(e.change_se));  // one pair: no spread
  CHECK(FigureOf(c, "good_coverage").pairs == 2);
  // A figure no pair has is NaN, and null in the JSON.
  for (RunSummary* r : {&base[0], &base[1]}) r->summary.erase("rmse_m");
  const experiments::Comparison none = experiments::Compare(base, variant, "fovea");
  CHECK(FigureOf(none, "rmse_m").pairs == 0);
  CHECK(std::isnan(FigureOf(none, "rmse_m").change));
  CHECK(experiments::ComparisonJson(none)["figures"]["rmse_m"]["change"].is_null());
}

TEST_CASE("compare counts issue 19's lines over each side's paired runs", "[compare]") {
  // A catalog run under 0.95 coverage and another run under 0.90 are misses
  // of their own lines; the largest catalog RMSE reads catalog runs only.
  std::vector<RunSummary> base = {Run("three_surfaces", 0, 0.93, 0.94),
                                  Run("random:1", 0, 0.79, 0.89), Run("post_slant", 0, 0.95, 0.96)};
  base[1].summary["rmse_m"] = 0.050;
  base[0].summary["rmse_m"] = 0.018;
  base[2].summary["stale_idr_patches"] = 2;
  base[2].summary["refused"] = 5;
  std::vector<RunSummary> variant = base;
  variant[0].summary["coverage"] = 0.96;
  const experiments::Comparison c = experiments::Compare(base, variant, "fovea");
  CHECK(c.base.catalog_coverage_misses == 1);
  CHECK(c.variant.catalog_coverage_misses == 0);
  CHECK(c.base.other_coverage_misses == 1);
  CHECK(c.base.runs_under_good_coverage == 1);
  CHECK(c.base.max_catalog_rmse_m == Approx(0.018));
  CHECK(c.base.stale_idr_patches == 2);
  CHECK(c.base.refused_share == Approx((1 + 1 + 5) / 78.0));
  const std::string text = experiments::ComparisonText(c);
  CHECK(text.find("3 pairs of fovea runs") != std::string::npos);
  CHECK(text.find("catalog runs with coverage under 0.95") != std::string::npos);
}

TEST_CASE("compare refuses an ambiguous pairing and a folder that is not a sweep's", "[compare]") {
  const std::vector<RunSummary> twice = {Run("two_planes", 0, 0.9), Run("two_planes", 0, 0.8)};
  CHECK_THROWS_AS(experiments::Compare(twice, twice, "fovea"), experiments::UsageError);
  CHECK_THROWS_WITH(experiments::Compare({Run("two_planes", 0, 0.9)}, twice, "fovea"),
                    Catch::Contains("variant sweep holds two fovea runs of scene 'two_planes'"));
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("fovea_compare_test_" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  CHECK_THROWS_WITH(experiments::SweepSummaries(dir.string()),
                    Catch::Contains("is not a sweep folder"));
  // A sweep folder's finished runs: scene names as the sweeps give them.
  // Runs are told apart by the grid's variant: a deterministic baseline's
  // summary says method fovea too.
  std::ofstream(dir / "grid.json") << R"({"axes": [{"path": "seed", "values": ["3", "4"]}],
      "baselines": ["deterministic"], "runs": [
      {"id": "a", "variant": "fovea", "point": {"seed": "3"}, "config": [["scene", "two_planes"]]},
      {"id": "b", "variant": "fovea", "point": {"seed": "4"}, "config": [["scene", "two_planes"]]},
      {"id": "c", "variant": "deterministic", "point": {"seed": "3"},
       "config": [["scene", "two_planes"]]}]})";
  for (const char* id : {"a", "c"}) {
    std::filesystem::create_directories(dir / "runs" / id);
    std::ofstream(dir / "runs" / id / "summary.json")
        << R"({"scene": "/somewhere/scenes/two_planes.xml", "seed": 3, "method": "fovea"})";
  }
  int unfinished = -1;
  const std::vector<RunSummary> runs = experiments::SweepSummaries(dir.string(), &unfinished);
  REQUIRE(runs.size() == 2);  // "b" has no summary yet
  CHECK(unfinished == 1);
  CHECK(runs[0].scene == "two_planes");
  CHECK(runs[0].seed == 3);
  CHECK(runs[0].method == "fovea");
  CHECK(runs[1].method == "deterministic");
  CHECK(experiments::Compare(runs, runs, "fovea").pairs == 1);
  CHECK(experiments::Compare(runs, runs, "deterministic").pairs == 1);
  // The text names the unfinished runs only when there are any; the JSON
  // always carries both counts.
  experiments::Comparison c = experiments::Compare(runs, runs, "fovea");
  CHECK_THAT(experiments::ComparisonText(c), !Catch::Contains("not finished"));
  c.variant_unfinished = unfinished;
  CHECK_THAT(experiments::ComparisonText(c),
             Catch::Contains("runs not finished (no summary.json), left out: 0 in base, 1 in "
                             "variant"));
  CHECK(experiments::ComparisonJson(c)["base_unfinished"] == 0);
  CHECK(experiments::ComparisonJson(c)["variant_unfinished"] == 1);
  std::filesystem::remove_all(dir);
}
