// The rig interface: what the algorithms may ask of a stereo head, simulated
// or real. No simulator type appears here.
#pragma once

#include "rig/kinematics.h"
#include "rig/types.h"

namespace rig {

/// A pair of cameras on six motorized axes (baseline, pan, tilt per camera).
/// Implementations: sim::SimRig (MuJoCo) and, later, a hardware rig.
/// All methods throw RigError on refusal or failure; none waits unboundedly.
class Rig {
 public:
  virtual ~Rig() = default;

  /// Moves all six axes to `target`, each quantized to whole motor steps
  /// first, and blocks until every axis has settled (within its position
  /// tolerance, speed near zero). Throws RigError, before anything moves, if
  /// any axis of `target` lies outside its limits, and if the stages fail to
  /// settle within the rig's move timeout.
  virtual MoveResult MoveTo(const StageState& target) = 0;

  /// Current positions of the six axes as read back from the stages.
  virtual StageState State() const = 0;

  /// Grabs both cameras at the current state.
  virtual StereoFrame Capture(const CaptureOptions& options = {}) = 0;

  /// Travel and step resolution of each axis.
  virtual const RigLimits& Limits() const = 0;

  /// Kinematic model of the heads (for vergence inverse kinematics).
  virtual const RigGeometry& Geometry() const = 0;

  /// Intrinsics of one camera (what Capture reports in its views).
  virtual CameraIntrinsics Intrinsics(Side side) const = 0;

  /// The rig's rest pose: cameras parallel and level at the home baseline.
  virtual StageState Home() const = 0;
};

}  // namespace rig
