#include "fovea/placement.h"

#include <vector>

#include "rig/left_pair.h"

namespace fovea {

const char* PlacementName(Placement placement) {
  switch (placement) {
    case Placement::kSymmetric:
      return "symmetric";
    case Placement::kRightInner:
      return "right_inner";
    case Placement::kLeftInner:
      return "left_inner";
    case Placement::kLeftPair:
      return "left_pair";
  }
  return "?";
}

PlacementRig PlacementRig::Of(const rig::Rig& rig, bool left_pair, bool left_pair_first) {
  PlacementRig r;
  r.geometry = rig.Geometry();
  r.limits = rig.Limits();
  r.left = rig.Intrinsics(rig::Side::kLeft);
  r.right = rig.Intrinsics(rig::Side::kRight);
  r.home_left_m = rig.Home().left.carriage_m;
  r.left_pair = left_pair;
  r.left_pair_first = left_pair_first;
  return r;
}

PlacementRig PlacementRig::For(Placement placement) const {
  if (placement != Placement::kLeftPair) return *this;
  PlacementRig r = *this;
  r.geometry = rig::LeftPairGeometry(geometry);
  r.limits = rig::LeftPairLimits(limits);
  r.right = left;
  return r;
}

rig::StageState PlaceCarriages(const PlacementRig& rig, double baseline_m, Placement placement) {
  const rig::RigLimits& limits = rig.limits;
  rig::StageState s = rig::StageState::Parallel(baseline_m);
  if (placement == Placement::kLeftPair) {
    s.right.carriage_m = rig.home_left_m;
    s.left.carriage_m = rig.home_left_m - baseline_m;
  } else if (placement == Placement::kRightInner) {
    s.right.carriage_m = limits[rig::Axis::kRightBaseline].min;
    s.left.carriage_m = s.right.carriage_m - baseline_m;
  } else if (placement == Placement::kLeftInner) {
    s.left.carriage_m = limits[rig::Axis::kLeftBaseline].max;
    s.right.carriage_m = s.left.carriage_m + baseline_m;
  }
  return s;
}

PlacementChoice ChoosePlacement(const PlacementRig& rig, const PatchMap& map,
                                const Eigen::Vector3d& p_W, double baseline_m,
                                const VergenceOptions& vergence,
                                const std::optional<DepthRange>& guessed_depths) {
  // A sample is hidden when the map has a patch this share nearer along the ray.
  constexpr double kNearerShare = 0.03;
  // Multiples of a guessed point's depth sampled behind it.
  constexpr double kBehind[] = {1.25, 1.6, 2.0, 2.5, 3.2, 4.0};
  auto hidden = [&](const Eigen::Vector3d& from_W, const Eigen::Vector3d& q_W) {
    const Eigen::Vector3d d = q_W - from_W;
    const double distance = d.norm();
    const auto hit = map.CastRay(from_W, d / distance);
    return hit && hit->distance_m < (1 - kNearerShare) * distance;
  };
  std::optional<PlacementChoice> best, failed;
  constexpr Placement kPairsFirst[] = {Placement::kRightInner, Placement::kSymmetric,
                                       Placement::kLeftInner, Placement::kLeftPair};
  constexpr Placement kLeftPairFirst[] = {Placement::kLeftPair, Placement::kRightInner,
                                          Placement::kSymmetric, Placement::kLeftInner};
  for (Placement placement : rig.left_pair_first ? kLeftPairFirst : kPairsFirst) {
    if (placement == Placement::kLeftPair && !rig.left_pair) continue;
    const PlacementRig pair = rig.For(placement);
    const rig::RigGeometry& geometry = pair.geometry;
    PlacementChoice c;
    c.placement = placement;
    c.vergence = Verge(geometry, pair.limits, pair.left, pair.right,
                       PlaceCarriages(pair, baseline_m, placement), p_W, vergence);
    if (!c.vergence.ok) {
      if (!failed) failed = c;
      continue;
    }
    const Eigen::Isometry3d left_W =
        geometry.WorldFromCamera(rig::Side::kLeft, c.vergence.state.left);
    const Eigen::Vector3d left_c = left_W.translation();
    const Eigen::Vector3d right_c =
        geometry.WorldFromCamera(rig::Side::kRight, c.vergence.state.right).translation();
    std::vector<Eigen::Vector3d> samples{p_W};
    if (guessed_depths) {
      const Eigen::Vector3d axis = left_W.linear().col(2);
      const double depth = (p_W - left_c).dot(axis);
      for (double k : kBehind)
        if (k * depth <= guessed_depths->far_m) samples.push_back(left_c + k * depth * axis);
    }
    if (!map.empty())
      for (const Eigen::Vector3d& q : samples)
        c.occluded += int(hidden(left_c, q)) + int(hidden(right_c, q));
    if (!best || c.occluded < best->occluded) best = c;
    if (best->occluded == 0) break;
  }
  return best ? *best : *failed;
}

}  // namespace fovea
