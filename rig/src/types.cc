#include "rig/types.h"

#include <cmath>
#include <cstdio>
#include <sstream>

namespace rig {

const char* SideName(Side side) { return side == Side::kLeft ? "left" : "right"; }

const char* AxisName(Axis axis) {
  switch (axis) {
    case Axis::kLeftBaseline:
      return "left baseline";
    case Axis::kLeftPan:
      return "left pan";
    case Axis::kLeftTilt:
      return "left tilt";
    case Axis::kRightBaseline:
      return "right baseline";
    case Axis::kRightPan:
      return "right pan";
    case Axis::kRightTilt:
      return "right tilt";
  }
  return "?";
}

namespace {
bool IsBaseline(int axis) { return axis % 3 == 0; }
}  // namespace

CameraIntrinsics CameraIntrinsics::FromHorizontalFov(int width_px, int height_px,
                                                     double horizontal_fov_rad) {
  if (width_px <= 0 || height_px <= 0) {
    throw RigError("image size must be positive, got " + std::to_string(width_px) + "x" +
                   std::to_string(height_px));
  }
  if (!(horizontal_fov_rad > 0 && horizontal_fov_rad < M_PI)) {
    throw RigError("horizontal field of view must be in (0, 180) degrees, got " +
                   std::to_string(horizontal_fov_rad * 180 / M_PI));
  }
  CameraIntrinsics k;
  k.width_px = width_px;
  k.height_px = height_px;
  // The frustum spans the full image width W, edge to edge: tan(fov/2) = (W/2)/f.
  k.fx_px = k.fy_px = 0.5 * width_px / std::tan(0.5 * horizontal_fov_rad);
  k.cx_px = 0.5 * (width_px - 1);
  k.cy_px = 0.5 * (height_px - 1);
  return k;
}

void CameraIntrinsics::Check() const {
  if (width_px <= 0 || height_px <= 0) {
    throw RigError("camera image size must be positive, got " + std::to_string(width_px) + "x" +
                   std::to_string(height_px));
  }
  if (!(fx_px > 0) || !(fy_px > 0)) throw RigError("camera focal lengths must be positive");
  const size_t n = distortion.size();
  if (n != 0 && n != 4 && n != 5 && n != 8) {
    throw RigError("camera distortion must have 0, 4, 5 or 8 coefficients, got " +
                   std::to_string(n));
  }
}

double CameraIntrinsics::VerticalFovRad() const { return 2 * std::atan(0.5 * height_px / fy_px); }

namespace {
// OpenCV's radial-tangential model applied to normalized coordinates.
Eigen::Vector2d Distort(const std::vector<double>& k, const Eigen::Vector2d& xy) {
  if (k.empty()) return xy;
  const double x = xy.x(), y = xy.y();
  const double r2 = x * x + y * y;
  const double k3 = k.size() >= 5 ? k[4] : 0.0;
  double radial = 1 + k[0] * r2 + k[1] * r2 * r2 + k3 * r2 * r2 * r2;
  if (k.size() == 8) radial /= 1 + k[5] * r2 + k[6] * r2 * r2 + k[7] * r2 * r2 * r2;
  const double p1 = k[2], p2 = k[3];
  return {x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x),
          y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y};
}
}  // namespace

Eigen::Vector2d CameraIntrinsics::ProjectDistorted(const Eigen::Vector3d& p_C) const {
  const Eigen::Vector2d d = Distort(distortion, {p_C.x() / p_C.z(), p_C.y() / p_C.z()});
  return {fx_px * d.x() + cx_px, fy_px * d.y() + cy_px};
}

Eigen::Vector3d CameraIntrinsics::RayDistorted(const Eigen::Vector2d& uv) const {
  const Eigen::Vector2d target((uv.x() - cx_px) / fx_px, (uv.y() - cy_px) / fy_px);
  Eigen::Vector2d xy = target;
  if (!distortion.empty()) {
    // Fixed-point iteration: xy <- xy + (target - distort(xy)); converges for
    // the moderate distortion of real lenses.
    for (int i = 0; i < 50; ++i) {
      const Eigen::Vector2d step = target - Distort(distortion, xy);
      xy += step;
      if (step.squaredNorm() < 1e-24) break;
    }
  }
  return {xy.x(), xy.y(), 1.0};
}

bool CameraIntrinsics::InImage(const Eigen::Vector2d& uv) const {
  return uv.x() >= -0.5 && uv.y() >= -0.5 && uv.x() < width_px - 0.5 && uv.y() < height_px - 0.5;
}

cv::Matx33d CameraIntrinsics::K() const {
  return cv::Matx33d(fx_px, 0, cx_px, 0, fy_px, cy_px, 0, 0, 1);
}

StageState StageState::Parallel(double baseline_m) {
  StageState s;
  s.left.carriage_m = -0.5 * baseline_m;
  s.right.carriage_m = 0.5 * baseline_m;
  return s;
}

StageState StageState::FromArray(const std::array<double, kNumAxes>& v) {
  StageState s;
  s.left = {v[0], v[1], v[2]};
  s.right = {v[3], v[4], v[5]};
  return s;
}

std::array<double, kNumAxes> StageState::ToArray() const {
  return {left.carriage_m,  left.pan_rad,  left.tilt_rad,
          right.carriage_m, right.pan_rad, right.tilt_rad};
}

std::string StageState::ToString() const {
  char buf[256];
  std::snprintf(buf, sizeof buf,
                "left(x=%.5f m, pan=%.4f deg, tilt=%.4f deg) right(x=%.5f m, pan=%.4f deg, "
                "tilt=%.4f deg)",
                left.carriage_m, left.pan_rad * 180 / M_PI, left.tilt_rad * 180 / M_PI,
                right.carriage_m, right.pan_rad * 180 / M_PI, right.tilt_rad * 180 / M_PI);
  return buf;
}

std::string RigLimits::Violation(const StageState& state) const {
  const auto v = state.ToArray();
  for (int i = 0; i < kNumAxes; ++i) {
    const AxisLimit& a = axes[i];
    if (!std::isfinite(v[i]) || v[i] < a.min || v[i] > a.max) {
      const bool lin = IsBaseline(i);
      const double scale = lin ? 1.0 : 180 / M_PI;
      char buf[200];
      std::snprintf(buf, sizeof buf, "%s position %.6g %s is outside its range [%.6g, %.6g]",
                    AxisName(static_cast<Axis>(i)), v[i] * scale, lin ? "m" : "deg", a.min * scale,
                    a.max * scale);
      return buf;
    }
  }
  return {};
}

std::array<long long, kNumAxes> RigLimits::ToSteps(const StageState& state) const {
  const auto v = state.ToArray();
  std::array<long long, kNumAxes> steps{};
  for (int i = 0; i < kNumAxes; ++i) steps[i] = std::llround(v[i] * axes[i].steps_per_unit);
  return steps;
}

StageState RigLimits::Quantize(const StageState& state) const {
  const auto steps = ToSteps(state);
  std::array<double, kNumAxes> v{};
  for (int i = 0; i < kNumAxes; ++i) v[i] = steps[i] / axes[i].steps_per_unit;
  return StageState::FromArray(v);
}

}  // namespace rig
