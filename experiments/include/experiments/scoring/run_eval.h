// Ground-truth scoring of the global map (design note "Ground truth and
// scoring"): the map raytraced into the reference view (the left camera at
// the rig's home pose) against the true depth there.
#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "fovea/patch.h"
#include "rig/rig.h"
#include "sim/ground_truth.h"
#include "sim/simulation.h"

namespace experiments {

/// The pixels on either side of a jump of more than kEdgeJumpM between
/// neighbouring pixels of `depth_m` (CV_32F; 0, nothing, counts as
/// infinitely far), CV_8U 255.
cv::Mat DepthEdges(const cv::Mat& depth_m);

/// The reference view and its truth.
struct ReferenceView {
  rig::CameraView view;  ///< left camera at home: image, pose, intrinsics
  cv::Mat depth_m;       ///< true planar depth (CV_32F, 0 = nothing)
  cv::Mat geom_ids;      ///< surface per pixel (CV_32S, -1 = nothing)
  cv::Mat textured;      ///< CV_8U, 255 where a textured surface is visible
  long textured_pixels = 0;
  /// CV_8U, 255 at the textured pixels whose true point the right camera's
  /// optical centre has in sight from some carriage position (kStereoPositions
  /// over its travel, the head turned to the point): the most that pairs of
  /// the two cameras can triangulate. Past a nearer surface's left edge lies
  /// a strip no right camera sees (it sits right of the rail centre, the
  /// home pose's left camera left of it); only the left camera paired with
  /// itself (rig::LeftCameraPair) sees there.
  cv::Mat stereo_visible;
  long stereo_visible_pixels = 0;
  /// CV_8U, 255 on either side of a true depth discontinuity of more than
  /// kEdgeJumpM (or of a surface's silhouette against nothing), found in the
  /// true camera's depth (on an imperfect rig, before it is carried to the
  /// delivered camera's axis).
  cv::Mat depth_edges;
  /// CV_8U, 255 within kEdgeRadiusPx of a depth_edges pixel.
  cv::Mat near_edge;
};

/// A depth discontinuity is a jump of more than this between neighbouring
/// pixels of the true depth, metres; pixels within kEdgeRadiusPx of one are
/// near an edge (edge_bad_share).
constexpr double kEdgeJumpM = 0.02;
constexpr int kEdgeRadiusPx = 8;

/// A mapped pixel is bad when its depth is off by more than this share of the
/// true depth (and good when within it).
constexpr double kBadShare = 0.01;

/// Right carriage positions, evenly spread over its travel, tried by
/// ReferenceView::stereo_visible.
constexpr int kStereoPositions = 8;

/// Moves `rig` (the scene's simulated rig, or a hardware rig in front of
/// the scene `sim` models) home and captures the left camera there. The
/// truth is what the delivered image really shows: the true camera of the
/// scene's model at home, its view carried to the delivered pixels
/// (sim::SimRig::True), whatever the rig believes.
ReferenceView MakeReferenceView(rig::Rig& rig, sim::Simulation& sim);

struct ErrorFigures {
  long pixels = 0;      ///< mapped textured pixels scored
  long bad = 0;         ///< of them, off by more than kBadShare of depth
  long bad_nearer = 0;  ///< of the bad ones, those the map puts nearer than the truth
  double share = 0;     ///< of the visible textured pixels
  double median_abs_error_m = 0, mean_abs_error_m = 0, rmse_m = 0;
  double median_rel_error = 0;    ///< |Z - Z_true| / Z_true
  double within_1pct = 0;         ///< share of scored pixels within 1% of depth
  double median_error_steps = 0;  ///< in disparity steps Z^2 / (f B) at the vergent baseline
};

struct SurfaceFigures {
  std::string name;
  long pixels = 0;  ///< visible textured pixels of the surface
  double coverage = 0, foveal_coverage = 0;
  double stereo_visible_share = 0;  ///< of its pixels, those in ReferenceView::stereo_visible
  double median_abs_error_m = 0, median_rel_error = 0, median_error_steps = 0,
         rmse_m = 0;  ///< 0 when unmapped
  long mapped = 0;    ///< of its pixels, those with an estimate
};

struct MapScore {
  double coverage = 0;         ///< share of visible textured pixels with an estimate
  double foveal_coverage = 0;  ///< ... with a foveal estimate
  double stereo_visible_share =
      0;  ///< of the visible textured pixels, those in ReferenceView::stereo_visible
  double stereo_visible_coverage = 0;  ///< share of those with an estimate
  ErrorFigures overall;
  /// Share of the visible textured pixels mapped within kBadShare of their
  /// depth: coverage x within_1pct, what the map gets right.
  double good_coverage = 0;
  /// The mapped pixels within kEdgeRadiusPx of a depth discontinuity.
  ErrorFigures near_edges;
  /// The visible textured pixels within kEdgeRadiusPx of a depth
  /// discontinuity, and the shares of them the map holds (edge_coverage)
  /// and holds within kBadShare of their depth (edge_good_coverage): where
  /// the coverage beside edges goes (0 when there are none).
  long edge_visible_pixels = 0;
  double edge_coverage = 0, edge_good_coverage = 0;
  /// The same pixels by the patch seen: IDR, or the resolution level of a
  /// foveal or peripheral patch (where the bleeding across edges comes from).
  ErrorFigures near_edges_idr;
  std::array<ErrorFigures, 6> near_edges_by_resolution;
  std::array<ErrorFigures, 3> by_level;  ///< by PatchLevel of the patch seen
  /// Foveal and peripheral pixels by the resolution level of the patch seen
  /// (0 = full resolution; level k samples every 2^k pixels).
  std::array<ErrorFigures, 6> by_resolution;
  std::vector<SurfaceFigures> surfaces;
  /// Per-patch 3D distance from the patch centre to the true surface (along
  /// the patch normal, by ray casting), when asked for.
  bool has_patch_error = false;
  double patch_error_median_m = 0, patch_error_p90_m = 0;
  int patches_scored = 0;
  /// With the per-patch figures: IDR patches that finer (peripheral or
  /// foveal) patches cover in the reference view, at least kStaleCoveredShare
  /// of their whole footprint, at the IDR patch's surface (or, for an IDR
  /// patch off its true surface, also in front of it): coarse data the
  /// replacement rule should have removed (StaleIdrPatches).
  int stale_idr_patches = 0;
};

inline constexpr double kStaleCoveredShare = 0.9;

/// How many IDR patches of `map` its finer patches cover in `view`
/// (MapScore::stale_idr_patches): at least kStaleCoveredShare of the patch's
/// whole footprint (the projected quad; a part past the image's border or
/// hidden by another IDR patch counts as not covered) shows finer patches at
/// the IDR patch's surface (PatchMap::SameSurface), or, where
/// off_surface[i] (indexed like `map`) says the IDR patch's centre lies off
/// its true surface, at its surface or in front of it. In front of an IDR
/// patch on its true surface a nearer surface's patches hide it in this
/// view; they do not measure it.
int StaleIdrPatches(const fovea::PatchMap& map, const rig::CameraView& view,
                    const std::vector<char>& off_surface);

/// `map`'s depth in the reference view (0: unmapped) and, if `ids` is
/// given, its patch ids (-1: none), read by the reading rule with `flank_px`
/// (fovea::ClearFlankedFarther; 0: as rendered). FOVEA's map is read with
/// IntegrationOptions::reference_flank_px; the static pair's, which is no
/// part of FOVEA, with 0.
void RenderInReference(const fovea::PatchMap& map, int flank_px, const ReferenceView& ref,
                       cv::Mat* depth, cv::Mat* ids = nullptr);

/// Where `map` (read with `flank_px`, RenderInReference) is right and wrong
/// in the reference view (BGR, the view's size): the reference image
/// dimmed; the mapped textured pixels (those the score counts) green within
/// kBadShare of the true depth; beyond it, red where the map is nearer than
/// the truth and magenta where it is farther (brighter the larger the
/// error, full at 5%); the true depth discontinuities (ref.depth_edges, if
/// set) blue.
cv::Mat ErrorPicture(const fovea::PatchMap& map, int flank_px, const ReferenceView& ref);

/// Scores `map`, read with `flank_px` (RenderInReference), in the reference
/// view; `baseline_m` sets the disparity step.
MapScore ScoreMap(const fovea::PatchMap& map, int flank_px, const ReferenceView& ref,
                  const sim::GroundTruth& truth, double baseline_m, bool per_patch);

/// Two maps on the pixels both map in the reference view (visible,
/// textured): how many, and each one's median absolute depth error there.
/// `map` is read with `flank_px` (RenderInReference), `other` as rendered.
struct CommonPixels {
  long pixels = 0;
  double median_abs_error_m = 0, other_median_abs_error_m = 0;
};
CommonPixels CompareOnCommonPixels(const fovea::PatchMap& map, int flank_px,
                                   const fovea::PatchMap& other, const ReferenceView& ref);

/// The figures as summary.json holds them. Error figures over no pixel (an
/// empty map, an unmapped level or surface) are null, not zero.
nlohmann::json ScoreJson(const MapScore& score);

/// The score in one line for messages and captions: "coverage 0.998, foveal
/// 0.284, median error 2.08 mm (0.230% of depth), RMSE 11.58 mm" ("median
/// error -" for an empty map); `brief`: coverage, foveal and median error.
std::string ScoreLine(const MapScore& score, bool brief = false);

}  // namespace experiments
