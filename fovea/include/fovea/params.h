// Every parameter of the algorithms' options: its YAML key, meaning and
// range, written once (rig::ParamSpec). The options' Check() checks against
// these specs and the run configuration binds each to its field, so a key,
// its range and its message are the same everywhere. Defaults are the
// options structs' member initializers. Keys are grouped by the YAML
// section the user sees: "idr." (IdrOptions), "foveal." (FixationOptions:
// vergence, servo, tessellation, foveal stereo), "nl1." and "sgbm." (the
// per-level matchers), "selection.", "criteria.", "integration." and
// "loop." (FoveaOptions).
#pragma once

#include "rig/input_file.h"
#include "rig/param.h"

namespace fovea::params {

using rig::ParamSpec;

// ---- IDR: ZeroCrossingOptions, ZcMatchOptions, IdrOptions (paper II) ------
inline constexpr ParamSpec kIdrLogSigmaPx{"idr.log_sigma_px",
                                          "LoG scale of the zero crossings, pixels", 1, 8};
inline constexpr ParamSpec kIdrLogMinSlope{
    "idr.log_min_slope",
    "a crossing counts only where the normalized LoG changes by at least this much across it, grey "
    "levels "
    "(0.6 keeps image noise of sigma up to 2.3 free of crossings)",
    0, 10};
inline constexpr ParamSpec kIdrOrientationToleranceRad{
    "idr.orientation_tolerance_rad",
    "matched crossings' orientations differ by at most this, radians", 0.01, 3.1416};
inline constexpr ParamSpec kIdrTakeNearest{
    "idr.take_nearest",
    "resolve an ambiguous crossing by its smallest disparity instead of rejecting it (classic "
    "matchers; false: "
    "FOVEA's rule)"};
inline constexpr ParamSpec kIdrUniqueShare{
    "idr.unique_share", "share of zero crossings kept unambiguous at the initial baseline", 0.5, 1};
inline constexpr ParamSpec kIdrZMinM{"idr.z_min_m", "nearest scene distance, metres", 0.05, 10};
inline constexpr ParamSpec kIdrMaxSlantDeg{
    "idr.max_slant_deg", "largest surface slant for the expansion factor, degrees", 0, 89};
inline constexpr ParamSpec kIdrMaxExpansion{
    "idr.max_expansion", "cap on the baseline expansion factor per stage", 1.1, 16};
inline constexpr ParamSpec kIdrMinExpansion{
    "idr.min_expansion",
    "an expansion factor below this does not earn another stage (at most idr.max_expansion)", 1.01,
    16};
inline constexpr ParamSpec kIdrVergentSearchPx{
    "idr.vergent_search_px", "P: the vergent stage resolves +-P px (IDR termination)", 0.5, 64};
inline constexpr ParamSpec kIdrVergentBaselineM{
    "idr.vergent_baseline_m",
    "vergent baseline the IDR termination rule assumes, metres (not tied to foveal.baseline_m: at "
    "0.06 m IDR "
    "stops at a 0.012 m baseline and the coarser map costs coverage)",
    0.001, 0.6};
inline constexpr ParamSpec kIdrMaxStages{"idr.max_stages", "baseline stage budget", 1, 20};
inline constexpr ParamSpec kIdrPatchSizePx{"idr.patch_size_px", "IDR patch size, pixels", 4, 128};
inline constexpr ParamSpec kIdrDiscontinuityJumpPx{
    "idr.discontinuity_jump_px",
    "matches with a neighbour within 2 LoG sigma whose disparity differs by more than this lie at "
    "a depth "
    "discontinuity and stay out of the patches, pixels",
    0.1, 64};
inline constexpr ParamSpec kIdrInitialBaselineM{
    "idr.initial_baseline_m",
    "fixed initial baseline instead of the period rule, metres (0 = the rule)", 0, 0.6};
inline constexpr ParamSpec kIdrFitMinSupport{
    "idr.fit_min_support", "IDR patch fit: inlier measurements needed in a block", 3, 4096};
inline constexpr ParamSpec kIdrFitTolerancePx{
    "idr.fit_tolerance_px",
    "IDR patch fit: measurements farther from the plane are outliers, pixels", 0.01, 16};
inline constexpr ParamSpec kIdrFitMinInlierShare{
    "idr.fit_min_inlier_share",
    "IDR patch fit: a block needs this share of its measurements as inliers", 0, 1};
inline constexpr ParamSpec kIdrMaxViewAngleDeg{
    "idr.max_view_angle_deg",
    "beyond the paper: an IDR block gives no patch when its plane is seen more obliquely than "
    "this, degrees between its normal and the left camera's ray to its centre (0 = any)",
    0, 90};
inline constexpr ParamSpec kIdrFitRequireQuadrants{
    "idr.fit_require_quadrants", "IDR patch fit: a block needs measurements in all four quadrants"};

// ---- Vergence, servo, tessellation, foveal stereo: FixationOptions (III) --
inline constexpr ParamSpec kFovealBaselineM{"foveal.baseline_m", "vergent baseline, metres", 0.001,
                                            0.6};
inline constexpr ParamSpec kFovealMappedBaselineM{
    "foveal.mapped_baseline_m",
    "beyond the paper: vergent baseline, metres, for a point the map holds (its depth known); a "
    "hole's point keeps foveal.baseline_m (0: foveal.baseline_m for every point)",
    0, 0.6};
inline constexpr ParamSpec kFovealChoosePlacement{
    "foveal.choose_placement",
    "beyond the paper: place the carriages per fixation (symmetric, right or left carriage "
    "innermost) so that no "
    "mapped surface hides the point from either camera (false: symmetric about the rail centre)"};
inline constexpr ParamSpec kFovealLeftPair{"foveal.left_pair",
                                           "beyond the paper, with foveal.choose_placement: where "
                                           "the map hides a point from every right camera, pair "
                                           "the left camera with itself at two carriage positions "
                                           "(the home pose's and foveal.baseline_m to its left; "
                                           "motion stereo, the scene must hold still)"};
inline constexpr ParamSpec kFovealLeftPairFirst{
    "foveal.left_pair_first",
    "beyond the paper, with foveal.left_pair: try the left camera paired with itself first, "
    "before the two-camera placements (its right stage is the home pose's left camera, so it sees "
    "what the reference views see; about 2.4 times the motion); false: only where the map hides "
    "the point from every right camera"};
inline constexpr ParamSpec kFovealMapCheck{
    "foveal.map_check",
    "beyond the paper: refuse a fixation whose servoed point lies in front of a surface the map "
    "holds with "
    "certainty on the optical axis (a false match in free space)"};
inline constexpr ParamSpec kFovealVergenceMaxIterations{
    "foveal.vergence_max_iterations", "vergence: Newton steps per camera", 1, 200};
inline constexpr ParamSpec kFovealVergenceTolerancePx{
    "foveal.vergence_tolerance_px",
    "vergence: the point must project this close to the principal point, else it is not fixable, "
    "pixels",
    1e-4, 1};
inline constexpr ParamSpec kFovealVergenceMinDistanceM{
    "foveal.vergence_min_distance_m", "vergence: nearer points are not fixable, metres", 0, 1};
inline constexpr ParamSpec kFovealServoWindowHalfPx{
    "foveal.servo_window_half_px", "servoing's window is (2 h + 1) pixels square; h, pixels", 2,
    100};
inline constexpr ParamSpec kFovealServoSearchPx{
    "foveal.servo_search_px", "servoing's first search on a mapped point: +- this many pixels", 1,
    300};
inline constexpr ParamSpec kFovealServoRefinePx{
    "foveal.servo_refine_px",
    "servoing after a move that nulled d: searches +- the larger of this and |d| / 4, pixels", 1,
    300};
inline constexpr ParamSpec kFovealServoTolerancePx{
    "foveal.servo_tolerance_px", "servoing stops below this centre disparity, pixels", 0.01, 10};
inline constexpr ParamSpec kFovealServoMaxSteps{"foveal.servo_max_steps", "servoing step budget", 1,
                                                50};
inline constexpr ParamSpec kFovealServoUniqueRatio{
    "foveal.servo_unique_ratio",
    "servoing on a hole searches every depth and keeps its best match only if its cost is below "
    "this share of "
    "the best elsewhere (1 = any)",
    0.01, 1};
inline constexpr ParamSpec kFovealServoMutualPx{
    "foveal.servo_mutual_px",
    "beyond the paper: a converged servo's match must be mutual (the right centre window, searched "
    "back along the "
    "left image's row, lands within this many pixels of the left centre), else the point is "
    "refused (0 = no "
    "check)",
    0, 100};
inline constexpr ParamSpec kFovealHorizontalDisparityLimitPx{
    "foveal.horizontal_disparity_limit_px",
    "the fovea's horizontal disparity limit (sets Z_T), pixels", 2, 256};
inline constexpr ParamSpec kFovealMaxLevels{"foveal.max_levels",
                                            "resolution levels of the tessellation", 1, 6};
inline constexpr ParamSpec kFovealMinFoveaPx{
    "foveal.min_fovea_px",
    "beyond the paper: the fovea is at least this many pixels wide and high, centred (vertical "
    "disparity at its edge then stays near half a pixel where the worst-case plane would shrink "
    "it; "
    "0 = the paper's rule alone)",
    0, 256};
inline constexpr ParamSpec kFovealFoveaPatchPx{"foveal.fovea_patch_px",
                                               "patch size at full resolution, pixels", 4, 64};
inline constexpr ParamSpec kFovealPeripheryPatchPx{
    "foveal.periphery_patch_px",
    "patch size at coarser levels, full-resolution pixels (at least 4 pixels of the level)", 4, 64};
inline constexpr ParamSpec kFovealMapMarginPx{
    "foveal.map_margin_px",
    "matching searches +- this many level pixels around the map's prediction", 0.1, 32};
inline constexpr ParamSpec kFovealCoarseMarginPx{
    "foveal.coarse_margin_px", "and +- this many level pixels around the coarser level's estimate",
    0.1, 32};
inline constexpr ParamSpec kFovealSilentCheckLevel{
    "foveal.silent_check_level",
    "see foveal.silent_check: the wide search runs once per fixation at this resolution level "
    "(2^level full-resolution pixels per pixel)",
    0, 4};
inline constexpr ParamSpec kFovealSilentConfidence{
    "foveal.silent_confidence",
    "see foveal.silent_check: the wider search's match confidence needed to drop a band match", 0,
    1};
inline constexpr ParamSpec kFovealSilentOutsideSeed{
    "foveal.silent_outside_seed",
    "see foveal.silent_check: beyond the paper, a silent pixel whose wide search matched outside "
    "the band with foveal.silent_confidence, away from depth edges, is searched about that match "
    "instead of over the band (false: only the band)"};
inline constexpr ParamSpec kFovealEdgeErosionPx{
    "foveal.edge_erosion_px",
    "beyond the paper: matches within this many level pixels of a disparity more than "
    "foveal.edge_jump_px "
    "smaller are dropped (window matching fattens a nearer surface over its edge; 0 = none)",
    0, 10};
inline constexpr ParamSpec kFovealFoveaEdgeErosionPx{
    "foveal.fovea_edge_erosion_px",
    "beyond the paper: the erosion beside disparity jumps of foveal.edge_erosion_px, at the "
    "fovea's level only (level 0, full resolution; the peripheral levels, and the margin beside "
    "unmatched runs of foveal.edge_hole_px at every level, keep foveal.edge_erosion_px); -1 = "
    "foveal.edge_erosion_px",
    -1, 10};
inline constexpr ParamSpec kFovealEdgeJumpPx{
    "foveal.edge_jump_px", "see foveal.edge_erosion_px: the disparity jump, level pixels", 0.1, 64};
inline constexpr ParamSpec kFovealEdgeHolePx{
    "foveal.edge_hole_px",
    "beyond the paper: matches within foveal.edge_erosion_px level pixels of a row or column run "
    "of at least this many unmatched level pixels do not set a patch's footprint, though they "
    "count in its fit (beside an edge whose farther side goes unmatched, out of the search band "
    "or without texture, no farther match shows the jump; 0 = none)",
    0, 64};
inline constexpr ParamSpec kFovealMinFillShare{
    "foveal.min_fill_share",
    "beyond the paper: a block is one patch only if its inliers fill this share of it, else it is "
    "split into "
    "quarters (0 = the paper's whole blocks)",
    0, 1};
inline constexpr ParamSpec kFovealMinBlockPx{
    "foveal.min_block_px", "the smallest quarter a block is split into, level pixels", 2, 64};
inline constexpr ParamSpec kFovealPeripheryMinBlockPx{
    "foveal.periphery_min_block_px",
    "beyond the paper: the smallest quarter a peripheral level's block is split into, level pixels "
    "(at least foveal.min_block_px; at or above the peripheral block size, 16 with the default "
    "foveal.periphery_patch_px, peripheral blocks are never split: a quarter smaller than the "
    "matching window rests on matches whose windows overlap, and beside a depth edge on windows "
    "that straddle it)",
    2, 64};
inline constexpr ParamSpec kFovealPeripheryHalfAgreement{
    "foveal.periphery_half_agreement",
    "beyond the paper: a peripheral block that is not whole and is split no further is cut in two "
    "halves; a half whole on its own becomes a patch where a whole block beside it has a plane "
    "within this many fit tolerances of the half's at its corners (it extends a surface found "
    "whole up to a depth edge; 0 = no halves)",
    0, 10};
inline constexpr ParamSpec kFovealClipToInliers{
    "foveal.clip_to_inliers",
    "beyond the paper: a block's patch covers only its inliers' bounding box, not the whole "
    "block (false = the paper's tiling blocks)"};
inline constexpr ParamSpec kFovealClipDiagonals{
    "foveal.clip_diagonals",
    "beyond the paper, with foveal.clip_to_inliers: a fovea block's patch covers only the "
    "quadrilateral of its inliers' extreme pixels along both diagonals, so that a depth edge "
    "crossing the block at a slant cuts the patch along it (false = their bounding box; the same "
    "where the inliers fill a rectangle; peripheral blocks keep the box)"};
inline constexpr ParamSpec kFovealRectify{
    "foveal.rectify",
    "beyond the paper: servo, tessellate and match in the pair's fixation frame (both images "
    "turned so that a tilted verged pair's rows do not twist and the optical axes meet; false = "
    "the paper's unrectified images)"};
inline constexpr ParamSpec kFovealRectifiedPeriphery{
    "foveal.rectified_periphery",
    "beyond the paper: the outermost level, beyond the finer level's rectangle, is matched in the "
    "pair turned into a rectified one, where vertical disparity is zero everywhere (false = the "
    "verged pair's rows, the paper's scheme)"};
inline constexpr ParamSpec kFovealRectifiedSilentConfidence{
    "foveal.rectified_silent_confidence",
    "foveal.silent_confidence for the rectified periphery (foveal.rectified_periphery): a band "
    "match where the map is silent is dropped where the wide search matched outside the band "
    "with at least this confidence",
    0, 1};
inline constexpr ParamSpec kFovealRectifiedPeripheryFullResolution{
    "foveal.rectified_periphery_full_resolution",
    "with foveal.rectified_periphery: the rectified periphery is matched at full resolution, in "
    "blocks of the level's size in level pixels (false = at its level's resolution: about half "
    "the compute per fixation, more wrong pixels beside depth edges)"};
inline constexpr ParamSpec kFovealSkipFovealEdgePx{
    "foveal.skip_foveal_edge_px",
    "beyond the paper: the peripheral levels do not match pixels outside the finer level's "
    "rectangle where the map shows a foveal patch within this many pixels of a depth jump or a "
    "hole in the map (0 = match every pixel of every level)",
    0, 64};
inline constexpr ParamSpec kFovealMaxViewAngleDeg{
    "foveal.max_view_angle_deg",
    "beyond the paper: a block gives no patch when its plane is seen more obliquely than this, "
    "degrees between its normal and the left camera's ray to its centre (0 = any)",
    0, 90};
inline constexpr ParamSpec kFovealFitMinSupport{
    "foveal.fit_min_support",
    "foveal and peripheral patch fit: inlier measurements needed in a block", 3, 4096};
inline constexpr ParamSpec kFovealFitTolerancePx{
    "foveal.fit_tolerance_px",
    "foveal and peripheral patch fit: measurements farther from the plane are outliers, level "
    "pixels",
    0.01, 16};
inline constexpr ParamSpec kFovealFitMinInlierShare{
    "foveal.fit_min_inlier_share",
    "foveal and peripheral patch fit: a block needs this share of its measurements as inliers", 0,
    1};
inline constexpr ParamSpec kFovealFitRequireQuadrants{
    "foveal.fit_require_quadrants",
    "foveal and peripheral patch fit: a block needs measurements in all four quadrants"};

// ---- The per-level matchers -------------------------------------------------
inline constexpr ParamSpec kNl1WindowHalfPx{
    "nl1.window_half_px", "the NL1 matcher's window is (2 h + 1) pixels square; h, pixels", 1, 20};
inline constexpr ParamSpec kNl1MinTextureDn{
    "nl1.min_texture_dn", "NL1: a left window needs this mean absolute deviation, grey levels", 0,
    50};
inline constexpr ParamSpec kNl1WeakWindowHalfPx{
    "nl1.weak_window_half_px",
    "beyond the paper: NL1 matches a pixel whose window of this half width has a faint texture "
    "(nl1.weak_texture_dn) with that wider window instead (0 = one window everywhere); h, pixels",
    0, 20};
inline constexpr ParamSpec kNl1WeakTextureDn{
    "nl1.weak_texture_dn",
    "see nl1.weak_window_half_px: a texture is faint where the wider window's standard deviation "
    "is below this, grey levels",
    0, 50};
inline constexpr ParamSpec kNl1LrTolerancePx{"nl1.lr_tolerance_px",
                                             "NL1: left-right check tolerance, pixels", 0.01, 10};
inline constexpr const char* kNl1Costs[] = {"window_mean", "prenormalized", "zero_mean_ssd",
                                            nullptr};
inline constexpr ParamSpec kNl1Cost{
    "nl1.cost",
    "NL1 cost: window_mean (the paper's: both windows less their own means, O(window area) per "
    "pixel and disparity) or prenormalized (each image less its mean over twice the window, "
    "box-summed: faster, worse beside depth edges) or zero_mean_ssd (both windows less their own "
    "means, squared: box-summed in exact integers, O(1) per pixel and disparity)",
    0, 0, kNl1Costs};
inline constexpr ParamSpec kSgbmBlockSize{"sgbm.block_size",
                                          "StereoSGBM matcher: block size, pixels (odd)", 1, 21};
inline constexpr ParamSpec kSgbmUniquenessRatio{"sgbm.uniqueness_ratio",
                                                "StereoSGBM matcher: uniqueness ratio, %", 0, 100};
inline constexpr ParamSpec kSgbmSpeckleWindow{
    "sgbm.speckle_window", "StereoSGBM matcher: speckle filter window, pixels (0 = off)", 0, 1000};
inline constexpr ParamSpec kSgbmSpeckleRange{
    "sgbm.speckle_range", "StereoSGBM matcher: speckle filter disparity range", 0, 64};

// ---- DDR: selection, criteria, integration, the loop (paper IV) -----------
inline constexpr const char* kSelectionStrategies[] = {"fovea",  "deterministic",  "random",
                                                       "raster", "next_best_view", nullptr};
inline constexpr ParamSpec kSelectionStrategy{
    "selection.strategy",
    "where to look next: fovea (the paper's composite criteria and exponential draw), "
    "deterministic (the composite's maximum), random (uniform over the reference view's "
    "candidates), raster (a fixed scan of the reference view in fovea-sized cells), "
    "next_best_view (the most unmapped or uncertain fovea-sized window, less a motion cost)",
    0, 0, kSelectionStrategies};
inline constexpr const char* kSelectionFirstFixations[] = {"ddr", "idr", nullptr};
inline constexpr ParamSpec kSelectionFirstFixation{
    "selection.first_fixation",
    "the first fixation: ddr (chosen by the strategy in IDR's final view, as in the paper) or idr "
    "(IDR's well-supported patch nearest the view's centre)",
    0, 0, kSelectionFirstFixations};
inline constexpr const char* kSelectionViews[] = {"current", "reference", nullptr};
inline constexpr ParamSpec kSelectionView{
    "selection.view",
    "where the composite rules (fovea, deterministic) choose: current (the current left view, as "
    "in the paper) or reference (IDR's final left view, the region the run maps, with 2D "
    "proximity measured from the current fixation point's image there); the other strategies "
    "always choose in the reference view",
    0, 0, kSelectionViews};
inline constexpr const char* kSelectionReferenceFallbacks[] = {"none", "mapped", "foveal",
                                                               "stalled", nullptr};
inline constexpr ParamSpec kSelectionReferenceFallback{
    "selection.reference_fallback",
    "beyond the paper: when the composite rule's choice in the current view is mapped data "
    "(mapped), foveal data (foveal), or mapped data after a fixation that raised the map's share "
    "of the reference view by less than 0.002 (stalled), it chooses again in the reference view "
    "and takes a hole chosen there instead (none: never); the other strategies, and view "
    "reference, choose in the reference view already and have no fallback",
    0, 0, kSelectionReferenceFallbacks};
inline constexpr ParamSpec kSelectionFoveaSizePx{
    "selection.fovea_size_px",
    "the fovea's size in the reference view: raster's cell and next_best_view's window, pixels", 8,
    1024};
inline constexpr ParamSpec kSelectionMotionWeight{
    "selection.motion_weight",
    "next_best_view: information (unmapped share of the window) given up per radian the left "
    "camera turns",
    0, 100};
inline constexpr ParamSpec kSelectionHalfKnownRelSigma{
    "selection.half_known_rel_sigma",
    "next_best_view: a mapped pixel whose depth sigma is this share of its depth counts as half "
    "unknown",
    1e-6, 1};
inline constexpr ParamSpec kSelectionDeterministic{
    "selection.deterministic", "always fixate the composite's maximum instead of drawing"};
inline constexpr ParamSpec kSelectionDrawScale{"selection.draw_scale",
                                               "scale s of the exponential draw", 0.001, 100};
inline constexpr ParamSpec kSelectionHistogramBins{"selection.histogram_bins",
                                                   "bins of the composite's histogram", 2, 4096};
inline constexpr ParamSpec kSelectionResolutionLevel{
    "selection.resolution_level",
    "beyond the paper: the criteria are weighed on the view reduced 2^level times in each "
    "direction (0 = full resolution; pixel sizes stay in full-resolution pixels)",
    0, 2};
inline constexpr ParamSpec kSelectionBorderPx{
    "selection.border_px", "fixation candidates keep this far from the image edge, pixels", 0, 200};
inline constexpr ParamSpec kSelectionRefusedRadiusM{
    "selection.refused_radius_m",
    "candidates this close to a point that could not be fixated are left out, metres", 0, 1};
inline constexpr ParamSpec kCriteriaGradient{"criteria.gradient", "use gradient attraction"};
inline constexpr ParamSpec kCriteriaSuppression{"criteria.suppression", "use local suppression"};
inline constexpr ParamSpec kCriteriaProximity2d{"criteria.proximity_2d", "use 2D proximity"};
inline constexpr ParamSpec kCriteriaProximity3d{"criteria.proximity_3d", "use 3D proximity"};
inline constexpr ParamSpec kCriteriaGradientBlurPx{
    "criteria.gradient_blur_px", "gradient attraction's smoothing scale, pixels", 0.1, 50};
inline constexpr ParamSpec kCriteriaSuppressedWeight{
    "criteria.suppressed_weight",
    "local suppression's weight where the map is foveal (1 elsewhere)", 0, 1};
inline constexpr ParamSpec kCriteriaSuppressionRadiusM{
    "criteria.suppression_radius_m",
    "local suppression also covers this distance around earlier fixation points, metres", 0, 1};
inline constexpr ParamSpec kCriteriaPeripheralWeight{
    "criteria.peripheral_weight",
    "local suppression's weight where the map is peripheral (1 = the paper's rule: foveal data "
    "only)",
    0, 1};
inline constexpr ParamSpec kCriteriaRevisitRadiusM{
    "criteria.revisit_radius_m",
    "local suppression's weight is 0 this close to an earlier fixation point (or a point aimed at "
    "where the servo "
    "settled farther than this from it), metres",
    0, 1};
inline constexpr ParamSpec kCriteriaHoleWidthPx{
    "criteria.hole_width_px",
    "local suppression's weight on a hole goes from criteria.hole_edge_weight at its edge to "
    "criteria.hole_inside_weight this far inside it, pixels (0: every hole weighs 1)",
    0, 1000};
inline constexpr ParamSpec kCriteriaHoleEdgeWeight{
    "criteria.hole_edge_weight",
    "local suppression's weight at a hole's edge, beside mapped data (with "
    "criteria.hole_width_px)",
    0, 1};
inline constexpr ParamSpec kCriteriaHoleInsideWeight{
    "criteria.hole_inside_weight",
    "local suppression's weight criteria.hole_width_px or more inside a hole (with "
    "criteria.hole_width_px)",
    0, 1};
inline constexpr ParamSpec kCriteriaProximity2dScalePx{
    "criteria.proximity_2d_scale_px", "2D proximity's scale s in exp(-r / s), pixels", 1, 1e9};
inline constexpr ParamSpec kCriteriaProximity3dLow{
    "criteria.proximity_3d_low", "3D proximity's weight outside the Z_T band (1 inside)", 0, 1};
inline constexpr ParamSpec kIntegrationOverlapShare{
    "integration.overlap_share",
    "overlap share at which new patches replace old ones (and finer data blocks new ones)", 0.01,
    1};
inline constexpr ParamSpec kIntegrationContradictionShare{
    "integration.contradiction_share",
    "beyond the paper: a patch the map contradicts (another surface on its line of sight, more "
    "certain, beyond "
    "their combined uncertainty) over more than this share of its footprint is dropped or removed "
    "(1 = never)",
    0, 1};
inline constexpr ParamSpec kIntegrationFuse{
    "integration.fuse",
    "beyond the paper: fuse a new patch with the map's depth where the map shows the same surface "
    "at the same or a finer level, or at any foveal or peripheral level with "
    "integration.fuse_across_levels (inverse-variance mean; false: the paper's replacement only)"};
inline constexpr ParamSpec kIntegrationFuseAcrossLevels{
    "integration.fuse_across_levels",
    "beyond the paper: with integration.fuse, a new foveal or peripheral patch is fused with the "
    "map's foveal and peripheral patches of its surface at any level, each weighed by its depth "
    "sigma (the periphery is matched at full resolution too, over wider blocks; false: only with "
    "patches of its level or finer; IDR patches are never fused into finer ones)"};
inline constexpr ParamSpec kIntegrationRetireIdr{
    "integration.retire_idr",
    "beyond the paper: after each fixation, remove the IDR patches whose footprint in the IDR view "
    "(and, with integration.retire_in_fixation_view, in the fixation's view) the map's finer "
    "patches cover by integration.retire_idr_share (false: only one fixation's new patches "
    "replace them, by integration.overlap_share)"};
inline constexpr ParamSpec kIntegrationRetireIdrShare{
    "integration.retire_idr_share",
    "beyond the paper: with integration.retire_idr, the share of an IDR patch's footprint that "
    "finer patches must cover for it to be removed",
    0.05, 1};
inline constexpr ParamSpec kIntegrationRetireInFixationView{
    "integration.retire_in_fixation_view",
    "beyond the paper: with integration.retire_idr, IDR patches covered in the fixation's own "
    "view are retired too (false: in the IDR view only)"};
inline constexpr ParamSpec kIntegrationReferenceMinNcc{
    "integration.reference_min_ncc",
    "beyond the paper: a new patch the reference camera (the left camera at the home pose) does "
    "not see stays in the map but leaves its depth in the reference view: the normalized "
    "cross-correlation of its texture in the image it was measured in and in the reference image, "
    "sampled on its plane, is below this in its left or right half or three of its quarters (a "
    "farther surface seen past a nearer one's edge from another viewpoint; 0 = no check)",
    0, 1};
inline constexpr ParamSpec kIntegrationReferencePooledMinNcc{
    "integration.reference_pooled_min_ncc",
    "beyond the paper: with integration.reference_min_ncc, a patch's left or right half, or the "
    "whole patch, is hidden from the reference camera when the cross-correlation of all its "
    "samples is below this (a faint texture, whose quarters vary too little to be judged on "
    "their own; 0 = quarters only)",
    0, 1};
inline constexpr ParamSpec kIntegrationReferenceSidePx{
    "integration.reference_side_px",
    "beyond the paper: with integration.reference_min_ncc, the strips this many pixels wide along "
    "a patch's sides (two per side, in the image it was measured in) are judged like its quarters, "
    "and those the reference camera does not see are cut from its depth in the reference view (a "
    "farther surface's few pixels past a nearer one's edge; 0 = no strips)",
    0, 16};
inline constexpr ParamSpec kIntegrationReferenceFlankPx{
    "integration.reference_flank_px",
    "beyond the paper: in the map's depth in the reference view, as the run reports and scores "
    "it, a pixel with a mapped pixel more than 2% nearer within this many pixels along its row is "
    "left out (a farther surface showing through a nearer one's unmapped edge; 0 = none)",
    0, 64};
inline constexpr ParamSpec kLoopFixations{"loop.fixations", "successful fixations to make", 1,
                                          10000};
inline constexpr ParamSpec kLoopStayInIdrView{
    "loop.stay_in_idr_view",
    "fixate only points inside the IDR view (the region the run maps), and, with "
    "integration.reference_min_ncc, none on a patch the reference camera does not see (a surface "
    "seen past a nearer one's edge from where the rig stands)"};
inline constexpr ParamSpec kLoopFixateHoles{"loop.fixate_holes",
                                            "beyond the paper: pixels the map is silent at are "
                                            "candidates, at the depth of the nearest mapped pixel "
                                            "(false: the paper's rule)"};
inline constexpr ParamSpec kLoopPrescreenHoles{
    "loop.prescreen_holes",
    "beyond the paper: a hole chosen as the next target whose window has no unique match along its "
    "ray in the "
    "current pair is passed over without moving the rig (false: every hole is attempted)"};
inline constexpr ParamSpec kLoopHoleFarFactor{
    "loop.hole_far_factor",
    "beyond the paper: a hole's servo search and prescreen reach this factor times the farthest "
    "depth IDR mapped in its view (99th percentile), not infinity (0 = to infinity)",
    0, 100};
inline constexpr ParamSpec kLoopStallFixations{"loop.stall_fixations",
                                               "stop when the foveal share grew by less than "
                                               "stall_growth over this many fixations (0 = never)",
                                               0, 10000};
inline constexpr ParamSpec kLoopStallGrowth{"loop.stall_growth",
                                            "see stall_fixations (share of the IDR view)", 0, 1};
inline constexpr ParamSpec kLoopAttemptsPerFixation{
    "loop.attempts_per_fixation",
    "attempt budget per fixation wanted (points that cannot be fixated)", 1, 100};
inline constexpr ParamSpec kFovealSilentCheck{
    "foveal.silent_check",
    "beyond the paper: where the map is silent, also search every depth from idr.z_min_m to "
    "infinity and drop the "
    "Z_T matches it confidently contradicts (false: the paper's rule, Z_T only)"};

}  // namespace fovea::params
