// Foveated vergent stereo at one fixation (paper section III; design note
// "Foveated vergent stereo"): verge, servo, tessellate, match each level,
// make patches.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <string>
#include <vector>

#include "fovea/fixation_frame.h"
#include "fovea/matcher.h"
#include "fovea/patch.h"
#include "fovea/placement.h"
#include "fovea/servo.h"
#include "fovea/tessellation.h"
#include "fovea/vergence.h"
#include "rig/rig.h"

namespace fovea {

struct FovealOptions {
  TessellationOptions tessellation;
  int fovea_patch_px = 8;  ///< patch size at level 0, in its pixels
  /// Patch size at coarser levels in full-resolution pixels: level k uses
  /// blocks of max(4, periphery_patch_px / 2^k) of its pixels.
  int periphery_patch_px = 32;
  /// The fit tolerance is 0.7 level-0 pixels, beyond the paper's 1: a
  /// pixel of disparity is 1.4% of depth at 1 m, and the tighter fit left
  /// 22% fewer wrong pixels over the accuracy benchmark (README, issue 19).
  /// Peripheral levels use max(0.25, it / their scale) of their pixels.
  PlaneFitOptions plane_fit{/*min_support=*/12, /*fit_tolerance_px=*/0.7, /*min_inlier_share=*/0.8,
                            /*require_quadrants=*/true};
  double map_margin_px = 2.0;     ///< search +- this many level pixels around the map's prediction
  double coarse_margin_px = 1.5;  ///< and around the coarser level's estimate
  /// Where the map is silent and no coarser estimate exists, the paper
  /// searches the Z_T band about the fixation depth, which takes a false
  /// match in the band for a surface outside it. With this > 0 such pixels
  /// are also searched over every depth from this many metres to infinity,
  /// and a band match is dropped where that wider search matched outside the
  /// band with at least `silent_confidence` (a repeated texture's copies
  /// leave its confidence low: the band's prior stands). RunFovea sets it
  /// to idr.z_min_m (FoveaOptions::silent_check, ResolvedFixationOptions);
  /// 0: the paper's band search only.
  double silent_near_m = 0;
  double silent_confidence = 0.2;
  /// The wide search runs once per fixation, at 2^silent_check_level
  /// full-resolution pixels per pixel, over every pixel the map is silent
  /// at (its cost grows with the depth range in pixels: at full resolution
  /// it would cost more than all the levels' band searches together).
  int silent_check_level = 2;
  /// Beyond the paper: at a pixel the map is silent at, where the wide
  /// search matched outside the band with at least `silent_confidence`,
  /// and its neighbours' matches lie within one of its pixels (no depth
  /// edge), the pixel is searched about that match (+- coarse_margin_px
  /// beyond its pixel) instead of over the band, where any match would be
  /// dropped: surfaces outside Z_T get mapped. Off: over the accuracy
  /// benchmark it moved good_coverage within the seed-to-seed spread and
  /// put two runs' edge_bad_share over 0.15 (README, "The map's trust").
  bool silent_outside_seed = false;
  /// Beyond the paper: pixels within this many level pixels of a pixel whose
  /// disparity is more than edge_jump_px smaller are dropped before the
  /// patches are fitted (window matching fattens a nearer surface over a
  /// farther one's pixels beside their edge); 0: none. A window's half width.
  int edge_erosion_px = 3;
  /// Beyond the paper (issue 19): the erosion beside disparity jumps at the
  /// fovea's level (level 0) only, the peripheral levels keeping
  /// edge_erosion_px; -1: the same at every level. The margin beside
  /// unmatched runs (edge_hole_px) keeps edge_erosion_px at every level,
  /// the fovea's too. 4 with periphery_half_agreement 2: over the
  /// accuracy benchmark the two together lifted good coverage and kept
  /// every accuracy line (README, "The map's trust").
  int fovea_edge_erosion_px = 4;
  double edge_jump_px = 1.5;
  /// Beyond the paper: matches within edge_erosion_px of a row or column run
  /// of at least this many unmatched pixels do not set a patch's footprint
  /// (they still count in its fit): beside an edge whose farther side goes
  /// unmatched (outside the search band, or without texture) the window
  /// still matches the nearer texture over the edge, and no farther match
  /// shows the jump. 0: none. 4 (was 7, a window's width): fewer wrong
  /// pixels beside edges over the accuracy benchmark, most likely because
  /// the half-occluded strip beside a nearer surface keeps a few false
  /// matches that cut it into shorter runs (README, "The map's trust").
  int edge_hole_px = 4;
  /// Beyond the paper: a block becomes one patch only if its inliers fill
  /// enough of it, else it is split into quarters, and a patch covers only
  /// its inliers' extent, so that no patch reaches over a depth edge or a
  /// strip without data (BlockOptions; min_fill_share = 0 and
  /// clip_to_inliers = false: the paper's whole blocks).
  BlockOptions blocks;
  /// Beyond the paper: at the peripheral levels (index > 0) blocks are split
  /// no smaller than this, level pixels (and no smaller than
  /// blocks.min_block_px): a quarter smaller than the matching window rests
  /// on matches whose windows overlap, and beside an edge on windows that
  /// straddle it. 16 with 32-pixel peripheral patches: never split.
  int periphery_min_block_px = 16;
  /// Beyond the paper (issue 19): at the peripheral levels, a block that is
  /// not whole and is split no further is tried as two halves, each kept
  /// where a whole block beside it agrees with its plane within this many
  /// fit tolerances (BlockOptions::half_agreement); 0: none. 2, with
  /// fovea_edge_erosion_px 4 (README, "The map's trust").
  double periphery_half_agreement = 2;
  /// Beyond the paper (issue 20): tessellate, match and triangulate in the
  /// pair's fixation frame (ToFixationFrame: both cameras turned virtually
  /// so that the rows of a tilted verged pair no longer twist against each
  /// other and both optical axes meet); false: the paper's unrectified
  /// images. Fixate hands it to the servo (ServoOptions::rectify), which
  /// measures in that frame and passes it on (ServoResult::measured).
  bool rectify = true;
  /// Beyond the paper (issue 19, off by default: README, "The map's
  /// trust"): with this > 0 the peripheral levels do not match the pixels,
  /// outside the finer level's rectangle, where the map shows a foveal patch
  /// within this many full-resolution pixels of a depth jump or of a pixel
  /// it does not map (FovealNearEdges): there such matches carry the foveal
  /// side's depth into peripheral blocks that straddle the edge. 0: every
  /// pixel of every level.
  int skip_foveal_edge_px = 0;
  /// Beyond the paper (issue 19): with this > 0 a block gives no patch when
  /// its plane is seen more obliquely than this, degrees between its normal
  /// and the left camera's line of sight to its centre (Patch::ViewAngleRad).
  /// Window matching assumes a surface seen face on; seen obliquely, the two
  /// cameras foreshorten its texture differently (at 1 m the 0.06 m pair's
  /// lines of sight differ by 3.4 degrees: one image stretches the texture
  /// 16-20% more than the other at 70 degrees, 4% at 30), and at a curved
  /// surface's grazing limb the plane lands 1-5% too far. 0: any angle, the
  /// paper's rule (README, "The map's trust").
  double max_view_angle_deg = 70;
  /// Beyond the paper (issue 19): the outermost level, where it reaches
  /// beyond the finer level's rectangle, is matched in the pair turned into
  /// a rectified one (ToRectifiedFrame), where vertical disparity is zero at
  /// every pixel; in the verged pair it passes half a level pixel outside
  /// the rectangle the paper's tessellation gives that level and grows to
  /// several towards the corners at a near fixation, and the row-wise
  /// matchers miss there. The fixation frame still matches it about the
  /// finer level, for that level's coarse estimates. false: the verged
  /// pair's rows everywhere, the paper's scheme.
  bool rectified_periphery = true;
  /// silent_confidence for the rectified periphery: there a band match at a
  /// pixel the map is silent at is dropped where the wide search matched
  /// outside the band with at least this confidence. 0 (any match outside
  /// drops it): matching far more of the periphery than the verged rows,
  /// the rectified pair also found more of a repeated texture's copies in
  /// the band (README, "The map's trust").
  double rectified_silent_confidence = 0;
  /// With rectified_periphery (issue 19, measured in the README, "The
  /// map's trust"): the rectified periphery is matched at full resolution
  /// rather than at its level's. Its blocks keep the level's size in level
  /// pixels (16 full-resolution pixels with two levels), its fit the
  /// level-0 tolerance, and its patches the level's index (peripheral,
  /// resolution level 1 with two levels) in the map and the scores. Fewer
  /// wrong pixels, beside depth edges most, at about twice the compute per
  /// fixation; false: at the level's resolution, the faster choice.
  bool rectified_periphery_full_resolution = true;
  void Check() const;  ///< throws rig::InputError naming the key (fovea/params.h)
};

/// Figures of one resolution level.
struct LevelFigures {
  int level = 0;
  cv::Rect rect;  ///< full-resolution pixels the level covers
  int searched = 0, matched = 0, patches = 0;
  int outside_band =
      0;  ///< band matches dropped: the wider search matched outside (FovealOptions::silent_near_m)
  int eroded = 0;  ///< matches dropped beside a disparity jump (FovealOptions::edge_erosion_px)
  double match_time_s = 0;  ///< search ranges, matching and patches; the wide search aside
};

/// The fovea at one fixation: level 0's rectangle, in pixels of the frame
/// it was matched in, its share of the image, and that frame's turns
/// (FixationFrame).
struct FoveaFigures {
  int width_px = 0, height_px = 0;
  double image_share = 0;
  bool resampled = false;  ///< matched in a resampled fixation frame
  double left_roll_rad = 0, right_roll_rad = 0, right_turn_rad = 0;
};

struct FovealResult {
  /// The frame everything below is in (the fixation frame, or the original
  /// pair when foveal.rectify is off): rects, disparities, the mask.
  FixationFrame frame;
  Tessellation tessellation;
  std::vector<cv::Mat> disparity_px;  ///< per level, at its resolution (NaN = none)
  /// With FovealOptions::rectified_periphery, the outermost level's
  /// disparities in the rectified pair (ToRectifiedFrame; its level's
  /// resolution, NaN = none); disparity_px then holds that level only about
  /// the finer one. Empty otherwise.
  cv::Mat rectified_periphery_px;
  std::vector<LevelFigures> levels;
  PatchMap patches;  ///< foveal (level 0) and peripheral patches
  double compute_time_s = 0;
  double silent_check_time_s = 0;  ///< the wide search (FovealOptions::silent_near_m)
  FoveaFigures Fovea() const;
};

/// Window matching carries a nearer surface's disparity over a farther
/// one's pixels beside their edge (a window straddling the edge is dominated
/// by the nearer texture, in both directions of the left-right check):
/// invalidates (sets to NaN) the pixels of `disparity` (CV_32F, NaN = none)
/// within `radius` pixels of a pixel whose disparity is more than `jump_px`
/// smaller. Only a surface sets a limit: a pixel with at least 3 of its 8
/// neighbours within `jump_px` of it; NaN pixels and isolated mismatches do
/// not. Returns how many (FovealOptions::edge_erosion_px).
int ErodeAtDisparityJumps(int radius, double jump_px, cv::Mat* disparity);

/// The pixels (CV_8U, 1) within `radius` pixels, along a row or a column, of
/// a run of at least `run_px` NaN pixels of `disparity` (CV_32F) on that
/// line; all 0 if either is 0 (FovealOptions::edge_hole_px).
cv::Mat BesideUnmatchedRuns(const cv::Mat& disparity, int radius, int run_px);

/// The pixels (CV_8U, 1) where the map, rendered as `depth` and `ids`
/// (PatchMap::Render), shows a foveal patch within `radius` pixels of a
/// depth jump (more than PatchMap::kSameSurfaceShare of the depth between
/// 4-neighbours) or of a pixel the map leaves empty
/// (FovealOptions::skip_foveal_edge_px); empty when radius is 0.
cv::Mat FovealNearEdges(const PatchMap& map, const cv::Mat& depth, const cv::Mat& ids, int radius);

/// Matches a verged pair that fixates p_W, level by level, coarse to fine,
/// with the range at each pixel bounded by `map` (or by Z_T where the map is
/// silent), and fits patches: `fixation` is recorded in each patch. `frame`
/// is the pair as it is matched (ToFixationFrame, or OriginalFrame with
/// foveal.rectify off): the servo's ServoResult::measured.
/// `options` must have passed Check(): the run checks them once, before
/// its work (RunFovea, RunIdr, RunConfig::Check), never per call.
FovealResult FovealStereo(const FixationFrame& frame, const Eigen::Vector3d& fixation_W,
                          const PatchMap& map, const StereoMatcher& matcher,
                          const FovealOptions& options, int fixation = 0);

/// Everything one fixation does on the rig.
struct FixationOptions {
  VergenceOptions vergence;
  ServoOptions servo;
  FovealOptions foveal;
  /// Vergent baseline. A narrow one keeps the vergence angle small: a
  /// larger fovea and Z_T, and a thinner strip of surface hidden from one
  /// camera beside a nearer surface's edge. 0.04 (was 0.06): over the
  /// accuracy benchmark, with the map's patches fused across levels, good
  /// coverage rose by 0.02 on its seeds and on held-out ones, every
  /// accuracy line held, and wrong pixels rose by about a quarter; 0.03
  /// broke the catalog's RMSE line (README, "The map's trust").
  double baseline_m = 0.04;
  /// Beyond the paper: the vergent baseline for a point the map holds, its
  /// depth known (0: baseline_m). Wider, it shrinks the foveal depth step
  /// (depth^2 / (f b) per pixel of disparity) where the map already has a
  /// coarser estimate to refine; a hole's point, its depth a guess, keeps
  /// baseline_m, whose wider Z_T and larger fovea find the surface.
  double mapped_baseline_m = 0.09;
  /// Beyond the paper: place the carriages per fixation (see
  /// ChoosePlacement) so that no mapped surface hides the point from either
  /// camera; false: always symmetric about the rail centre.
  bool choose_placement = true;
  /// With choose_placement: also consider the left camera alone at two
  /// positions (Placement::kLeftPair) for points no right camera sees.
  bool left_pair = true;
  /// With left_pair (issue 19): try the left camera pair first, before the
  /// two-camera placements, rather than last. Its "right" stage is the
  /// home pose's left camera, so each fixation maps what the reference
  /// views see, past nearer surfaces' left edges too. Over the accuracy
  /// set (seeds 0-2 and 3-5) it raised good coverage and lowered RMSE and
  /// edge_bad_share, at about 2.4 times the simulated motion (every servo
  /// step moves the left carriage between the two stages; README, "The
  /// map's trust"). false: the left camera pair only where the map hides
  /// the point from every right camera.
  bool left_pair_first = true;
  /// Nothing in the scene lies nearer (planar depth in the left camera): a
  /// servo that settles nearer took a false match (a repeated texture's
  /// copy) and the point is refused before any matching (0: no check).
  double min_depth_m = 0;
  /// Beyond the paper: a servo whose point lies in front of a surface the map
  /// holds with certainty on the left optical axis (beyond their combined
  /// uncertainty) is refused: a false match in free space.
  bool map_check = true;
  void Check() const;  ///< throws rig::InputError naming the key (fovea/params.h)
};

struct FixationResult {
  bool ok = false;
  Placement placement = Placement::kSymmetric;
  std::string why;  ///< when not ok: why the point could not be fixated
  VergenceSolution vergence;
  ServoResult servo;
  Eigen::Vector3d fixation_W =
      Eigen::Vector3d::Zero();  ///< where the optical axes meet after servoing
  FovealResult foveal;
  double motion_time_s = 0, compute_time_s = 0;
  double verge_time_s = 0;  ///< inverse kinematics
  double baseline_m = 0;    ///< the vergent baseline asked for (FixationOptions)
  double servo_wall_s = 0;  ///< the servo loop: moves, captures and measurements, wall clock
};

/// Verges on p_W, servos, captures and runs the foveated stereo. Given
/// `guessed_depths`, p_W's depth is only a guess (a hole in the map): the
/// servo's first search spans those depths, and a servo that does not
/// converge leaves the point not fixable (the foveated stage would search
/// around a depth nobody measured).
/// `options` must have passed Check(): the run checks them once, before
/// its work (RunFovea, RunIdr, RunConfig::Check), never per call.
FixationResult Fixate(rig::Rig& rig, const PatchMap& map, const Eigen::Vector3d& p_W,
                      const StereoMatcher& matcher, const FixationOptions& options,
                      int fixation = 0,
                      const std::optional<DepthRange>& guessed_depths = std::nullopt);

}  // namespace fovea
