// A virtual stereo head made of the left camera alone at two carriage
// positions: motion stereo along the rail (beyond the paper). It sees what
// no pair of the two cameras can: the right carriage cannot come left of the
// rail centre, so past a nearer surface's left edge lies a strip that the
// left camera at its home position sees and no right camera does.
#pragma once

#include "rig/rig.h"

namespace rig {

/// Limits of the virtual pair: both "cameras" travel where the left carriage
/// does, with the left camera's pan and tilt.
RigLimits LeftPairLimits(const RigLimits& limits);
/// Geometry of the virtual pair: the left head twice.
RigGeometry LeftPairGeometry(const RigGeometry& geometry);

/// The virtual pair on a real (or simulated) rig. Its left camera is the
/// physical left camera at state.left, its right camera the same physical
/// camera at state.right (further right on the rail, never right of the left
/// carriage's travel). MoveTo takes the physical left camera to the right
/// stage and grabs it, then to the left stage, where it stays; Capture grabs
/// it there and pairs the grab with the stored one. The scene must hold
/// still between the two grabs. The physical right camera does not move.
/// Colour captures are not offered (RigError).
class LeftCameraPair : public Rig {
 public:
  explicit LeftCameraPair(Rig& rig);

  MoveResult MoveTo(const StageState& target) override;
  StageState State() const override;
  StereoFrame Capture(const CaptureOptions& options = {}) override;
  const RigLimits& Limits() const override { return limits_; }
  const RigGeometry& Geometry() const override { return geometry_; }
  CameraIntrinsics Intrinsics(Side side) const override;
  /// Both stages at the physical home pose's left stage (zero baseline).
  StageState Home() const override;

 private:
  Rig& rig_;
  RigLimits limits_;
  RigGeometry geometry_;
  StageState state_;
  bool has_right_ = false;
  CameraView right_;  ///< the grab at state_.right
};

}  // namespace rig
