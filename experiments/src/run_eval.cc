#include "run_eval.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "stats.h"

namespace experiments {
namespace {

struct Accumulator {
  std::vector<double> abs, rel, steps;
  double sum_sq = 0, sum_abs = 0;
  long within = 0;
  void Add(double z, double zt, double step) {
    const double e = std::abs(z - zt);
    abs.push_back(e);
    rel.push_back(e / zt);
    steps.push_back(e / step);
    sum_sq += e * e;
    sum_abs += e;
    within += e <= 0.01 * zt;
  }
  ErrorFigures Figures(long total) const {
    ErrorFigures f;
    f.pixels = static_cast<long>(abs.size());
    f.share = total ? double(f.pixels) / total : 0;
    if (abs.empty()) return f;
    f.median_abs_error_m = Quantile(abs, 0.5);
    f.mean_abs_error_m = sum_abs / abs.size();
    f.rmse_m = std::sqrt(sum_sq / abs.size());
    f.median_rel_error = Quantile(rel, 0.5);
    f.within_1pct = double(within) / abs.size();
    f.median_error_steps = Quantile(steps, 0.5);
    return f;
  }
};

}  // namespace

ReferenceView MakeReferenceView(rig::Rig& rig, const sim::GroundTruth& truth) {
  ReferenceView ref;
  rig.MoveTo(rig.Home());
  ref.view = rig.Capture().left;
  ref.depth_m = truth.RayCastDepth(ref.view.world_T_camera, ref.view.intrinsics, &ref.geom_ids);
  ref.textured = truth.TexturedMask(ref.geom_ids);
  ref.textured_pixels = cv::countNonZero(ref.textured);
  return ref;
}

MapScore ScoreMap(const fovea::PatchMap& map, const ReferenceView& ref, const sim::GroundTruth& truth,
                  double baseline_m, bool per_patch) {
  MapScore s;
  cv::Mat depth, ids;
  map.Render(ref.view.world_T_camera, ref.view.intrinsics, &depth, &ids);
  const double f = ref.view.intrinsics.fx_px;
  Accumulator all;
  std::array<Accumulator, 3> level;
  struct PerSurface {
    long pixels = 0, mapped = 0, foveal = 0;
    Accumulator errors;
  };
  std::map<int, PerSurface> surfaces;
  long mapped = 0, foveal = 0;
  for (int y = 0; y < depth.rows; ++y)
    for (int x = 0; x < depth.cols; ++x) {
      if (!ref.textured.at<uchar>(y, x)) continue;
      const double zt = ref.depth_m.at<float>(y, x);
      PerSurface& ps = surfaces[ref.geom_ids.at<int>(y, x)];
      ++ps.pixels;
      const int id = ids.at<int>(y, x);
      if (id < 0 || zt <= 0) continue;
      const double z = depth.at<float>(y, x);
      const int lv = static_cast<int>(map[id].level);
      ++mapped;
      ++ps.mapped;
      if (lv == static_cast<int>(fovea::PatchLevel::kFoveal)) ++foveal, ++ps.foveal;
      const double step = zt * zt / (f * baseline_m);
      all.Add(z, zt, step);
      level[lv].Add(z, zt, step);
      ps.errors.Add(z, zt, step);
    }
  const long total = ref.textured_pixels;
  s.coverage = total ? double(mapped) / total : 0;
  s.foveal_coverage = total ? double(foveal) / total : 0;
  s.overall = all.Figures(total);
  for (int i = 0; i < 3; ++i) s.by_level[i] = level[i].Figures(total);
  for (const auto& [geom, ps] : surfaces) {
    SurfaceFigures sf;
    sf.name = truth.GeomName(geom);
    sf.pixels = ps.pixels;
    sf.coverage = double(ps.mapped) / ps.pixels;
    sf.foveal_coverage = double(ps.foveal) / ps.pixels;
    const ErrorFigures e = ps.errors.Figures(ps.pixels);
    sf.median_abs_error_m = e.median_abs_error_m;
    sf.median_rel_error = e.median_rel_error;
    sf.median_error_steps = e.median_error_steps;
    sf.rmse_m = e.rmse_m;
    s.surfaces.push_back(sf);
  }
  if (per_patch) {
    s.has_patch_error = true;
    std::vector<double> err;
    for (const fovea::Patch& p : map.patches()) {
      const Eigen::Vector3d c = p.Centre(), n = p.Normal();
      double best = std::numeric_limits<double>::infinity();
      for (const double sign : {1.0, -1.0}) {
        const auto hit = truth.CastRay(c, sign * n);
        if (hit) best = std::min(best, hit->distance_m);
      }
      if (std::isfinite(best)) err.push_back(best);
    }
    s.patches_scored = static_cast<int>(err.size());
    s.patch_error_median_m = Quantile(err, 0.5);
    s.patch_error_p90_m = Quantile(err, 0.9);
  }
  return s;
}

namespace {
nlohmann::json ErrorJson(const ErrorFigures& f) {
  return {{"pixels", f.pixels},
          {"share", f.share},
          {"median_abs_error_m", f.median_abs_error_m},
          {"mean_abs_error_m", f.mean_abs_error_m},
          {"rmse_m", f.rmse_m},
          {"median_rel_error", f.median_rel_error},
          {"within_1pct", f.within_1pct},
          {"median_error_steps", f.median_error_steps}};
}
}  // namespace

nlohmann::json ScoreJson(const MapScore& s) {
  nlohmann::json j;
  j["coverage"] = s.coverage;
  j["foveal_coverage"] = s.foveal_coverage;
  j["median_abs_error_m"] = s.overall.median_abs_error_m;
  j["median_rel_error"] = s.overall.median_rel_error;
  j["rmse_m"] = s.overall.rmse_m;
  j["mean_abs_error_m"] = s.overall.mean_abs_error_m;
  j["within_1pct"] = s.overall.within_1pct;
  j["median_error_steps"] = s.overall.median_error_steps;
  for (int i = 0; i < 3; ++i)
    j["by_level"][fovea::PatchLevelName(static_cast<fovea::PatchLevel>(i))] = ErrorJson(s.by_level[i]);
  for (const SurfaceFigures& sf : s.surfaces)
    j["by_surface"][sf.name] = {{"pixels", sf.pixels},
                                {"coverage", sf.coverage},
                                {"foveal_coverage", sf.foveal_coverage},
                                {"median_abs_error_m", sf.median_abs_error_m},
                                {"median_rel_error", sf.median_rel_error},
                                {"median_error_steps", sf.median_error_steps},
                                {"rmse_m", sf.rmse_m}};
  if (s.has_patch_error)
    j["patch_3d_error"] = {{"patches", s.patches_scored},
                           {"median_m", s.patch_error_median_m},
                           {"p90_m", s.patch_error_p90_m}};
  return j;
}

}  // namespace experiments
