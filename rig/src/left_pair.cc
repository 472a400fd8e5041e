#include "rig/left_pair.h"

namespace rig {

RigLimits LeftPairLimits(const RigLimits& limits) {
  RigLimits l = limits;
  l[Axis::kRightBaseline] = limits[Axis::kLeftBaseline];
  l[Axis::kRightPan] = limits[Axis::kLeftPan];
  l[Axis::kRightTilt] = limits[Axis::kLeftTilt];
  return l;
}

RigGeometry LeftPairGeometry(const RigGeometry& geometry) {
  RigGeometry g = geometry;
  g.right = geometry.left;
  return g;
}

LeftCameraPair::LeftCameraPair(Rig& rig)
    : rig_(rig),
      limits_(LeftPairLimits(rig.Limits())),
      geometry_(LeftPairGeometry(rig.Geometry())) {}

MoveResult LeftCameraPair::MoveTo(const StageState& target) {
  const StageState q = limits_.Quantize(target);
  const std::string why = limits_.Violation(q);
  if (!why.empty()) throw RigError("left camera pair: " + why);
  // The physical right camera stays: at its read-back position rounded to
  // whole steps (a settled axis may read back a hair outside its travel).
  StageState physical = rig_.Limits().Quantize(rig_.State());
  physical.left = q.right;
  const MoveResult to_right = rig_.MoveTo(physical);
  right_ = rig_.Capture().left;
  has_right_ = true;
  physical.left = q.left;
  const MoveResult to_left = rig_.MoveTo(physical);
  state_ = q;
  MoveResult r;
  r.motion_time_s = to_right.motion_time_s + to_left.motion_time_s;
  r.reached.left = to_left.reached.left;
  r.reached.right = to_right.reached.left;
  return r;
}

StageState LeftCameraPair::State() const {
  StageState s = state_;
  s.left = rig_.State().left;
  return s;
}

StereoFrame LeftCameraPair::Capture(const CaptureOptions& options) {
  if (options.color) throw RigError("left camera pair: colour captures are not offered");
  if (!has_right_) throw RigError("left camera pair: Capture before MoveTo");
  const StereoFrame physical = rig_.Capture();
  StereoFrame f;
  f.left = physical.left;
  f.right = right_;
  f.state = State();
  f.timestamp_s = physical.timestamp_s;
  return f;
}

CameraIntrinsics LeftCameraPair::Intrinsics(Side) const { return rig_.Intrinsics(Side::kLeft); }

StageState LeftCameraPair::Home() const {
  StageState s;
  s.left = s.right = rig_.Home().left;
  return s;
}

}  // namespace rig
