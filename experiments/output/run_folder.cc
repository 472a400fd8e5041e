#include "experiments/output/run_folder.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "experiments/output/output.h"
#include "experiments/output/run_output.h"
#include "experiments/scoring/foveal_eval.h"
#include "fovea/stats.h"
#include "fovea/timing.h"
#include "fovea/visibility.h"

namespace experiments::run_folder {
namespace {

nlohmann::json Vec(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

nlohmann::json SelectionJson(const fovea::SelectionSummary& s) {
  nlohmann::json j = {{"pixel", {s.pixel.x(), s.pixel.y()}},
                      {"candidates", s.candidates},
                      {"composite_max", s.composite_max},
                      {"composite_chosen", s.composite_chosen},
                      {"drawn_value", s.drawn_value},
                      {"bin", s.bin},
                      {"in_hole", s.in_hole},
                      {"prescreened", s.prescreened}};
  for (const auto& [name, v] : s.criteria) j["criteria_vs_mean"][name] = v;
  // Only with selection.reference_fallback: the pixel is the reference view's.
  if (s.in_reference) j["in_reference"] = true;
  return j;
}

// What a record adds for a fixation that succeeded.
void AddFixation(const fovea::FixationRecord& r, nlohmann::json* j) {
  (*j)["fixation_W"] = Vec(r.fixation_W);
  const auto a = r.state.ToArray();
  (*j)["stage_state"] = {{"left_baseline_m", a[0]}, {"left_pan_rad", a[1]},
                         {"left_tilt_rad", a[2]},   {"right_baseline_m", a[3]},
                         {"right_pan_rad", a[4]},   {"right_tilt_rad", a[5]}};
  (*j)["placement"] = fovea::PlacementName(r.placement);
  (*j)["vergent_baseline_m"] = r.baseline_m;
  (*j)["servo"] = {{"iterations", r.servo_iterations},
                   {"residual_px", r.servo_residual_px},
                   {"converged", r.servo_converged}};
  (*j)["tessellation"] = {{"fixation_depth_m", r.tessellation.fixation_depth_m},
                          {"z_t_near_m", r.tessellation.z_t_near_m},
                          {"z_t_far_m", r.tessellation.z_t_far_m},
                          {"levels", r.tessellation.rects.size()}};
  (*j)["fovea"] = FoveaJson(r.fovea);
  nlohmann::json levels = nlohmann::json::array();
  for (const fovea::LevelFigures& l : r.levels)
    levels.push_back({{"level", l.level},
                      {"rect", {l.rect.x, l.rect.y, l.rect.width, l.rect.height}},
                      {"searched", l.searched},
                      {"matched", l.matched},
                      {"patches", l.patches}});
  (*j)["levels"] = levels;
  const fovea::IntegrationStats& in = r.integration;
  (*j)["integration"] = {{"offered", in.offered},
                         {"added", in.added},
                         {"dropped_under_finer", in.dropped_under_finer},
                         {"replaced_idr", in.replaced[0]},
                         {"replaced_peripheral", in.replaced[1]},
                         {"replaced_foveal", in.replaced[2]},
                         {"dropped_contradicted", in.dropped_contradicted},
                         {"fused", in.fused},
                         {"retired_idr", in.retired_idr},
                         {"hidden_in_reference", in.hidden_in_reference},
                         {"removed_contradicted_idr", in.removed_contradicted[0]},
                         {"removed_contradicted_peripheral", in.removed_contradicted[1]},
                         {"removed_contradicted_foveal", in.removed_contradicted[2]}};
}

}  // namespace

std::string SnapshotName(int fixation) {
  char name[32];
  std::snprintf(name, sizeof name, "map_after_%02d.png", fixation);
  return name;
}

bool IsWallClockKey(const std::string& key) {
  return key == "wall_time_s" || key == "compute_time_s" || key == "time_s" ||
         key.rfind("time_s.", 0) == 0;
}

nlohmann::json FoveaSizesJson(const std::vector<fovea::FixationRecord>& records) {
  std::vector<double> width, height, share;
  int under_32 = 0, resampled = 0;
  for (const fovea::FixationRecord& r : records) {
    if (!r.ok) continue;
    width.push_back(r.fovea.width_px);
    height.push_back(r.fovea.height_px);
    share.push_back(r.fovea.image_share);
    under_32 += r.fovea.width_px < 32 || r.fovea.height_px < 32;
    resampled += r.fovea.resampled;
  }
  const double none = std::nan("");
  auto figure = [&](double v) { return share.empty() ? nlohmann::json() : nlohmann::json(v); };
  auto range = [&](const std::vector<double>& v) {
    return nlohmann::json{{"min", figure(fovea::Quantile(v, 0, none))},
                          {"median", figure(fovea::Quantile(v, 0.5, none))},
                          {"max", figure(fovea::Quantile(v, 1, none))}};
  };
  nlohmann::json j = {{"fixations", share.size()},  {"width_px", range(width)},
                      {"height_px", range(height)}, {"image_share", range(share)},
                      {"under_32px", under_32},     {"in_fixation_frame", resampled}};
  double sum = 0;
  for (const double v : share) sum += v;
  j["image_share"]["mean"] = figure(share.empty() ? none : sum / share.size());
  return j;
}

nlohmann::json TravelJson(double pan_rad, double tilt_rad, double carriage_m) {
  constexpr double kDeg = 180 / M_PI;
  return {{"pan_deg", kDeg * pan_rad}, {"tilt_deg", kDeg * tilt_rad}, {"carriage_m", carriage_m}};
}

nlohmann::json RecordJson(const fovea::FixationRecord& r, const MapScore& score) {
  nlohmann::json j;
  j["attempt"] = r.attempt;
  j["fixation"] = r.fixation;
  j["ok"] = r.ok;
  if (!r.ok) j["why"] = r.why;
  j["selection"] = SelectionJson(r.selection);
  j["target_W"] = Vec(r.target_W);
  j["motion_time_s"] = r.motion_time_s;
  j["travel"] = TravelJson(r.pan_rad, r.tilt_rad, r.carriage_m);
  j["time_s"] = {{"select", r.time.select_s},    {"verge", r.time.verge_s},
                 {"servo_wall", r.time.servo_s}, {"foveal", r.time.foveal_s},
                 {"match", r.time.match_s},      {"integrate", r.time.integrate_s}};
  if (r.ok) AddFixation(r, &j);
  j["map_patches"] = {
      {"idr", r.map_by_level[0]}, {"peripheral", r.map_by_level[1]}, {"foveal", r.map_by_level[2]}};
  j["score"] = ScoreJson(score);
  return j;
}

nlohmann::json SummaryJson(const MapScore& score, const std::string& scene_path,
                           const RunConfig& config, const std::array<int, 3>& patches_by_level,
                           double motion_time_s, double compute_time_s, double wall_time_s) {
  nlohmann::json summary = ScoreJson(score);
  summary["scene"] = scene_path;
  summary["seed"] = config.seed;
  summary["method"] = config.method;
  summary["map_patches"] = {{"idr", patches_by_level[0]},
                            {"peripheral", patches_by_level[1]},
                            {"foveal", patches_by_level[2]}};
  summary["motion_time_s"] = motion_time_s;
  summary["compute_time_s"] = compute_time_s;
  summary["wall_time_s"] = wall_time_s;
  return summary;
}

Recorder::Recorder(const std::string& dir, const std::string& scene_path, const ReferenceView& ref,
                   const sim::GroundTruth& truth, const RunConfig& config)
    : dir_(dir),
      scene_name_(std::filesystem::path(scene_path).stem().string()),
      ref_(ref),
      truth_(truth),
      baseline_m_(config.fovea.fixation.baseline_m),
      flank_px_(config.fovea.integration.reference_flank_px),
      fixations_(config.fovea.fixations),
      snapshots_(kSnapshotFixations.begin(), kSnapshotFixations.end()) {
  snapshots_.push_back(fixations_);
}

nlohmann::json Recorder::SurfaceAt(const Eigen::Vector3d& p_W) const {
  // The nearest hit among the ray from the reference camera through the
  // point (both ways) and the rays from the point along the six axis
  // directions: a point on a surface, a few millimetres off it, or past an
  // edge that the reference ray grazes.
  const Eigen::Vector3d eye = ref_.view.world_T_camera.translation();
  const Eigen::Vector3d to_point = (p_W - eye).normalized();
  std::vector<Eigen::Vector3d> directions = {to_point, -to_point};
  for (int a = 0; a < 3; ++a)
    for (const double sign : {1.0, -1.0}) directions.push_back(sign * Eigen::Vector3d::Unit(a));
  std::optional<sim::RayHit> nearest;
  for (const Eigen::Vector3d& d : directions)
    if (const auto hit = truth_.CastRay(p_W, d);
        hit && (!nearest || hit->distance_m < nearest->distance_m))
      nearest = hit;
  if (!nearest) return {{"name", nullptr}, {"distance_m", nullptr}};
  return {{"name", truth_.GeomName(nearest->geom_id)}, {"distance_m", nearest->distance_m}};
}

Recorder::~Recorder() {
  if (pending_ && pending_->score.valid()) pending_->score.wait();
}

void Recorder::operator()(const fovea::FixationRecord& r, const fovea::PatchMap& map) {
  Finish();
  auto t = fovea::Clock::now();
  Pending p;
  p.record = r;
  if (r.ok) p.surface = SurfaceAt(r.fixation_W);
  p.map = std::make_shared<const fovea::PatchMap>(fovea::ReferenceMap(map));
  p.score = std::async(std::launch::async, [this, m = p.map] {
    return ScoreMap(*m, flank_px_, ref_, truth_, baseline_m_, false);
  });
  pending_ = std::move(p);
  scoring_s += fovea::Since(t);
}

void Recorder::Finish() {
  if (!pending_) return;
  Pending p = std::move(*pending_);
  pending_.reset();
  Complete(&p);
}

void Recorder::Complete(Pending* pending) {
  auto t = fovea::Clock::now();
  const MapScore score = pending->score.get();
  scoring_s += fovea::Since(t);
  const fovea::FixationRecord& r = pending->record;
  nlohmann::json record = RecordJson(r, score);
  if (r.ok) record["surface"] = pending->surface;
  jsonl_ += record.dump() + "\n";
  if (r.ok)
    path_.push_back(r.fixation_W);
  else
    refused_.push_back(r.target_W);
  if (r.ok && r.fixation == 1) view_target_ = r.fixation_W;
  std::fprintf(
      stderr,
      "fovea run: fixation %2d/%d%s at (%+.3f, %.3f, %+.3f): %3d new patches, map %4d idr / %4d "
      "peripheral / %4d foveal, %s\n",
      r.fixation, fixations_, r.ok ? "" : " REFUSED", r.target_W.x(), r.target_W.y(),
      r.target_W.z(), r.integration.added, r.map_by_level[0], r.map_by_level[1], r.map_by_level[2],
      ScoreLine(score, /*brief=*/true).c_str());
  if (!r.ok) std::fprintf(stderr, "fovea run:   refused: %s\n", r.why.c_str());
  t = fovea::Clock::now();
  if (r.ok && std::count(snapshots_.begin(), snapshots_.end(), r.fixation)) {
    char caption[200];
    std::snprintf(caption, sizeof caption, "%s after fixation %d: %s", scene_name_.c_str(),
                  r.fixation, ScoreLine(score, /*brief=*/true).c_str());
    WriteImageAtomic(dir_ + "/" + SnapshotName(r.fixation),
                     MapSnapshot(*pending->map, flank_px_, ref_, view_target_, caption));
  }
  output_s += fovea::Since(t);
}

}  // namespace experiments::run_folder
