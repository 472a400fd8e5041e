// Integration of a fixation's patches into the global map (paper section IV;
// design note "DDR"): the hierarchical replacement rule, with overlap judged
// where the patches project in the current left view.
#pragma once

#include <vector>

#include "fovea/patch.h"
#include "rig/types.h"

namespace fovea {

struct IntegrationOptions {
  /// A new patch is dropped when more than this share of its footprint in the
  /// view shows finer map data (peripheral never replaces foveal); an old
  /// patch is removed when at least this share of its visible footprint is
  /// covered by kept new patches of its level or finer.
  double overlap_share = 0.9;
  /// Beyond the paper: where a new patch and the map show different surfaces
  /// on one line of sight (beyond their combined uncertainty), the camera
  /// that saw the farther one saw through the nearer: the less certain of
  /// the two gets a vote, and a patch whose votes pass this share of its
  /// footprint is dropped (new) or removed (old), whatever their levels
  /// (1: never).
  double contradiction_share = 0.25;
  /// Beyond the paper: a new patch's corners are fused (inverse-variance
  /// mean along the viewing ray) with the map's depth there where the map
  /// shows the same surface at the same or a finer level (at any foveal or
  /// peripheral level with fuse_across_levels).
  bool fuse = true;
  /// Beyond the paper, with fuse: a new foveal or peripheral patch is fused
  /// with the map's foveal and peripheral patches of its surface whatever
  /// their levels, each weighed by its sigma; false: only with patches of
  /// its level or finer. IDR patches are never fused into finer ones. The
  /// paper's hierarchy has a finer level outrank a coarser one, but the
  /// periphery is matched at full resolution too
  /// (FovealOptions::rectified_periphery_full_resolution), over blocks four
  /// times the fovea's: over the accuracy benchmark, fusing them took the
  /// median relative error down on every one of its 42 runs (README, "The
  /// map's trust").
  bool fuse_across_levels = true;
  /// Beyond the paper: after each fixation, IDR patches whose footprint in
  /// the IDR view, or in the fixation's own view, finer patches (of any
  /// fixations) cover by retire_idr_share are removed (CoveredIdrPatches).
  /// false: an IDR patch goes only when one fixation's new patches cover it
  /// in that fixation's view by overlap_share.
  bool retire_idr = true;
  /// The share of its footprint finer patches must cover for an IDR patch
  /// to be retired. Below overlap_share: an IDR patch is a coarse guess
  /// (near depth edges about half its pixels are more than 1% off), and the
  /// uncovered rest of one 75% covered is mostly its border.
  double retire_idr_share = 0.75;
  /// Whether the fixation's own view counts too (false: the IDR view only).
  /// The views stand apart and see different parts past nearer surfaces: a
  /// patch the IDR view sees mostly uncovered can be covered where the
  /// fixation looked.
  bool retire_in_fixation_view = true;
  /// Beyond the paper: a new patch the reference camera (the left camera at
  /// the home pose) does not see is marked so (Patch::hidden_in_reference,
  /// by HiddenQuarters with this as ReferenceCheckOptions::min_ncc; 0:
  /// none is): kept in the map, left out of its depth in the reference view.
  double reference_min_ncc = 0.5;
  /// ReferenceCheckOptions::pooled_min_ncc of that check (0: quarters
  /// only). 0.2: on faint textures (the wall behind `three_surfaces`'
  /// boxes) the farther surface seen past a nearer one's edge went
  /// unnoticed, quarter by quarter; over the accuracy benchmark the pooled
  /// check took wrong pixels 0.51% -> 0.43% and the largest edge_bad_share
  /// 0.162 -> 0.146, for 0.17% of good coverage (README, "The map's trust").
  double reference_pooled_min_ncc = 0.2;
  /// ReferenceCheckOptions::side_px of that check: the width of the strips
  /// along a patch's sides that are judged on their own and cut from its
  /// part in the reference view when it does not see them (0: none). 3:
  /// over the accuracy benchmark wrong pixels fell by about a quarter and
  /// RMSE on every run with any, for about 0.003 of good coverage (README,
  /// "The map's trust").
  double reference_side_px = 3;
  /// Beyond the paper, the reading rule of the map's depth in the reference
  /// view (ClearFlankedFarther; 0: none): a pixel with a mapped pixel more
  /// than 2% nearer within this many pixels along its row is left out of it.
  /// It reads the map, as the run reports and scores it; the map, the
  /// fixations and their choice are the same with any value.
  /// 4: with selection.reference_fallback "stalled", over the accuracy
  /// benchmark's 42 runs (and 42 held-out ones) good coverage rose and
  /// every accuracy figure held; on its own it removed wrong pixels at the
  /// cost of four good ones each (README, "The map's trust").
  int reference_flank_px = 4;
  void Check() const;  ///< throws rig::InputError naming the key (fovea/params.h)
};

struct IntegrationStats {
  int offered = 0;               ///< new patches
  int added = 0;                 ///< kept and added to the map
  int dropped_under_finer = 0;   ///< new patches dropped because finer data covers them
  int added_outside_view = 0;    ///< new patches with no footprint in the view (added as they are)
  int dropped_contradicted = 0;  ///< new patches dropped: the map contradicts them
  int fused = 0;                 ///< new patches fused with the map's depth
  int retired_idr = 0;           ///< IDR patches finer data covers (retire_idr)
  int hidden_in_reference = 0;   ///< new patches the reference camera does not see
  std::array<int, 3> replaced{0, 0, 0};              ///< old patches removed, by their PatchLevel
  std::array<int, 3> removed_contradicted{0, 0, 0};  ///< old patches new data contradicts, by level
};

/// Merges `fresh` into `map` by the replacement rule: a new patch replaces
/// the old patches it covers in `view` whose level is the same or coarser
/// (IDR < peripheral < foveal); new data never replaces finer old data. We
/// refine "peripheral replaces peripheral": a coarser resolution level does
/// not replace a finer one (Patch::Fineness). Beyond the paper, new patches
/// are fused with the map where both show one surface, and contradictions
/// between them are settled by certainty (IntegrationOptions). Cost: three
/// renders into the view, O(N + M + pixels) for N old and M new patches.
/// `options` must have passed Check(): the run checks them once, before
/// its work (RunFovea, RunIdr, RunConfig::Check), never per call.
IntegrationStats Integrate(PatchMap* map, const PatchMap& fresh, const rig::CameraView& view,
                           const IntegrationOptions& options = {});

/// How the map's foveal and peripheral patches cover one IDR patch in a
/// view (IdrCoverage), in pixels of the IDR patches rendered alone.
struct IdrCover {
  size_t index = 0;       ///< the IDR patch's index in the map
  long shown = 0;         ///< its pixels (not hidden by another IDR patch)
  long same_surface = 0;  ///< of them, a finer patch of its surface (PatchMap::SameSurface)
  long in_front = 0;      ///< of them, a finer patch of another surface in front of it
};

/// Per view, one IdrCover per IDR patch of the map (in map order); all
/// counts 0 without finer patches. One split of the map, two renders per
/// view (the finer patches only over the IDR patches' bounding box):
/// O(N + views x pixels).
std::vector<std::vector<IdrCover>> IdrCoverage(const PatchMap& map,
                                               const std::vector<rig::CameraView>& views);

/// Which of the map's patches (in map order) are IDR patches whose
/// footprint in any of `views` (the IDR patches rendered alone) the map's
/// foveal and peripheral patches (rendered alone) cover by `share` or more,
/// at the IDR patch's surface or in front of it: the coarse guess adds
/// nothing there. Finer data behind an IDR patch does not cover it: that is
/// a farther surface seen past the IDR patch's edge from another viewpoint.
/// From IdrCoverage.
std::vector<char> CoveredIdrPatches(const PatchMap& map, const std::vector<rig::CameraView>& views,
                                    double share);

}  // namespace fovea
