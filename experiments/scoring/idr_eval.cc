#include "experiments/scoring/idr_eval.h"

#include <algorithm>
#include <cmath>

#include "fovea/stats.h"

namespace experiments {
using fovea::Quantile;
namespace {

// Planar depth where the pixel's ray meets the patch's plane.
double PlaneDepth(const fovea::Patch& p, const rig::CameraView& view, const Eigen::Vector2d& uv) {
  const Eigen::Vector3d o = view.world_T_camera.translation();
  const Eigen::Vector3d ray_C = view.intrinsics.Ray(uv);
  const Eigen::Vector3d d = view.world_T_camera.linear() * ray_C;
  const Eigen::Vector3d n = p.Normal();
  const double t = n.dot(p.Centre() - o) / n.dot(d);
  return t;  // ray_C has z = 1, so t is the planar depth
}

double TrueDepth(const sim::GroundTruth& truth, const rig::CameraView& view,
                 const Eigen::Vector2d& uv, int* geom = nullptr) {
  const Eigen::Vector3d ray_C = view.intrinsics.Ray(uv);
  const auto hit =
      truth.CastRay(view.world_T_camera.translation(), view.world_T_camera.linear() * ray_C);
  if (geom) *geom = hit ? hit->geom_id : -1;
  return hit ? hit->distance_m / ray_C.norm() : 0;
}

}  // namespace

IdrScore ScoreIdr(const fovea::IdrResult& r, const sim::GroundTruth& truth) {
  IdrScore s;
  const rig::CameraView& view = r.final_frame.left;
  const rig::CameraIntrinsics& k = view.intrinsics;
  const double b =
      (r.final_frame.right.world_T_camera.translation() - view.world_T_camera.translation()).norm();
  if (!r.stages.empty()) s.stage0_unambiguous_share = r.stages.front().stats.UnambiguousShare();
  std::vector<double> errors, steps;
  const Eigen::Isometry3d camera_T_world = view.world_T_camera.inverse();
  for (const fovea::Patch& p : r.map.patches()) {
    ++s.patches;
    // The patch's block in the left view: its corners' projections.
    Eigen::Vector2d lo(1e9, 1e9), hi(-1e9, -1e9);
    for (const auto& c : p.corners_W) {
      const Eigen::Vector3d q = camera_T_world * c;
      const Eigen::Vector2d uv = k.Project(q);
      lo = lo.cwiseMin(uv);
      hi = hi.cwiseMax(uv);
    }
    const Eigen::Vector2d centre = 0.5 * (lo + hi);
    int geom = -1;
    const double z_true = TrueDepth(truth, view, centre, &geom);
    if (!truth.Textured(geom)) ++s.patches_on_textureless;
    if (z_true <= 0) continue;
    const double z = PlaneDepth(p, view, centre);
    errors.push_back(std::abs(z - z_true));
    steps.push_back(std::abs(z - z_true) / (z_true * z_true / (k.fx_px * b)));
    // Straddle: a 5 x 5 grid over the footprint, in disparity units.
    bool straddles = false;
    for (int i = 0; i < 5; ++i)
      for (int j = 0; j < 5; ++j) {
        const Eigen::Vector2d uv(lo.x() + (hi.x() - lo.x()) * (i + 0.5) / 5,
                                 lo.y() + (hi.y() - lo.y()) * (j + 0.5) / 5);
        int g = -1;
        const double zt = TrueDepth(truth, view, uv, &g);
        if (zt <= 0) continue;
        const double dz = PlaneDepth(p, view, uv);
        const double dev = std::abs(k.fx_px * b / dz - k.fx_px * b / zt);
        s.max_plane_deviation_px = std::max(s.max_plane_deviation_px, dev);
        if (g != geom) {
          straddles = true;
          if (dev > s.max_straddle_px) s.max_straddle_px = dev, s.worst_straddle_uv = uv;
        }
      }
    if (straddles) ++s.straddling_patches;
  }
  s.median_abs_error_m = Quantile(errors, 0.5);
  s.median_error_steps = Quantile(steps, 0.5);
  for (const fovea::DisparitySample& m : r.final_samples) {
    ++s.matches;
    const double zt = TrueDepth(truth, view, {m.x_px, m.y_px});
    if (zt <= 0 || std::abs(m.disparity_px - k.fx_px * b / zt) > 1.0) ++s.wrong_matches;
  }
  return s;
}

nlohmann::json IdrJson(const fovea::IdrResult& r, const IdrScore& s) {
  nlohmann::json stages = nlohmann::json::array();
  for (const fovea::IdrStage& st : r.stages) {
    stages.push_back({{"baseline_m", st.baseline_m},
                      {"search_limit_px", st.search_limit_px},
                      {"expansion_factor", st.expansion_factor},
                      {"min_separation_px", st.min_separation_px},
                      {"max_disparity_px", st.max_disparity_px},
                      {"left_crossings", st.stats.left_crossings},
                      {"right_crossings", st.stats.right_crossings},
                      {"searched", st.stats.searched},
                      {"unique", st.stats.unique},
                      {"ambiguous", st.stats.ambiguous},
                      {"no_candidate", st.stats.no_candidate},
                      {"inconsistent", st.stats.inconsistent},
                      {"matches", st.stats.matches},
                      {"unambiguous_share", st.stats.UnambiguousShare()},
                      {"motion_time_s", st.motion_time_s},
                      {"compute_time_s", st.compute_time_s}});
  }
  nlohmann::json j = {{"stages", stages},
                      {"stop_reason", r.stop_reason},
                      {"patches", r.map.size()},
                      {"compute_time_s", r.compute_time_s},
                      {"motion_time_s", r.motion_time_s},
                      {"score",
                       {{"patches", s.patches},
                        {"median_abs_error_m", s.median_abs_error_m},
                        {"median_error_steps", s.median_error_steps},
                        {"max_straddle_px", s.max_straddle_px},
                        {"worst_straddle_uv", {s.worst_straddle_uv.x(), s.worst_straddle_uv.y()}},
                        {"straddling_patches", s.straddling_patches},
                        {"max_plane_deviation_px", s.max_plane_deviation_px},
                        {"patches_on_textureless", s.patches_on_textureless},
                        {"matches", s.matches},
                        {"wrong_matches", s.wrong_matches},
                        {"stage0_unambiguous_share", s.stage0_unambiguous_share}}}};
  if (r.has_fixation)
    j["first_fixation_W"] = {r.first_fixation_W.x(), r.first_fixation_W.y(),
                             r.first_fixation_W.z()};
  return j;
}

}  // namespace experiments
