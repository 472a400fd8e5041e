#include "fovea/integration.h"

#include <stdexcept>
#include <string>

#include "fovea/params.h"

namespace fovea {

void IntegrationOptions::Check() const {
  rig::CheckParam(params::kIntegrationOverlapShare, overlap_share);
}

IntegrationStats Integrate(PatchMap* map, const PatchMap& fresh, const rig::CameraView& view,
                           const IntegrationOptions& options) {
  IntegrationStats stats;
  stats.offered = static_cast<int>(fresh.size());
  cv::Mat old_ids, new_ids;
  map->Render(view.world_T_camera, view.intrinsics, nullptr, &old_ids);
  fresh.Render(view.world_T_camera, view.intrinsics, nullptr, &new_ids);
  const size_t n_old = map->size(), n_new = fresh.size();
  auto level = [](const Patch& p) { return p.Fineness(); };

  // Footprint of each new patch, and how much of it finer old data shows.
  std::vector<int> footprint(n_new, 0), under_finer(n_new, 0);
  for (int y = 0; y < new_ids.rows; ++y) {
    const int* nr = new_ids.ptr<int>(y);
    const int* orow = old_ids.ptr<int>(y);
    for (int x = 0; x < new_ids.cols; ++x) {
      if (nr[x] < 0) continue;
      ++footprint[nr[x]];
      if (orow[x] >= 0 && level((*map)[orow[x]]) > level(fresh[nr[x]])) ++under_finer[nr[x]];
    }
  }
  std::vector<char> keep(n_new, 1);
  for (size_t k = 0; k < n_new; ++k) {
    if (footprint[k] == 0) {
      ++stats.added_outside_view;
    } else if (under_finer[k] > options.overlap_share * footprint[k]) {
      keep[k] = 0;
      ++stats.dropped_under_finer;
    }
  }
  // Old patches: the share of their visible footprint that kept new patches
  // of their level or finer cover.
  std::vector<int> visible(n_old, 0), covered(n_old, 0);
  for (int y = 0; y < old_ids.rows; ++y) {
    const int* nr = new_ids.ptr<int>(y);
    const int* orow = old_ids.ptr<int>(y);
    for (int x = 0; x < old_ids.cols; ++x) {
      if (orow[x] < 0) continue;
      ++visible[orow[x]];
      if (nr[x] >= 0 && keep[nr[x]] && level(fresh[nr[x]]) >= level((*map)[orow[x]]))
        ++covered[orow[x]];
    }
  }
  std::vector<char> drop(n_old, 0);
  for (size_t j = 0; j < n_old; ++j)
    if (visible[j] > 0 && covered[j] >= options.overlap_share * visible[j]) {
      drop[j] = 1;
      ++stats.replaced[static_cast<int>((*map)[j].level)];
    }
  map->Remove(drop);
  for (size_t k = 0; k < n_new; ++k)
    if (keep[k]) {
      map->Add(fresh[k]);
      ++stats.added;
    }
  return stats;
}

}  // namespace fovea
