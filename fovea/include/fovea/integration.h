// Integration of a fixation's patches into the global map (paper section IV;
// design note "DDR"): the hierarchical replacement rule, with overlap judged
// where the patches project in the current left view.
#pragma once

#include "fovea/patch.h"
#include "rig/types.h"

namespace fovea {

struct IntegrationOptions {
  /// A new patch is dropped when more than this share of its footprint in the
  /// view shows finer map data (peripheral never replaces foveal); an old
  /// patch is removed when at least this share of its visible footprint is
  /// covered by kept new patches of its level or finer.
  double overlap_share = 0.9;
  void Check() const;  ///< throws rig::InputError naming the key (fovea/params.h)
};

struct IntegrationStats {
  int offered = 0;              ///< new patches
  int added = 0;                ///< kept and added to the map
  int dropped_under_finer = 0;  ///< new patches dropped because finer data covers them
  int added_outside_view = 0;   ///< new patches with no footprint in the view (added as they are)
  std::array<int, 3> replaced{0, 0, 0};  ///< old patches removed, by their PatchLevel
};

/// Merges `fresh` into `map` by the replacement rule: a new patch replaces
/// the old patches it covers in `view` whose level is the same or coarser
/// (IDR < peripheral < foveal); new data never replaces finer old data. We
/// refine "peripheral replaces peripheral": a coarser resolution level does
/// not replace a finer one (Patch::Fineness). Cost:
/// two renders into the view, O(N + M + pixels) for N old and M new patches.
/// `options` must have passed Check(): the run checks them once, before
/// its work (RunFovea, RunIdr, RunConfig::Check), never per call.
IntegrationStats Integrate(PatchMap* map, const PatchMap& fresh, const rig::CameraView& view,
                           const IntegrationOptions& options = {});

}  // namespace fovea
