#include "fovea/ddr.h"

#include <stdexcept>

#include "fovea/geometry.h"
#include "fovea/timing.h"

namespace fovea {
namespace {

// Share of the view's pixels where the map shows foveal data.
double FovealShare(const PatchMap& map, const rig::CameraView& view) {
  cv::Mat ids;
  map.Render(view.world_T_camera, view.intrinsics, nullptr, &ids);
  long foveal = 0;
  for (int y = 0; y < ids.rows; ++y)
    for (int x = 0; x < ids.cols; ++x) {
      const int id = ids.at<int>(y, x);
      if (id >= 0 && map[id].level == PatchLevel::kFoveal) ++foveal;
    }
  return ids.total() ? double(foveal) / double(ids.total()) : 0.0;
}

}  // namespace

void CriteriaOptions::Check() const {
  auto bad = [](const std::string& what) { throw std::invalid_argument(what); };
  if (!(gradient_blur_px > 0)) bad("criteria.gradient_blur_px must be > 0");
  if (!(suppressed_weight >= 0 && suppressed_weight <= 1))
    bad("criteria.suppressed_weight must be in [0, 1]");
  if (!(suppression_radius_m >= 0)) bad("criteria.suppression_radius_m must be >= 0");
  if (!(peripheral_weight >= 0 && peripheral_weight <= 1))
    bad("criteria.peripheral_weight must be in [0, 1]");
  if (!(revisit_radius_m >= 0)) bad("criteria.revisit_radius_m must be >= 0");
  if (!(proximity_2d_scale_px > 0)) bad("criteria.proximity_2d_scale_px must be > 0");
  if (!(proximity_3d_low >= 0 && proximity_3d_low <= 1))
    bad("criteria.proximity_3d_low must be in [0, 1]");
}

std::vector<std::shared_ptr<const FixationCriterion>> CriteriaOptions::Make() const {
  std::vector<std::shared_ptr<const FixationCriterion>> c;
  if (gradient) c.push_back(std::make_shared<GradientAttraction>(gradient_blur_px));
  if (suppression)
    c.push_back(std::make_shared<LocalSuppression>(suppressed_weight, suppression_radius_m,
                                                   peripheral_weight, revisit_radius_m));
  if (proximity_2d) c.push_back(std::make_shared<Proximity2D>(proximity_2d_scale_px));
  if (proximity_3d) c.push_back(std::make_shared<Proximity3D>(proximity_3d_low));
  return c;
}

void FoveaOptions::Check() const {
  idr.Check();
  fixation.Check();
  selection.Check();
  criteria.Check();
  integration.Check();
  if (fixations < 1 || fixations > 10000)
    throw std::invalid_argument("fixations must be 1 to 10000, got " + std::to_string(fixations));
  if (stall_fixations < 0) throw std::invalid_argument("stall_fixations must be >= 0");
  if (!(stall_growth >= 0)) throw std::invalid_argument("stall_growth must be >= 0");
  if (attempts_per_fixation < 1) throw std::invalid_argument("attempts_per_fixation must be >= 1");
}

FoveaRun RunFovea(rig::Rig& rig, const StereoMatcher& matcher, const FoveaOptions& options,
                  const FixationObserver& observer) {
  options.Check();
  FoveaRun run;
  std::mt19937_64 rng(options.seed);
  const FixationSelector selector(options.criteria.Make(), options.selection);

  run.idr = RunIdr(rig, options.idr);
  run.map = run.idr.map;
  run.motion_time_s = run.idr.motion_time_s;
  run.compute_time_s = run.idr.compute_time_s;
  if (!run.idr.has_fixation) {
    run.stop_reason = "IDR found no point to fixate";
    return run;
  }
  const rig::CameraView& idr_view = run.idr.final_frame.left;

  // The current view and fixation, from which the next one is chosen.
  rig::CameraView view = idr_view;
  bool has_fixation = false;
  Tessellation current;
  std::vector<Eigen::Vector3d> refused, fixated;
  std::vector<double> share_history;
  // Nothing lies nearer than idr.z_min_m: a fixation the servo settles
  // nearer is refused, and where the map is silent the fovea's wider search
  // starts there.
  FixationOptions fixation_options = options.fixation;
  fixation_options.min_depth_m = options.idr.z_min_m;
  fixation_options.foveal.silent_near_m = options.silent_check ? options.idr.z_min_m : 0;
  const int max_attempts = options.fixations * options.attempts_per_fixation;
  run.stop_reason = "done: " + std::to_string(options.fixations) + " fixations";
  for (int attempt = 1; run.fixations_done < options.fixations; ++attempt) {
    if (attempt > max_attempts) {
      run.stop_reason = "attempt budget spent (" + std::to_string(max_attempts) + " attempts)";
      break;
    }
    FixationRecord rec;
    rec.attempt = attempt;
    auto t = Clock::now();
    if (attempt == 1) {
      rec.selection.ok = true;
      rec.selection.point_W = run.idr.first_fixation_W;
    } else {
      SelectionContext context =
          SelectionContext::Make(view.gray, view, run.map, options.fixate_holes);
      context.has_fixation = has_fixation;
      context.fixation_depth_m = current.fixation_depth_m;
      context.z_t_near_m = current.z_t_near_m;
      context.z_t_far_m = current.z_t_far_m;
      context.fixated_W = fixated;
      if (options.stay_in_idr_view) context.region = idr_view;
      rec.selection = selector.Choose(context, run.map, refused, &rng);
    }
    rec.time.select_s = Since(t);
    if (!rec.selection.ok) {
      rec.why = rec.selection.why;
      run.records.push_back(rec);
      if (observer) observer(run.records.back(), run.map);
      run.stop_reason = "nothing left to fixate: " + rec.why;
      break;
    }
    rec.target_W = rec.selection.point_W;
    // A hole's depth is the nearest mapped depth, a guess: the servo searches
    // every depth from the nearest the scene allows to infinity.
    const std::optional<DepthRange> guessed =
        rec.selection.in_hole
            ? std::optional<DepthRange>(DepthRange{options.idr.z_min_m, kFarDepthM})
            : std::nullopt;
    const FixationResult r = Fixate(rig, run.map, rec.target_W, matcher, fixation_options,
                                    run.fixations_done + 1, guessed);
    rec.time.verge_s = r.verge_time_s;
    rec.time.servo_s = r.servo_wall_s;
    rec.motion_time_s = r.motion_time_s;
    run.motion_time_s += r.motion_time_s;
    if (!r.ok) {
      rec.why = r.why;
      refused.push_back(rec.target_W);
      run.compute_time_s += rec.time.ComputeS();
      run.records.push_back(rec);
      if (observer) observer(run.records.back(), run.map);
      continue;
    }
    rec.ok = true;
    rec.fixation = ++run.fixations_done;
    rec.fixation_W = r.fixation_W;
    rec.state = r.servo.state;
    rec.servo_iterations = r.servo.iterations;
    rec.servo_residual_px = r.servo.residual_px;
    rec.servo_converged = r.servo.converged;
    rec.placement = r.placement;
    rec.tessellation = r.foveal.tessellation;
    rec.tessellation.vertical_disparity_px.release();
    rec.tessellation.mask.release();
    rec.levels = r.foveal.levels;
    rec.time.foveal_s = r.foveal.compute_time_s;
    for (const LevelFigures& l : r.foveal.levels) rec.time.match_s += l.match_time_s;

    t = Clock::now();
    view = r.servo.frame.left;
    rec.integration = Integrate(&run.map, r.foveal.patches, view, options.integration);
    run.map.BuildIndex();
    rec.time.integrate_s = Since(t);
    rec.map_by_level = run.map.CountByLevel();
    rec.foveal_share = FovealShare(run.map, idr_view);
    has_fixation = true;
    fixated.push_back(rec.fixation_W);
    // The point aimed at stays unmapped where the servo settled elsewhere (a
    // hole's guessed depth, a false match): suppress it as well.
    if ((rec.target_W - rec.fixation_W).norm() > options.criteria.revisit_radius_m)
      fixated.push_back(rec.target_W);
    current = rec.tessellation;
    run.compute_time_s += rec.time.ComputeS();
    run.records.push_back(rec);
    if (observer) observer(run.records.back(), run.map);

    share_history.push_back(rec.foveal_share);
    const int k = options.stall_fixations;
    if (k > 0 && static_cast<int>(share_history.size()) > k &&
        share_history.back() - share_history[share_history.size() - 1 - k] < options.stall_growth) {
      run.stop_reason = "coverage stopped growing (foveal share grew by less than " +
                        std::to_string(options.stall_growth) + " over " + std::to_string(k) +
                        " fixations)";
      break;
    }
  }
  return run;
}

}  // namespace fovea
