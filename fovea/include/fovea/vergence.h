// Vergence: turning both cameras so their optical axes meet at a 3D point
// (paper section III; design note "Vergence inverse kinematics").
#pragma once

#include <Eigen/Core>
#include <string>

#include "rig/rig.h"

namespace fovea {

struct VergenceOptions {
  int max_iterations = 30;      ///< Newton steps per camera
  double tolerance_px = 0.01;   ///< the point must project this close to the principal point
  double min_distance_m = 0.2;  ///< nearer points are not fixable
  void Check() const;           ///< throws rig::InputError naming the key (fovea/params.h)
};

/// Stage state that fixates a point, or why it cannot be fixated.
struct VergenceSolution {
  bool ok = false;
  rig::StageState state;           ///< quantized to motor steps; baselines as given
  double residual_px[2] = {0, 0};  ///< distance of the point's projection from each principal point
  std::string why;                 ///< empty when ok
};

/// Pan and tilt of each camera (carriages kept where `baselines` has them)
/// that put p_W on both optical axes, honouring the optical-centre offset:
/// an atan2 start refined by Newton steps. A point outside the pan/tilt
/// limits, behind a camera, too near, or that no solution projects within
/// the tolerance of the principal point (after quantization to steps) is
/// reported as not fixable, never clamped.
/// `options` must have passed Check(): the run checks them once, before
/// its work (RunFovea, RunIdr, RunConfig::Check), never per call.
VergenceSolution Verge(const rig::RigGeometry& geometry, const rig::RigLimits& limits,
                       const rig::CameraIntrinsics& left, const rig::CameraIntrinsics& right,
                       const rig::StageState& baselines, const Eigen::Vector3d& p_W,
                       const VergenceOptions& options = {});

}  // namespace fovea
