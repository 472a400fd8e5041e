// The full FOVEA loop (paper section IV; design note "DDR"): IDR, then
// fixation after fixation: choose, verge, servo, tessellate, match, patch,
// integrate, record.
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "fovea/foveal.h"
#include "fovea/idr.h"
#include "fovea/integration.h"
#include "fovea/selection.h"
#include "fovea/sgbm.h"
#include "rig/rig.h"

namespace fovea {

struct FoveaOptions {
  IdrOptions idr;
  FixationOptions fixation;
  Nl1Options nl1;    ///< the NL1 per-level matcher's (MakeMatcher)
  SgbmOptions sgbm;  ///< the StereoSGBM per-level matcher's (MakeMatcher)
  SelectionOptions selection;
  CriteriaOptions criteria;
  IntegrationOptions integration;
  int fixations = 25;  ///< successful fixations to make
  /// Fixate only points inside the IDR view: the region the run maps; and,
  /// with a reference view, none on a patch it does not see
  /// (SelectionContext::region_hidden).
  bool stay_in_idr_view = true;
  /// Beyond the paper: pixels the map is silent at are fixation candidates
  /// too, at the depth of the nearest mapped pixel (SelectionContext::Make).
  bool fixate_holes = true;
  /// Beyond the paper: a hole chosen as the next target is first looked at
  /// in the current pair; if its window has no unique match along its ray
  /// (UniqueAlongRay over every depth from idr.z_min_m), it is passed over
  /// without moving the rig, as a refused point would be.
  bool prescreen_holes = true;
  /// Beyond the paper: a hole's depth is unknown, so its servo search (and
  /// its prescreen) spans the depths from idr.z_min_m to this factor times
  /// the farthest depth IDR mapped in its view (the 99th percentile of the
  /// IDR map's depths there): IDR saw nothing farther anywhere in the view,
  /// and a match far beyond it is a false one (a texture's copy at a
  /// disparity of nearly zero). 0: to infinity.
  double hole_far_factor = 1.5;
  /// Beyond the paper: where the map is silent, the fovea also searches every
  /// depth from idr.z_min_m (the scene's nearest) to infinity and drops Z_T
  /// matches that search contradicts (sets FovealOptions::silent_near_m;
  /// false: the paper's Z_T search only).
  bool silent_check = true;
  /// Stop early when the map's foveal share of the IDR view grew by less
  /// than `stall_growth` over this many fixations in a row (0 = never).
  int stall_fixations = 0;
  double stall_growth = 0.002;
  /// Attempts allowed per fixation wanted, so that a run of refused points
  /// always ends.
  int attempts_per_fixation = 3;
  uint64_t seed = 0;   ///< the one generator's seed
  void Check() const;  ///< throws rig::InputError naming the key (fovea/params.h)
};

/// The options every fixation of a run uses, resolved once from the run's:
/// nothing lies nearer than idr.z_min_m, so a servo settling nearer is
/// refused (FixationOptions::min_depth_m) and, with silent_check, the
/// fovea's wider search where the map is silent starts there
/// (FovealOptions::silent_near_m). RunFovea, `fovea fixate` and `fovea bench
/// fixation` all fixate with it.
FixationOptions ResolvedFixationOptions(const FoveaOptions& options);

/// The per-level matcher a run names ("nl1" or "sgbm"), with the run's
/// options for it. Throws rig::InputError for another name.
std::unique_ptr<StereoMatcher> MakeMatcher(const std::string& name, const FoveaOptions& options);

/// Wall-clock seconds by stage of one fixation.
struct StageTimes {
  double select_s = 0, verge_s = 0, servo_s = 0, foveal_s = 0, match_s = 0, integrate_s = 0;
  double ComputeS() const { return select_s + verge_s + foveal_s + integrate_s; }
};

/// Everything one attempt did, for the records.
struct FixationRecord {
  int attempt = 0;   ///< 1-based
  int fixation = 0;  ///< 1-based index among successful ones (0 if refused)
  bool ok = false;
  std::string why;             ///< when refused
  SelectionSummary selection;  ///< how the target was chosen (first one: from IDR)
  Eigen::Vector3d target_W = Eigen::Vector3d::Zero();
  Eigen::Vector3d fixation_W = Eigen::Vector3d::Zero();
  rig::StageState state;
  Placement placement = Placement::kSymmetric;  ///< of the carriages
  double baseline_m = 0;  ///< vergent baseline asked for (FixationResult::baseline_m)
  int servo_iterations = 0;
  double servo_residual_px = 0;
  bool servo_converged = false;
  Tessellation tessellation;  ///< without its images (cleared)
  FoveaFigures fovea;         ///< level 0's rectangle, in the frame matched in, and its turns
  std::vector<LevelFigures> levels;
  IntegrationStats integration;
  std::array<int, 3> map_by_level{0, 0, 0};
  /// The map's foveal share of the IDR view, as the loop sees it (computed
  /// only for the stall rule, loop.stall_fixations > 0, and when the
  /// "stalled" fallback is in force, SelectionOptions::FallsBack; else 0).
  double foveal_share = 0;
  double motion_time_s = 0;
  /// The attempt's stage travel, from the state before it to the state after
  /// it, summed over both cameras: pan and tilt in radians, carriages in
  /// metres.
  double pan_rad = 0, tilt_rad = 0, carriage_m = 0;
  StageTimes time;
};

struct FoveaRun {
  IdrResult idr;
  PatchMap map;
  /// IDR patches the reference camera does not see (Patch::
  /// hidden_in_reference; IntegrationOptions::reference_min_ncc).
  int idr_hidden = 0;
  std::vector<FixationRecord> records;
  int fixations_done = 0;
  std::string stop_reason;
  double motion_time_s = 0;  ///< IDR's and every fixation's
  double compute_time_s = 0;
};

/// The depths a hole's servo search and prescreen span: from idr.z_min_m to
/// options.hole_far_factor times the 99th percentile of the depths `idr_map`
/// shows in `idr_view` (to kFarDepthM with factor 0 or an empty map).
DepthRange HoleDepths(const PatchMap& idr_map, const rig::CameraView& idr_view,
                      const FoveaOptions& options);

/// Called after every attempt with the record and the map as it stands.
using FixationObserver = std::function<void(const FixationRecord&, const PatchMap&)>;

/// Runs FOVEA on a rig. Throws rig::RigError if the rig fails; points that
/// cannot be fixated are recorded and skipped. `reference_view`, if given,
/// is the left camera's image at the home pose (IntegrationOptions::
/// reference_min_ncc); without it, a run with the check on moves home and
/// captures one first.
FoveaRun RunFovea(rig::Rig& rig, const StereoMatcher& matcher, const FoveaOptions& options,
                  const FixationObserver& observer = {},
                  const rig::CameraView* reference_view = nullptr);

}  // namespace fovea
