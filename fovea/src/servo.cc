#include "fovea/servo.h"

#include <cmath>
#include <stdexcept>

namespace fovea {

void ServoOptions::Check() const {
  if (window_half_px < 2 || window_half_px > 100) throw std::invalid_argument("servo: window_half_px must be 2 to 100");
  if (search_px < 1 || search_px > 300) throw std::invalid_argument("servo: search_px must be 1 to 300");
  if (!(tolerance_px > 0)) throw std::invalid_argument("servo: tolerance_px must be positive");
  if (max_steps < 1) throw std::invalid_argument("servo: max_steps must be >= 1");
}

double NormalizedL1(const cv::Mat& left, int xl, int yl, const cv::Mat& right, int xr, int yr, int half) {
  const int n = (2 * half + 1) * (2 * half + 1);
  double ml = 0, mr = 0;
  for (int dy = -half; dy <= half; ++dy) {
    const uchar* l = left.ptr<uchar>(yl + dy) + xl;
    const uchar* r = right.ptr<uchar>(yr + dy) + xr;
    for (int dx = -half; dx <= half; ++dx) {
      ml += l[dx];
      mr += r[dx];
    }
  }
  const double offset = (ml - mr) / n;
  double cost = 0;
  for (int dy = -half; dy <= half; ++dy) {
    const uchar* l = left.ptr<uchar>(yl + dy) + xl;
    const uchar* r = right.ptr<uchar>(yr + dy) + xr;
    for (int dx = -half; dx <= half; ++dx) cost += std::abs(l[dx] - r[dx] - offset);
  }
  return cost / n;
}

std::optional<double> CentreDisparity(const rig::StereoFrame& frame, const ServoOptions& o) {
  const cv::Mat& l = frame.left.gray;
  const cv::Mat& r = frame.right.gray;
  const int xl = static_cast<int>(std::lround(frame.left.intrinsics.cx_px));
  const int yl = static_cast<int>(std::lround(frame.left.intrinsics.cy_px));
  const int xr0 = static_cast<int>(std::lround(frame.right.intrinsics.cx_px));
  const int h = o.window_half_px;
  // No texture in the left window: nothing to servo on.
  if (xl - h < 0 || yl - h < 0 || xl + h >= l.cols || yl + h >= l.rows) return std::nullopt;
  if (NormalizedL1(l, xl, yl, cv::Mat(l.size(), CV_8U, cv::Scalar(0)), xl, yl, h) < 2.0) return std::nullopt;
  std::vector<double> cost(2 * o.search_px + 1, 1e300);
  int best = -1;
  for (int i = 0; i <= 2 * o.search_px; ++i) {
    const int xr = xr0 - o.search_px + i;
    if (xr - h < 0 || xr + h >= r.cols) continue;
    cost[i] = NormalizedL1(l, xl, yl, r, xr, yl, h);
    if (best < 0 || cost[i] < cost[best]) best = i;
  }
  if (best <= 0 || best >= 2 * o.search_px) return std::nullopt;
  const double c0 = cost[best - 1], c1 = cost[best], c2 = cost[best + 1];
  const double denom = c0 - 2 * c1 + c2;
  const double sub = denom > 0 ? 0.5 * (c0 - c2) / denom : 0.0;
  return (xr0 - o.search_px + best + sub) - frame.right.intrinsics.cx_px;
}

ServoResult Servo(rig::Rig& rig, const rig::StageState& start, const ServoOptions& o) {
  o.Check();
  ServoResult result;
  rig::StageState state = start;
  result.motion_time_s += rig.MoveTo(state).motion_time_s;
  for (int step = 0;; ++step) {
    result.frame = rig.Capture();
    result.state = result.frame.state;
    const auto d = CentreDisparity(result.frame, o);
    if (!d) break;
    result.residual_px = *d;
    result.residuals_px.push_back(*d);
    if (std::abs(*d) < o.tolerance_px) {
      result.converged = true;
      break;
    }
    if (step >= o.max_steps) break;
    // The right camera turns towards the point: positive pan turns left.
    state.right.pan_rad -= std::atan(*d / result.frame.right.intrinsics.fx_px);
    const std::string why = rig.Limits().Violation(state);
    if (!why.empty()) break;
    result.motion_time_s += rig.MoveTo(state).motion_time_s;
    ++result.iterations;
  }
  return result;
}

}  // namespace fovea
