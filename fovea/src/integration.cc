#include "fovea/integration.h"

#include <array>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <utility>
#include <vector>

#include "fovea/params.h"

namespace fovea {

void IntegrationOptions::Check() const {
  rig::CheckParam(params::kIntegrationOverlapShare, overlap_share);
  rig::CheckParam(params::kIntegrationRetireIdrShare, retire_idr_share);
  rig::CheckParam(params::kIntegrationContradictionShare, contradiction_share);
  rig::CheckParam(params::kIntegrationReferenceMinNcc, reference_min_ncc);
  rig::CheckParam(params::kIntegrationReferencePooledMinNcc, reference_pooled_min_ncc);
  rig::CheckParam(params::kIntegrationReferenceSidePx, reference_side_px);
  rig::CheckParam(params::kIntegrationReferenceFlankPx, reference_flank_px);
}

namespace {

// Of two patches seen on one line of sight at different surfaces (depths za
// and zb there), the one that yields: the less precise measurement, or at
// equal precision the coarser, or at equal fineness the older (`a_is_old`).
// True when `a` yields. Precision is sigma_Z / Z^2 (that is sigma_d / (f B)):
// sigma_Z alone grows with depth and would always favour the nearer of the
// two, a window's fattening over an edge included.
bool Yields(const Patch& a, double za, const Patch& b, double zb, bool a_is_old) {
  const double pa = a.sigma_z_m / (za * za), pb = b.sigma_z_m / (zb * zb);
  if (pa != pb) return pa > pb;
  if (a.Fineness() != b.Fineness()) return a.Fineness() < b.Fineness();
  return a_is_old;
}

// Moves each corner of `fresh` along its viewing ray to the inverse-variance
// mean of its depth and the old map's where the old map shows the same
// surface there at the same or a finer level, or with `across_levels` at any
// foveal or peripheral level (the old patch seen just inside the corner, its
// plane met by the corner's ray); the patch's sigma shrinks accordingly.
// Returns whether any corner was fused.
bool Fuse(const PatchMap& map, const cv::Mat& old_ids, const rig::CameraView& view,
          bool across_levels, Patch* fresh) {
  const Eigen::Isometry3d camera_T_world = view.world_T_camera.inverse();
  const Eigen::Vector3d origin = view.world_T_camera.translation();
  const rig::CameraIntrinsics& k = view.intrinsics;
  const Eigen::Vector3d centre = fresh->Centre();
  double old_var_sum = 0;
  int fused = 0;
  for (Eigen::Vector3d& corner : fresh->corners_W) {
    const Eigen::Vector3d inside = camera_T_world * (corner + 0.1 * (centre - corner));
    if (inside.z() <= 0) continue;
    const int u = static_cast<int>(std::lround(k.fx_px * inside.x() / inside.z() + k.cx_px));
    const int v = static_cast<int>(std::lround(k.fy_px * inside.y() / inside.z() + k.cy_px));
    if (u < 0 || v < 0 || u >= old_ids.cols || v >= old_ids.rows || old_ids.at<int>(v, u) < 0)
      continue;
    const Patch& old = map[old_ids.at<int>(v, u)];
    // The old patch's plane along the corner's ray.
    const Eigen::Vector3d ray = (corner - origin).normalized(), n = old.Normal();
    const double denom = ray.dot(n);
    if (std::abs(denom) < 1e-6) continue;
    const double t_old = (old.Centre() - origin).dot(n) / denom, t_new = (corner - origin).norm();
    const double along =
        ray.dot(view.world_T_camera.linear().col(2));  // planar depth per unit range
    const bool coarser = old.Fineness() < fresh->Fineness();
    if ((coarser && (!across_levels || old.level == PatchLevel::kIdr)) || !(old.sigma_z_m > 0) ||
        !(fresh->sigma_z_m > 0) ||
        !PatchMap::SameSurface(t_new * along, *fresh, t_old * along, old))
      continue;
    const double wn = 1 / (fresh->sigma_z_m * fresh->sigma_z_m),
                 wo = 1 / (old.sigma_z_m * old.sigma_z_m);
    corner = origin + ray * ((wn * t_new + wo * t_old) / (wn + wo));
    old_var_sum += old.sigma_z_m * old.sigma_z_m;
    ++fused;
  }
  if (fused == 0) return false;
  // The fused sigma, with the mean variance of the old observations met.
  const double old_var = old_var_sum / fused, new_var = fresh->sigma_z_m * fresh->sigma_z_m;
  const double share = double(fused) / 4;
  fresh->sigma_z_m =
      std::sqrt((1 - share) * new_var + share * (new_var * old_var / (new_var + old_var)));
  return true;
}

// The share of a patch's projected footprint that falls inside the view's
// image (the projected quadrilateral clipped to the image rectangle, by
// area). 0 when a corner lies behind the camera.
double InViewShare(const Patch& p, const rig::CameraView& view) {
  const Eigen::Isometry3d camera_T_world = view.world_T_camera.inverse();
  const rig::CameraIntrinsics& k = view.intrinsics;
  std::vector<Eigen::Vector2d> poly;
  for (const Eigen::Vector3d& c : p.corners_W) {
    const Eigen::Vector3d q = camera_T_world * c;
    if (q.z() <= 1e-9) return 0;
    poly.emplace_back(k.fx_px * q.x() / q.z() + k.cx_px, k.fy_px * q.y() / q.z() + k.cy_px);
  }
  auto area = [](const std::vector<Eigen::Vector2d>& v) {
    double a = 0;
    for (size_t i = 0; i < v.size(); ++i) {
      const Eigen::Vector2d &p0 = v[i], &p1 = v[(i + 1) % v.size()];
      a += p0.x() * p1.y() - p1.x() * p0.y();
    }
    return std::abs(a) / 2;
  };
  const double whole = area(poly);
  if (!(whole > 0)) return 0;
  // Sutherland-Hodgman against the four sides of [-0.5, w - 0.5] x [-0.5, h - 0.5].
  const double lo = -0.5, w = k.width_px - 0.5, h = k.height_px - 0.5;
  const std::array<std::pair<int, double>, 4> sides{
      {{0, lo}, {1, lo}, {2, w}, {3, h}}};  // x >= lo, y >= lo, x <= w, y <= h
  for (const auto& [side, bound] : sides) {
    auto inside = [&, side = side, bound = bound](const Eigen::Vector2d& v) {
      return side == 0   ? v.x() >= bound
             : side == 1 ? v.y() >= bound
             : side == 2 ? v.x() <= bound
                         : v.y() <= bound;
    };
    auto cut = [&, side = side, bound = bound](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
      const double t =
          (side % 2 == 0) ? (bound - a.x()) / (b.x() - a.x()) : (bound - a.y()) / (b.y() - a.y());
      return Eigen::Vector2d(a + t * (b - a));
    };
    std::vector<Eigen::Vector2d> out;
    for (size_t i = 0; i < poly.size(); ++i) {
      const Eigen::Vector2d &cur = poly[i], &prev = poly[(i + poly.size() - 1) % poly.size()];
      if (inside(cur)) {
        if (!inside(prev)) out.push_back(cut(prev, cur));
        out.push_back(cur);
      } else if (inside(prev)) {
        out.push_back(cut(prev, cur));
      }
    }
    poly = std::move(out);
    if (poly.empty()) return 0;
  }
  return area(poly) / whole;
}

// The new patches, each fused with the map's patches of the same surface.
PatchMap FuseAll(const PatchMap& map, const cv::Mat& old_ids, const rig::CameraView& view,
                 const PatchMap& fresh, bool across_levels, int* fused) {
  PatchMap out;
  for (const Patch& p : fresh.patches()) {
    Patch q = p;
    *fused += Fuse(map, old_ids, view, across_levels, &q);
    out.Add(q);
  }
  return out;
}

// Which old patches go: those contradicted over the contradiction share of
// their visible footprint, and those whose visible footprint kept new
// patches of their level or finer cover (by the overlap share) when that
// footprint is the patch, not a sliver of a patch mostly outside the view.
std::vector<char> OldPatchesToDrop(const PatchMap& map, const rig::CameraView& view,
                                   const std::vector<int>& visible,
                                   const std::vector<int>& old_votes,
                                   const std::vector<int>& covered,
                                   const IntegrationOptions& options, IntegrationStats* stats) {
  std::vector<char> drop(map.size(), 0);
  for (size_t j = 0; j < map.size(); ++j) {
    if (visible[j] == 0) continue;
    if (old_votes[j] > options.contradiction_share * visible[j]) {
      drop[j] = 1;
      ++stats->removed_contradicted[static_cast<int>(map[j].level)];
    } else if (covered[j] >= options.overlap_share * visible[j] &&
               InViewShare(map[j], view) >= options.overlap_share) {
      drop[j] = 1;
      ++stats->replaced[static_cast<int>(map[j].level)];
    }
  }
  return drop;
}

}  // namespace

IntegrationStats Integrate(PatchMap* map, const PatchMap& fresh_in, const rig::CameraView& view,
                           const IntegrationOptions& options) {
  IntegrationStats stats;
  stats.offered = static_cast<int>(fresh_in.size());
  cv::Mat old_depth, old_ids, new_depth, new_ids;
  map->Render(view.world_T_camera, view.intrinsics, &old_depth, &old_ids);
  const PatchMap fresh = options.fuse ? FuseAll(*map, old_ids, view, fresh_in,
                                                options.fuse_across_levels, &stats.fused)
                                      : fresh_in;
  fresh.Render(view.world_T_camera, view.intrinsics, &new_depth, &new_ids);
  const size_t n_old = map->size(), n_new = fresh.size();

  // Per pixel: each new patch's footprint, how much of it shows the same
  // surface at a finer level in the map; each old patch's visible footprint;
  // and, where the two show different surfaces on one line of sight, a vote
  // against the one that yields (the camera that saw the farther surface saw
  // through the nearer one: one of them is wrong).
  std::vector<int> footprint(n_new, 0), under_finer(n_new, 0), new_votes(n_new, 0);
  std::vector<int> visible(n_old, 0), old_votes(n_old, 0);
  for (int y = 0; y < new_ids.rows; ++y)
    for (int x = 0; x < new_ids.cols; ++x) {
      const int n = new_ids.at<int>(y, x), o = old_ids.at<int>(y, x);
      if (n >= 0) ++footprint[n];
      if (o >= 0) ++visible[o];
      if (n < 0 || o < 0) continue;
      const Patch &pn = fresh[n], &po = (*map)[o];
      const double zn = new_depth.at<float>(y, x), zo = old_depth.at<float>(y, x);
      if (PatchMap::SameSurface(zn, pn, zo, po)) {
        if (po.Fineness() > pn.Fineness()) ++under_finer[n];
      } else if (Yields(po, zo, pn, zn, /*a_is_old=*/true)) {
        ++old_votes[o];
      } else {
        ++new_votes[n];
      }
    }
  std::vector<char> keep(n_new, 1);
  for (size_t k = 0; k < n_new; ++k) {
    if (footprint[k] == 0) {
      ++stats.added_outside_view;
    } else if (under_finer[k] > options.overlap_share * footprint[k]) {
      keep[k] = 0;
      ++stats.dropped_under_finer;
    } else if (new_votes[k] > options.contradiction_share * footprint[k]) {
      keep[k] = 0;
      ++stats.dropped_contradicted;
    }
  }
  // Old patches' visible footprint covered by kept new patches of their
  // level or finer.
  std::vector<int> covered(n_old, 0);
  for (int y = 0; y < old_ids.rows; ++y)
    for (int x = 0; x < old_ids.cols; ++x) {
      const int n = new_ids.at<int>(y, x), o = old_ids.at<int>(y, x);
      if (o >= 0 && n >= 0 && keep[n] && fresh[n].Fineness() >= (*map)[o].Fineness()) ++covered[o];
    }
  map->Remove(OldPatchesToDrop(*map, view, visible, old_votes, covered, options, &stats));
  for (size_t k = 0; k < n_new; ++k)
    if (keep[k]) {
      map->Add(fresh[k]);
      ++stats.added;
    }
  return stats;
}

std::vector<std::vector<IdrCover>> IdrCoverage(const PatchMap& map,
                                               const std::vector<rig::CameraView>& views) {
  PatchMap idr, finer;
  std::vector<IdrCover> none;  // one per IDR patch, nothing counted
  for (size_t i = 0; i < map.size(); ++i) {
    if (map[i].level == PatchLevel::kIdr) {
      idr.Add(map[i]);
      none.push_back({i});
    } else {
      finer.Add(map[i]);
    }
  }
  std::vector<std::vector<IdrCover>> out(views.size(), none);
  if (idr.size() == 0 || finer.size() == 0) return out;
  for (size_t v = 0; v < views.size(); ++v) {
    const rig::CameraView& view = views[v];
    cv::Mat idr_depth, idr_ids, finer_depth, finer_ids;
    idr.Render(view.world_T_camera, view.intrinsics, &idr_depth, &idr_ids);
    // The finer patches are read only where an IDR patch is seen.
    const cv::Rect seen = cv::boundingRect(idr_ids >= 0);
    if (seen.empty()) continue;
    finer.Render(view.world_T_camera, view.intrinsics, &finer_depth, &finer_ids, seen);
    std::vector<IdrCover>& cover = out[v];
    for (int y = 0; y < idr_ids.rows; ++y)
      for (int x = 0; x < idr_ids.cols; ++x)
        if (const int id = idr_ids.at<int>(y, x); id >= 0) {
          ++cover[id].shown;
          const int f = finer_ids.at<int>(y, x);
          if (f < 0) continue;
          const double zi = idr_depth.at<float>(y, x), zf = finer_depth.at<float>(y, x);
          if (PatchMap::SameSurface(zi, idr[id], zf, finer[f]))
            ++cover[id].same_surface;
          else if (zf <= zi)
            ++cover[id].in_front;
        }
  }
  return out;
}

std::vector<char> CoveredIdrPatches(const PatchMap& map, const std::vector<rig::CameraView>& views,
                                    double share) {
  std::vector<char> covered_idr(map.size(), 0);
  for (const std::vector<IdrCover>& view : IdrCoverage(map, views))
    for (const IdrCover& c : view)
      // Finer data behind the IDR patch is another surface it hides (the
      // background seen past a near box's edge from another viewpoint), not
      // a measurement of its own.
      covered_idr[c.index] |= c.shown > 0 && c.same_surface + c.in_front >= share * c.shown;
  return covered_idr;
}

}  // namespace fovea
