// Initial depth recovery (IDR): adaptive variable-baseline stereo with
// parallel cameras (paper section II; design note "IDR").
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "fovea/patch.h"
#include "fovea/zero_crossings.h"
#include "rig/rig.h"

namespace fovea {

/// A search window per crossing: anchors (positions on a row with a disparity
/// range) near a crossing define where its match may lie. Stage 0 uses one
/// global range instead.
struct DisparityWindows {
  bool global = true;
  double global_lo_px = 0, global_hi_px = 0;
  /// Per row: anchors sorted by x.
  struct Anchor {
    float x_px, lo_px, hi_px;
  };
  std::vector<std::vector<Anchor>> rows;
  double reach_px = 4;  ///< anchors within this horizontal distance count
  int row_reach = 1;    ///< and within this many rows

  /// The disparity range for a crossing at (x, y); false if nothing predicts it.
  bool Window(double x_px, int y_px, double* lo_px, double* hi_px) const;
};

struct ZcMatchOptions {
  double orientation_tolerance_rad = 30 * 3.14159265358979 / 180;
  /// FOVEA rejects a crossing whose window holds several candidates. Classic
  /// matchers instead take the candidate of smallest disparity; that policy
  /// is here for comparison (it turns ambiguity into wrong matches).
  bool take_nearest_when_ambiguous = false;
  void Check() const;  ///< throws rig::InputError naming the key (fovea/params.h)
};

/// Figures of one matching pass (counts of left crossings unless named).
struct ZcMatchStats {
  int left_crossings = 0, right_crossings = 0;
  int searched = 0;      ///< left crossings with a search window
  int no_candidate = 0;  ///< window held no compatible crossing
  int ambiguous = 0;     ///< window held more than one
  int unique = 0;        ///< exactly one
  int inconsistent = 0;  ///< unique left-to-right but not confirmed right-to-left
  int matches = 0;       ///< consistent both ways
  /// Share of crossings with candidates whose window held exactly one.
  double UnambiguousShare() const;
};

/// A consistent match: left crossing index, right crossing index, disparity
/// x_left - x_right in pixels (sub-pixel).
struct ZcMatch {
  int left, right;
  double disparity_px;
};

/// Scanline matching of zero crossings between rectified images (same
/// polarity, orientation within tolerance, disparity inside the window),
/// left-to-right and right-to-left; only unique matches that agree both ways
/// are kept (paper section II-A, occlusion).
std::vector<ZcMatch> MatchZeroCrossings(const ZeroCrossingImage& left,
                                        const ZeroCrossingImage& right,
                                        const DisparityWindows& left_windows,
                                        const DisparityWindows& right_windows,
                                        const ZcMatchOptions& options, ZcMatchStats* stats);

/// Flags isolated outliers: samples whose disparity differs by more than
/// `jump_px` from the median of their neighbours within `radius_px` (at
/// least 3 of them). Isolated wrong matches would otherwise look like depth
/// discontinuities.
std::vector<char> IsolatedOutliers(const std::vector<DisparitySample>& samples, double radius_px,
                                   double jump_px);

/// Flags samples that lie at a depth discontinuity: another sample within
/// `radius_px`, or the next sample along its row at any distance, whose
/// disparity differs by more than `jump_px`.
std::vector<char> NearDiscontinuity(const std::vector<DisparitySample>& samples, double radius_px,
                                    double jump_px);

/// Expansion factor (paper section II-B): the largest k such that the
/// uncertainty windows of crossings s_min apart cannot overlap,
/// k (1 + g) <= s_min with g = d_max s_min tan(theta_max) / f the disparity
/// difference a surface slanted by theta_max makes across s_min.
double ExpansionFactor(double s_min_px, double d_max_px, double focal_px, double max_slant_rad);

struct IdrOptions {
  ZeroCrossingOptions zero_crossings;
  ZcMatchOptions matching;
  double unique_share = 0.90;    ///< share of crossings kept unambiguous at B0
  double z_min_m = 0.40;         ///< nearest surface
  double max_slant_deg = 60;     ///< for the expansion factor
  double max_expansion = 4.0;    ///< cap on k per stage
  double min_expansion = 1.1;    ///< below this, expanding is not worth a stage
  double vergent_search_px = 4;  ///< P: the vergent stage searches +-P px
  /// Baseline of the vergent stage, for the termination rule. Deliberately
  /// not tied to foveal.baseline_m (0.04): with 0.06 IDR stops at a 0.012 m
  /// baseline instead of 0.048 m, and the coarser map cost fovea run
  /// coverage (two_planes 0.995 -> 0.949, three_surfaces 0.947 -> 0.927,
  /// seed 0) and two_planes' near-then-far order.
  double vergent_baseline_m = 0.12;
  int max_stages = 6;  ///< budget: IDR always ends
  int patch_size_px = 16;
  PlaneFitOptions plane_fit;
  /// Beyond the paper (issue 19): blocks whose plane is seen more obliquely
  /// than this, degrees, give no patch (as foveal.max_view_angle_deg; the
  /// expansion rule above already assumes no steeper slant); 0: any angle,
  /// the paper's rule (README, "The map's trust").
  double max_view_angle_deg = 60;
  /// Matches with a neighbour within 2 sigma whose disparity differs by more
  /// than this lie at a depth discontinuity, where the LoG's blur displaces
  /// the crossings: they are left out of the patches.
  double discontinuity_jump_px = 2.0;
  /// Fixed initial baseline instead of the period rule (0 = use the rule);
  /// for experiments that show why the rule matters.
  double fixed_initial_baseline_m = 0;
  void Check() const;  ///< throws rig::InputError naming the key (fovea/params.h)
};

/// Figures of one baseline stage, for the experiment harness.
struct IdrStage {
  double baseline_m = 0;
  double search_limit_px = 0;    ///< d_max searched (stage 0) or widest window (later)
  double expansion_factor = 1;   ///< applied after this stage (1 at the last)
  double min_separation_px = 0;  ///< s_min at this stage
  double max_disparity_px = 0;   ///< largest matched disparity
  ZcMatchStats stats;
  double motion_time_s = 0;
  double compute_time_s = 0;
};

struct IdrResult {
  std::vector<IdrStage> stages;
  std::string stop_reason;
  rig::StereoFrame final_frame;                  ///< the pair the patches come from
  std::vector<DisparitySample> final_samples;    ///< matched crossings at the final baseline
  std::vector<Eigen::Vector2d> final_unmatched;  ///< searched crossings left unmatched
  PatchMap map;                                  ///< IDR patches
  bool has_fixation = false;
  Eigen::Vector3d first_fixation_W = Eigen::Vector3d::Zero();
  int first_fixation_patch = -1;
  double compute_time_s = 0, motion_time_s = 0;
};

/// Runs IDR on a rig: cameras parallel and level, the left carriage parked
/// at its innermost position, the right carriage moved to set each baseline.
/// Throws rig::RigError if the rig refuses a move.
IdrResult RunIdr(rig::Rig& rig, const IdrOptions& options);

/// Patches from disparity samples of a rectified parallel pair (left view),
/// one per patch_size block that fits, each cut back to half a pixel beyond
/// its inliers' extent (so that it never reaches over a depth step where the
/// features stop short of the edge); corners back-projected with Z = f B / d.
/// With max_view_angle_deg > 0, a block whose plane is seen more obliquely
/// than that from the left camera gives no patch (Patch::ViewAngleRad).
PatchMap PatchesFromDisparities(const std::vector<DisparitySample>& samples,
                                const rig::CameraView& left, double baseline_m, int patch_size_px,
                                const PlaneFitOptions& options, PatchLevel level,
                                double max_view_angle_deg = 0);

}  // namespace fovea
