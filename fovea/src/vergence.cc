#include "fovea/vergence.h"

#include <Eigen/Dense>
#include <cmath>
#include <stdexcept>

#include "fovea/params.h"

namespace fovea {

void VergenceOptions::Check() const {
  rig::CheckParam(params::kFovealVergenceMaxIterations, max_iterations);
  rig::CheckParam(params::kFovealVergenceTolerancePx, tolerance_px);
  rig::CheckParam(params::kFovealVergenceMinDistanceM, min_distance_m);
}

namespace {

// Normalized image coordinates (x/z, y/z) of p_W for a camera at `stage`; z
// returned through *z.
Eigen::Vector2d Normalized(const rig::RigGeometry& g, rig::Side side, const rig::CameraStage& stage,
                           const Eigen::Vector3d& p_W, double* z) {
  const Eigen::Vector3d p_C = g.WorldFromCamera(side, stage).inverse() * p_W;
  *z = p_C.z();
  return {p_C.x() / p_C.z(), p_C.y() / p_C.z()};
}

}  // namespace

VergenceSolution Verge(const rig::RigGeometry& g, const rig::RigLimits& limits,
                       const rig::CameraIntrinsics& left, const rig::CameraIntrinsics& right,
                       const rig::StageState& baselines, const Eigen::Vector3d& p_W,
                       const VergenceOptions& options) {
  VergenceSolution sol;
  sol.state = baselines;
  for (rig::Side side : {rig::Side::kLeft, rig::Side::kRight}) {
    const rig::CameraIntrinsics& k = side == rig::Side::kLeft ? left : right;
    rig::CameraStage& stage = sol.state[side];
    const Eigen::Vector3d v = p_W - g.WorldFromHead(side, {stage.carriage_m, 0, 0}).translation();
    if (v.norm() < options.min_distance_m) {
      sol.why = std::string(rig::SideName(side)) + " camera: point nearer than " +
                std::to_string(options.min_distance_m) + " m";
      return sol;
    }
    // Start: the optical centre on the axes.
    stage = g.FacingStage(side, stage.carriage_m, p_W);
    // Newton on the normalized projection (x/z, y/z) -> 0.
    double z = 0;
    for (int it = 0; it < options.max_iterations; ++it) {
      const Eigen::Vector2d f = Normalized(g, side, stage, p_W, &z);
      if (z <= 0) break;
      if (f.norm() * k.fx_px < 1e-6) break;
      Eigen::Matrix2d jac;
      const double h = 1e-7;
      for (int c = 0; c < 2; ++c) {
        rig::CameraStage plus = stage, minus = stage;
        (c == 0 ? plus.pan_rad : plus.tilt_rad) += h;
        (c == 0 ? minus.pan_rad : minus.tilt_rad) -= h;
        double zp, zm;
        jac.col(c) =
            (Normalized(g, side, plus, p_W, &zp) - Normalized(g, side, minus, p_W, &zm)) / (2 * h);
      }
      const Eigen::Vector2d step = jac.colPivHouseholderQr().solve(-f);
      stage.pan_rad += step.x();
      stage.tilt_rad += step.y();
    }
    stage.pan_rad = std::remainder(stage.pan_rad, 2 * M_PI);
  }
  // Limits before quantization: outside is not fixable.
  const std::string violation = limits.Violation(sol.state);
  if (!violation.empty()) {
    sol.why = "outside the axis limits: " + violation;
    return sol;
  }
  sol.state = limits.Quantize(sol.state);
  for (rig::Side side : {rig::Side::kLeft, rig::Side::kRight}) {
    const rig::CameraIntrinsics& k = side == rig::Side::kLeft ? left : right;
    const Eigen::Vector3d p_C = g.WorldFromCamera(side, sol.state[side]).inverse() * p_W;
    if (p_C.z() <= 0) {
      sol.why = std::string(rig::SideName(side)) + " camera: point behind the camera";
      return sol;
    }
    const Eigen::Vector2d uv = k.Project(p_C);
    sol.residual_px[static_cast<int>(side)] = (uv - Eigen::Vector2d(k.cx_px, k.cy_px)).norm();
    if (sol.residual_px[static_cast<int>(side)] > options.tolerance_px) {
      sol.why = std::string(rig::SideName(side)) + " camera: projection " +
                std::to_string(sol.residual_px[static_cast<int>(side)]) +
                " px from the principal point";
      return sol;
    }
  }
  sol.ok = true;
  return sol;
}

}  // namespace fovea
