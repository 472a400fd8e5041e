// The simulated TAVT behind the rig interface.
#pragma once

#include <cstdint>

#include "rig/rig.h"
#include "sim/config.h"

namespace sim {

struct World;

/// Six position-servoed joints (slide, pan hinge, tilt hinge per camera) with
/// rotor inertia, damping and force limits, so a move takes physical time.
/// Commands are quantized to motor steps; MoveTo steps the physics until the
/// stages settle. Capture renders both cameras offscreen (OSMesa) and applies
/// the seeded sensor-noise model.
class SimRig : public rig::Rig {
 public:
  SimRig(World* world, const SimRigConfig& config);

  rig::MoveResult MoveTo(const rig::StageState& target) override;
  rig::StageState State() const override;
  rig::StereoFrame Capture(const rig::CaptureOptions& options = {}) override;
  const rig::RigLimits& Limits() const override { return limits_; }
  const rig::RigGeometry& Geometry() const override { return geometry_; }
  rig::CameraIntrinsics Intrinsics(rig::Side side) const override;
  rig::StageState Home() const override { return home_; }

  /// Simulated time since load, seconds.
  double TimeS() const;

 private:
  World* world_;
  SimRigConfig config_;
  rig::RigLimits limits_;
  rig::RigGeometry geometry_;
  rig::StageState home_;
  uint64_t capture_count_ = 0;
};

}  // namespace sim
