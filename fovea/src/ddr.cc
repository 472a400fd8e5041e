#include "fovea/ddr.h"

#include <cmath>
#include <optional>
#include <stdexcept>

#include "fovea/geometry.h"
#include "fovea/params.h"
#include "fovea/stats.h"
#include "fovea/strategy.h"
#include "fovea/timing.h"
#include "fovea/visibility.h"

namespace fovea {
namespace {

struct ViewShares {
  double mapped = 0, foveal = 0;
};

// The shares of `view`'s pixels where the map shows a patch, and a foveal one.
ViewShares MapShares(const PatchMap& map, const rig::CameraView& view) {
  cv::Mat ids;
  map.Render(view.world_T_camera, view.intrinsics, nullptr, &ids);
  long mapped = 0, foveal = 0;
  for (int y = 0; y < ids.rows; ++y)
    for (int x = 0; x < ids.cols; ++x) {
      const int id = ids.at<int>(y, x);
      if (id < 0) continue;
      ++mapped;
      if (map[id].level == PatchLevel::kFoveal) ++foveal;
    }
  if (ids.total() == 0) return {};
  return {double(mapped) / double(ids.total()), double(foveal) / double(ids.total())};
}

}  // namespace

void FoveaOptions::Check() const {
  idr.Check();
  fixation.Check();
  nl1.Check();
  sgbm.Check();
  selection.Check();
  criteria.Check();
  integration.Check();
  rig::CheckParam(params::kLoopFixations, fixations);
  rig::CheckParam(params::kLoopStallFixations, stall_fixations);
  rig::CheckParam(params::kLoopHoleFarFactor, hole_far_factor);
  rig::CheckParam(params::kLoopStallGrowth, stall_growth);
  rig::CheckParam(params::kLoopAttemptsPerFixation, attempts_per_fixation);
}

FixationOptions ResolvedFixationOptions(const FoveaOptions& options) {
  FixationOptions fixation = options.fixation;
  // Nothing lies nearer than idr.z_min_m: a fixation the servo settles
  // nearer is refused, and where the map is silent the fovea's wider search
  // starts there.
  fixation.min_depth_m = options.idr.z_min_m;
  fixation.foveal.silent_near_m = options.silent_check ? options.idr.z_min_m : 0;
  return fixation;
}

std::unique_ptr<StereoMatcher> MakeMatcher(const std::string& name, const FoveaOptions& options) {
  if (name == "nl1") return std::make_unique<Nl1Matcher>(options.nl1);
  if (name == "sgbm") return std::make_unique<SgbmMatcher>(options.sgbm);
  throw rig::InputError("key 'matcher': '" + rig::ClipForMessage(name) +
                        "' is not one of nl1, sgbm");
}

namespace {

// What the loop carries from one attempt to the next.
struct LoopState {
  rig::StereoFrame frame;  ///< the current pair, from whose left view the next target is chosen
  bool has_fixation = false;
  Tessellation current;  ///< the current fixation's
  std::vector<Eigen::Vector3d> refused;
  /// The last choice's context, kept while attempts are refused (the view,
  /// the map and the visits stay; only the refused points grow) and
  /// dropped when a fixation is absorbed.
  std::optional<SelectionContext> context;
  std::vector<SelectionContext::Visit> visits;
  std::vector<double> share_history;
  /// The strategy last weighed the reference view for
  /// selection.reference_fallback, not `context`.
  bool weighed_fallback = false;
  /// The map's share of the IDR view after the last fixation, and whether
  /// that fixation raised it by less than SelectionOptions::kStalledGrowth
  /// (reference_fallback "stalled").
  double mapped_share = 0;
  bool stalled = false;
};

// The selection context of `view` (reduced `level` times) for the loop's
// state: the map rendered into it, the current fixation's depth band, the
// visits; in another view than the current one, 2D proximity is measured
// from the current fixation point's image there.
SelectionContext MakeContext(const FoveaRun& run, const LoopState& state,
                             const rig::CameraView& full_view, bool current_view,
                             const FoveaOptions& options) {
  const int level = options.selection.resolution_level;
  const rig::CameraView view = level > 0 ? ReducedView(full_view, level) : full_view;
  SelectionContext context = SelectionContext::Make(view.gray, view, run.map, options.fixate_holes);
  context.eye_W = state.frame.left.world_T_camera;
  context.has_fixation = state.has_fixation;
  context.fixation_depth_m = state.current.fixation_depth_m;
  context.z_t_near_m = state.current.z_t_near_m;
  context.z_t_far_m = state.current.z_t_far_m;
  context.visits = state.visits;
  if (current_view && options.stay_in_idr_view)
    context.SetRegion(run.idr.final_frame.left, run.map);
  if (!current_view && state.has_fixation && !state.visits.empty())
    context.gaze_px = ProjectIntoCamera(view.world_T_camera.inverse(), view.intrinsics,
                                        state.visits.back().settled_W);
  return context;
}

// The next target: the strategy's choice, in the current view or the
// reference view as it asks (with selection.first_fixation "idr", IDR's
// point first; with selection.reference_fallback, a choice of mapped data in
// the current view, of foveal data, or of mapped data after a stalled
// fixation, gives way to a hole chosen in the reference view). With
// prescreen_holes, a hole whose window has no unique match along its ray in
// the pair it was chosen in is passed over without a move (and its
// neighbourhood with it, as a refused point's), up to kMaxPrescreened times.
SelectionSummary ChooseTarget(const FoveaRun& run, LoopState& state, FixationStrategy& strategy,
                              const FoveaOptions& options, const DepthRange& hole_depths,
                              int attempt, std::mt19937_64* rng) {
  if (attempt == 1 && options.selection.first_fixation == "idr") {
    SelectionSummary first;
    first.ok = true;
    first.point_W = run.idr.first_fixation_W;
    return first;
  }
  const bool in_reference = strategy.View() == StrategyView::kReference;
  const rig::StereoFrame& frame = in_reference ? run.idr.final_frame : state.frame;
  // The strategy keeps the weights of the context it weighed last: the
  // loop's context unless the fallback weighed the reference view since.
  const bool same_context = state.context.has_value() && !state.weighed_fallback;
  const int level = options.selection.resolution_level;
  if (!state.context)
    state.context.emplace(MakeContext(run, state, frame.left, !in_reference, options));
  constexpr int kMaxPrescreened = 8;
  // The prescreen of holes chosen in `pair`'s left view (which outlives the
  // choice: held by the pointer, not by the parameter's reference).
  auto accept_in = [&options, &hole_depths, level](const rig::StereoFrame& pair) {
    return [&options, &hole_depths, level, frame = &pair](const SelectionSummary& s) {
      return !s.in_hole || !options.prescreen_holes ||
             UniqueAlongRay(*frame, FullResolutionPixel(s.pixel, level), hole_depths,
                            options.fixation.servo);
    };
  };
  SelectionSummary chosen =
      strategy.ChooseAccepted(*state.context, run.map, &state.refused, rng, accept_in(frame),
                              kMaxPrescreened, same_context);
  state.weighed_fallback = false;
  const std::string& fallback = options.selection.reference_fallback;
  auto chose_foveal = [&] {
    return state.context->map_level.at<signed char>(static_cast<int>(chosen.pixel.y()),
                                                    static_cast<int>(chosen.pixel.x())) ==
           static_cast<signed char>(PatchLevel::kFoveal);
  };
  if (options.selection.FallsBack() && state.has_fixation && chosen.ok && !chosen.in_hole &&
      (fallback == "mapped" || (fallback == "stalled" ? state.stalled : chose_foveal()))) {
    const SelectionContext reference =
        MakeContext(run, state, run.idr.final_frame.left, false, options);
    std::vector<Eigen::Vector3d> refused = state.refused;
    const SelectionSummary hole = strategy.ChooseAccepted(
        reference, run.map, &refused, rng, accept_in(run.idr.final_frame), kMaxPrescreened, false);
    state.weighed_fallback = true;
    if (hole.ok && hole.in_hole) {
      chosen = hole;
      chosen.in_reference = true;
      state.refused = std::move(refused);
    }
  }
  // The record gives the pixel of the full-resolution view.
  if (chosen.ok) chosen.pixel = FullResolutionPixel(chosen.pixel, level);
  return chosen;
}

// Total travel of each kind of axis between two stage states, both cameras
// summed.
void AddTravel(const rig::StageState& from, const rig::StageState& to, FixationRecord* rec) {
  for (const rig::Side side : {rig::Side::kLeft, rig::Side::kRight}) {
    rec->pan_rad += std::abs(to[side].pan_rad - from[side].pan_rad);
    rec->tilt_rad += std::abs(to[side].tilt_rad - from[side].tilt_rad);
    rec->carriage_m += std::abs(to[side].carriage_m - from[side].carriage_m);
  }
}

// The record's figures of a fixation that succeeded.
void RecordFixation(const FixationResult& r, FixationRecord* rec) {
  rec->ok = true;
  rec->fixation_W = r.fixation_W;
  rec->state = r.servo.state;
  rec->servo_iterations = r.servo.iterations;
  rec->servo_residual_px = r.servo.residual_px;
  rec->servo_converged = r.servo.converged;
  rec->placement = r.placement;
  rec->baseline_m = r.baseline_m;
  rec->tessellation = r.foveal.tessellation;
  rec->tessellation.mask.release();
  rec->fovea = r.foveal.Fovea();
  rec->levels = r.foveal.levels;
  rec->time.foveal_s = r.foveal.compute_time_s;
  rec->time.match_s = r.foveal.silent_check_time_s;
  for (const LevelFigures& l : r.foveal.levels) rec->time.match_s += l.match_time_s;
}

// The reference check that IntegrationOptions asks for.
ReferenceCheckOptions ReferenceCheck(const IntegrationOptions& integration) {
  ReferenceCheckOptions check;
  check.min_ncc = integration.reference_min_ncc;
  check.pooled_min_ncc = integration.reference_pooled_min_ncc;
  check.side_px = integration.reference_side_px;
  return check;
}

// Merges a fixation's patches into the map (timed as integration) and moves
// the loop on to the fixation's view.
void Absorb(const FixationResult& r, const rig::CameraView& idr_view,
            const rig::CameraView* reference, const IntegrationOptions& integration, bool shares,
            FoveaRun* run, LoopState* state, FixationRecord* rec) {
  const auto t = Clock::now();
  state->frame = r.servo.frame;
  PatchMap fresh = r.foveal.patches;
  const int hidden = reference ? MarkHiddenFromReference(&fresh, state->frame.left, *reference,
                                                         ReferenceCheck(integration))
                               : 0;
  rec->integration = Integrate(&run->map, fresh, state->frame.left, integration);
  rec->integration.hidden_in_reference = hidden;
  if (integration.retire_idr) {
    // Covered in the IDR view or in this fixation's: the views differ in
    // where they stand and what they see past the nearer surfaces.
    std::vector<rig::CameraView> views{idr_view};
    if (integration.retire_in_fixation_view) views.push_back(state->frame.left);
    rec->integration.retired_idr = static_cast<int>(
        run->map.Remove(CoveredIdrPatches(run->map, views, integration.retire_idr_share)));
  }
  run->map.BuildIndex();
  rec->time.integrate_s = Since(t);
  rec->map_by_level = run->map.CountByLevel();
  // Only the stall rule and the stalled fallback read them: a render of the
  // whole map per fixation.
  if (shares) {
    const ViewShares s = MapShares(run->map, idr_view);
    rec->foveal_share = s.foveal;
    state->stalled = s.mapped - state->mapped_share < SelectionOptions::kStalledGrowth;
    state->mapped_share = s.mapped;
  }
  state->has_fixation = true;
  state->context.reset();
  state->visits.push_back({rec->fixation_W, rec->target_W});
  state->current = rec->tessellation;
}

// Whether the foveal share grew by less than stall_growth over the last
// stall_fixations fixations (never when that is 0).
bool Stalled(const std::vector<double>& shares, const FoveaOptions& options) {
  const int k = options.stall_fixations;
  return k > 0 && static_cast<int>(shares.size()) > k &&
         shares.back() - shares[shares.size() - 1 - k] < options.stall_growth;
}

}  // namespace

DepthRange HoleDepths(const PatchMap& idr_map, const rig::CameraView& idr_view,
                      const FoveaOptions& options) {
  DepthRange range{options.idr.z_min_m, kFarDepthM};
  if (options.hole_far_factor <= 0) return range;
  cv::Mat depth;
  idr_map.Render(idr_view.world_T_camera, idr_view.intrinsics, &depth, nullptr);
  std::vector<double> depths;
  for (auto it = depth.begin<float>(); it != depth.end<float>(); ++it)
    if (*it > 0) depths.push_back(*it);
  if (depths.empty()) return range;
  range.far_m = std::max(range.near_m, options.hole_far_factor * Quantile(depths, 0.99));
  return range;
}

FoveaRun RunFovea(rig::Rig& rig, const StereoMatcher& matcher, const FoveaOptions& options,
                  const FixationObserver& observer, const rig::CameraView* reference_view) {
  options.Check();  // once: nothing below checks again
  FoveaRun run;
  std::mt19937_64 rng(options.seed);
  // The strategy chooses in the view reduced by the selection's resolution
  // level, with its pixel sizes at that level.
  SelectionOptions selection = options.selection;
  CriteriaOptions criteria = options.criteria;
  AtResolutionLevel(selection.resolution_level, &selection, &criteria);
  const std::unique_ptr<FixationStrategy> strategy = MakeStrategy(selection, criteria);
  const FixationOptions fixation_options = ResolvedFixationOptions(options);
  // The reference view the map is read in, the left camera at the home
  // pose (IntegrationOptions::reference_min_ncc): the caller's, or captured.
  std::optional<rig::CameraView> reference;
  if (options.integration.reference_min_ncc > 0) {
    if (reference_view) {
      reference = *reference_view;
    } else {
      run.motion_time_s += rig.MoveTo(rig.Home()).motion_time_s;
      reference = rig.Capture().left;
    }
  }
  run.idr = RunIdr(rig, options.idr);
  run.map = run.idr.map;
  run.motion_time_s += run.idr.motion_time_s;
  run.compute_time_s = run.idr.compute_time_s;
  if (reference) {
    const auto t = Clock::now();
    run.idr_hidden = MarkHiddenFromReference(&run.map, run.idr.final_frame.left, *reference,
                                             ReferenceCheck(options.integration));
    run.compute_time_s += Since(t);
  }
  if (options.selection.first_fixation == "idr" && !run.idr.has_fixation) {
    run.stop_reason = "IDR found no point to fixate";
    return run;
  }
  const rig::CameraView& idr_view = run.idr.final_frame.left;
  const DepthRange hole_depths = HoleDepths(run.idr.map, idr_view, options);
  LoopState state;
  state.frame = run.idr.final_frame;
  auto record = [&](const FixationRecord& rec) {
    run.compute_time_s += rec.time.ComputeS();
    run.records.push_back(rec);
    if (observer) observer(run.records.back(), run.map);
  };
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
    rec.selection = ChooseTarget(run, state, *strategy, options, hole_depths, attempt, &rng);
    rec.time.select_s = Since(t);
    if (!rec.selection.ok) {
      rec.why = rec.selection.why;
      record(rec);
      run.stop_reason = "nothing left to fixate: " + rec.why;
      break;
    }
    rec.target_W = rec.selection.point_W;
    // A hole's depth is the nearest mapped depth, a guess: the servo searches
    // every depth the scene allows.
    const std::optional<DepthRange> guessed =
        rec.selection.in_hole ? std::optional<DepthRange>(hole_depths) : std::nullopt;
    const rig::StageState before = rig.State();
    const FixationResult r = Fixate(rig, run.map, rec.target_W, matcher, fixation_options,
                                    run.fixations_done + 1, guessed);
    AddTravel(before, rig.State(), &rec);
    rec.time.verge_s = r.verge_time_s;
    rec.time.servo_s = r.servo_wall_s;
    rec.motion_time_s = r.motion_time_s;
    run.motion_time_s += r.motion_time_s;
    if (!r.ok) {
      rec.why = r.why;
      state.refused.push_back(rec.target_W);
      record(rec);
      continue;
    }
    rec.fixation = ++run.fixations_done;
    RecordFixation(r, &rec);
    Absorb(r, idr_view, reference ? &*reference : nullptr, options.integration,
           options.stall_fixations > 0 ||
               (options.selection.FallsBack() && options.selection.reference_fallback == "stalled"),
           &run, &state, &rec);
    record(rec);
    state.share_history.push_back(rec.foveal_share);
    if (Stalled(state.share_history, options)) {
      run.stop_reason = "coverage stopped growing (foveal share grew by less than " +
                        std::to_string(options.stall_growth) + " over " +
                        std::to_string(options.stall_fixations) + " fixations)";
      break;
    }
  }
  return run;
}

}  // namespace fovea
