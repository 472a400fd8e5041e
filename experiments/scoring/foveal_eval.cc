#include "experiments/scoring/foveal_eval.h"

#include <algorithm>
#include <cmath>

#include "fovea/stats.h"

namespace experiments {
using fovea::Quantile;

FovealScore ScoreFoveal(const fovea::FixationResult& r, const sim::GroundTruth& truth) {
  FovealScore score;
  // The frame the fovea was matched in: its rects and disparities are there.
  const rig::StereoFrame& frame = r.foveal.frame.views;
  const rig::CameraView& left = frame.left;
  const rig::CameraIntrinsics& k = left.intrinsics;
  score.baseline_m =
      (frame.right.world_T_camera.translation() - left.world_T_camera.translation()).norm();
  const double b = score.baseline_m;
  const sim::GroundTruth::Labels labels = truth.RenderLabels(left.world_T_camera, k);
  const cv::Mat& depth = labels.depth_m;
  const cv::Mat& ids = labels.geom_ids;
  const Eigen::Isometry3d right_T_left = frame.right.world_T_camera.inverse() * left.world_T_camera;
  const fovea::Tessellation& t = r.foveal.tessellation;
  const int levels = static_cast<int>(t.rects.size());
  score.levels.resize(levels);
  for (int level = 0; level < levels; ++level) score.levels[level].level = level;

  // Patches: depth at the centre pixel against truth.
  std::vector<std::vector<double>> err(levels), steps(levels);
  const Eigen::Isometry3d camera_T_world = left.world_T_camera.inverse();
  for (const fovea::Patch& p : r.foveal.patches.patches()) {
    const int level = p.resolution_level;
    ++score.levels[level].patches;
    const Eigen::Vector3d c_C = camera_T_world * p.Centre();
    const Eigen::Vector2d uv = k.Project(c_C);
    const int u = static_cast<int>(std::lround(uv.x())), v = static_cast<int>(std::lround(uv.y()));
    if (u < 0 || v < 0 || u >= k.width_px || v >= k.height_px) continue;
    const double zt = depth.at<float>(v, u);
    if (zt <= 0) continue;
    // Patch plane depth on the same pixel ray.
    const Eigen::Vector3d ray = k.Ray({double(u), double(v)});
    const Eigen::Vector3d n_C = camera_T_world.linear() * p.Normal();
    const double z = n_C.dot(c_C) / n_C.dot(ray);
    err[level].push_back(std::abs(z - zt));
    if (std::abs(z - zt) > 0.05 * zt) ++score.levels[level].gross_errors;
    steps[level].push_back(std::abs(z - zt) / (std::pow(2.0, level) * zt * zt / (k.fx_px * b)));
  }
  // Per-pixel disparities against truth, and the fovea's coverage.
  long fovea_pixels = 0, fovea_matched = 0;
  for (int level = 0; level < levels; ++level) {
    const double s = std::pow(2.0, level);
    const cv::Mat& d = r.foveal.disparity_px[level];
    std::vector<double> derr;
    for (int y = 0; y < d.rows; ++y)
      for (int x = 0; x < d.cols; ++x) {
        const double u = (x + 0.5) * s - 0.5, v = (y + 0.5) * s - 0.5;
        const int ui = std::clamp(int(std::lround(u)), 0, k.width_px - 1),
                  vi = std::clamp(int(std::lround(v)), 0, k.height_px - 1);
        const bool in_level = t.rects[level].contains({ui, vi}) &&
                              (level == 0 || !t.rects[level - 1].contains({ui, vi}));
        const float dd = d.at<float>(y, x);
        if (level == 0 && in_level && t.mask.at<uchar>(vi, ui) &&
            truth.Textured(ids.at<int>(vi, ui))) {
          ++fovea_pixels;
          if (std::isfinite(dd)) ++fovea_matched;
        }
        if (!std::isfinite(dd) || !in_level) continue;
        const float zt = depth.at<float>(vi, ui);
        if (zt <= 0) continue;
        const Eigen::Vector3d p_R = right_T_left * (zt * k.Ray({u, v}));
        const double ur =
            frame.right.intrinsics.fx_px * p_R.x() / p_R.z() + frame.right.intrinsics.cx_px;
        derr.push_back(std::abs(dd - (u - ur) / s));
      }
    score.levels[level].median_disparity_error_px = Quantile(derr, 0.5, std::nan(""));
  }
  for (int level = 0; level < levels; ++level) {
    score.levels[level].median_abs_error_m = Quantile(err[level], 0.5, std::nan(""));
    score.levels[level].median_error_steps = Quantile(steps[level], 0.5, std::nan(""));
  }
  score.fovea_coverage = fovea_pixels ? double(fovea_matched) / fovea_pixels : 0.0;
  return score;
}

nlohmann::json FoveaJson(const fovea::FoveaFigures& f) {
  constexpr double kDeg = 180 / M_PI;
  return {{"width_px", f.width_px},
          {"height_px", f.height_px},
          {"image_share", f.image_share},
          {"frame", f.resampled ? "fixation" : "original"},
          {"left_roll_deg", kDeg * f.left_roll_rad},
          {"right_roll_deg", kDeg * f.right_roll_rad},
          {"right_turn_deg", kDeg * f.right_turn_rad}};
}

nlohmann::json FixationJson(const fovea::FixationResult& r, const FovealScore& s) {
  nlohmann::json j;
  j["ok"] = r.ok;
  if (!r.ok) {
    j["why"] = r.why;
    return j;
  }
  j["fixation_W"] = {r.fixation_W.x(), r.fixation_W.y(), r.fixation_W.z()};
  j["servo"] = {{"converged", r.servo.converged},
                {"iterations", r.servo.iterations},
                {"residual_px", r.servo.residual_px},
                {"residuals_px", r.servo.residuals_px}};
  const auto& t = r.foveal.tessellation;
  j["tessellation"] = {{"fixation_depth_m", t.fixation_depth_m},
                       {"z_t_near_m", t.z_t_near_m},
                       {"z_t_far_m", t.z_t_far_m},
                       {"z_max_near_m", t.z_max_near_m},
                       {"z_max_far_m", t.z_max_far_m}};
  j["fovea"] = FoveaJson(r.foveal.Fovea());
  nlohmann::json levels = nlohmann::json::array();
  for (size_t i = 0; i < r.foveal.levels.size(); ++i) {
    const auto& f = r.foveal.levels[i];
    nlohmann::json l = {
        {"level", f.level},       {"rect", {f.rect.x, f.rect.y, f.rect.width, f.rect.height}},
        {"searched", f.searched}, {"matched", f.matched},
        {"patches", f.patches},   {"match_time_s", f.match_time_s}};
    if (i < s.levels.size()) {
      l["median_abs_error_m"] = s.levels[i].median_abs_error_m;
      l["median_error_steps"] = s.levels[i].median_error_steps;
      l["median_disparity_error_px"] = s.levels[i].median_disparity_error_px;
      l["gross_errors"] = s.levels[i].gross_errors;
    }
    levels.push_back(l);
  }
  j["levels"] = levels;
  j["fovea_coverage"] = s.fovea_coverage;
  j["baseline_m"] = s.baseline_m;
  j["motion_time_s"] = r.motion_time_s;
  j["compute_time_s"] = r.compute_time_s;
  return j;
}

}  // namespace experiments
