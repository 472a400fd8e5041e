// Where the carriages sit for a fixation (beyond the paper): each camera
// sees its own side of a nearer surface's edge, so the placement decides
// which strips past the edges both cameras see.
#pragma once

#include <Eigen/Core>
#include <optional>

#include "fovea/patch.h"
#include "fovea/servo.h"
#include "fovea/vergence.h"
#include "rig/kinematics.h"
#include "rig/rig.h"
#include "rig/types.h"

namespace fovea {

/// Where the two carriages sit for a vergent baseline b.
enum class Placement {
  kSymmetric,   ///< +-b/2 about the rail centre
  kRightInner,  ///< right carriage innermost, the left one b to its left
  kLeftInner,   ///< left carriage innermost (where IDR's left camera sits), the right one b to its
                ///< right
  /// The left camera alone at two positions (rig::LeftCameraPair): its
  /// "right" stage at the home pose's left carriage, its left stage b
  /// further left. Sees past nearer surfaces' left edges what the home
  /// pose's left camera sees there and no right camera can.
  kLeftPair,
};
const char* PlacementName(Placement placement);

/// What ChoosePlacement needs of the rig.
struct PlacementRig {
  rig::RigGeometry geometry;
  rig::RigLimits limits;
  rig::CameraIntrinsics left, right;
  double home_left_m = 0;  ///< the left carriage at the home pose
  bool left_pair = true;   ///< also consider Placement::kLeftPair
  /// With left_pair: try Placement::kLeftPair first rather than last.
  bool left_pair_first = false;
  static PlacementRig Of(const rig::Rig& rig, bool left_pair, bool left_pair_first);
  /// Geometry, limits and right intrinsics of the pair `placement` uses
  /// (the virtual pair's for kLeftPair).
  PlacementRig For(Placement placement) const;
};

/// Carriage positions (pan and tilt zero) of `placement` for baseline_m; for
/// kLeftPair, the virtual pair's stages.
rig::StageState PlaceCarriages(const PlacementRig& rig, double baseline_m, Placement placement);

/// A placement and the vergence on p_W from it.
struct PlacementChoice {
  Placement placement = Placement::kSymmetric;
  VergenceSolution vergence;
  int occluded = 0;  ///< sample points the map hides from either camera
};

/// Beyond the paper. Each camera sees its own side of a nearer surface's
/// edge: past a near surface's left edge lies a strip the left camera sees
/// and the right one does not (and the reverse past a right edge), as wide as
/// the carriages are apart. The views the map is built for (IDR's, the home
/// pose's) have their left camera left of the rail centre, so of the
/// two-camera placements the right carriage innermost is tried first: it
/// puts the right camera as near them as the rail allows and leaves the
/// thinnest strips past left edges (which IDR's pair, its right camera
/// moving right, cannot see either). Then symmetric, then left innermost.
/// For each, this verges on p_W and raytraces the map from both optical
/// centres to sample points: p_W, and when its depth is a guess
/// (`guessed_depths`, a hole), the points behind it on the left optical
/// axis up to 4 times its depth. A sample is hidden from
/// a camera when the map has a patch more than 3% nearer along the ray.
/// Returns the first placement with the fewest hidden samples (at once when
/// one hides none), or the first whose vergence failed if none can fixate
/// p_W. If `rig.left_pair`, the left camera pair (kLeftPair), which costs
/// twice the moves, is tried too: last, or with `rig.left_pair_first`
/// before the others (its "right" stage sits where the home pose's left
/// camera does, so it sees what the reference views see, strips past
/// nearer surfaces' edges included). Cost: 4 vergences and up to 56 ray
/// casts, each O(log patches).
PlacementChoice ChoosePlacement(const PlacementRig& rig, const PatchMap& map,
                                const Eigen::Vector3d& p_W, double baseline_m,
                                const VergenceOptions& vergence,
                                const std::optional<DepthRange>& guessed_depths);

}  // namespace fovea
