#include "fovea/servo.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "fovea/geometry.h"
#include "fovea/params.h"

namespace fovea {

void ServoOptions::Check() const {
  rig::CheckParam(params::kFovealServoWindowHalfPx, window_half_px);
  rig::CheckParam(params::kFovealServoSearchPx, search_px);
  rig::CheckParam(params::kFovealServoRefinePx, refine_px);
  rig::CheckParam(params::kFovealServoTolerancePx, tolerance_px);
  rig::CheckParam(params::kFovealServoMaxSteps, max_steps);
  rig::CheckParam(params::kFovealServoUniqueRatio, unique_ratio);
  rig::CheckParam(params::kFovealServoMutualPx, mutual_tolerance_px);
}

double NormalizedL1(const cv::Mat& left, int xl, int yl, const cv::Mat& right, int xr, int yr,
                    int half) {
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

namespace {

// Whether the window of half-width `half` about (x, y) has texture to match:
// its mean absolute deviation from its mean is at least 2 grey levels (the
// normalized L1 cost against a flat window).
bool Textured(const cv::Mat& image, int x, int y, int half) {
  const int n = (2 * half + 1) * (2 * half + 1);
  double sum = 0;
  for (int dy = -half; dy <= half; ++dy) {
    const uchar* row = image.ptr<uchar>(y + dy) + x;
    for (int dx = -half; dx <= half; ++dx) sum += row[dx];
  }
  const double mean = sum / n;
  double deviation = 0;
  for (int dy = -half; dy <= half; ++dy) {
    const uchar* row = image.ptr<uchar>(y + dy) + x;
    for (int dx = -half; dx <= half; ++dx) deviation += std::abs(row[dx] - mean);
  }
  return deviation / n >= 2.0;
}

// The index of the lowest cost (1e300 = not compared) if it is a match: not
// at either end of the search nor beside an uncompared position, and with
// `unique_ratio` < 1 below that share of every other local minimum farther
// than `half` from it.
std::optional<int> UniqueMinimum(const std::vector<double>& cost, int half, double unique_ratio) {
  const int n = static_cast<int>(cost.size());
  int best = -1;
  for (int i = 0; i < n; ++i)
    if (cost[i] < 1e300 && (best < 0 || cost[i] < cost[best])) best = i;
  if (best <= 0 || best >= n - 1 || cost[best - 1] >= 1e300 || cost[best + 1] >= 1e300)
    return std::nullopt;
  if (unique_ratio < 1) {
    for (int i = 1; i + 1 < n; ++i) {
      const bool local_min = cost[i] <= cost[i - 1] && cost[i] <= cost[i + 1] && cost[i] < 1e300;
      if (local_min && std::abs(i - best) > half && cost[best] >= unique_ratio * cost[i])
        return std::nullopt;
    }
  }
  return best;
}

// The normalized L1 search of the centre window of `from` (at its rounded
// principal point) along the same row of `to`, over offsets [lo, hi] pixels
// from `to`'s principal point; the minimum is refined by a parabola. A
// minimum at the edge of the search is no match, and with `unique_ratio` < 1
// neither is one whose cost is not below that share of the best minimum
// elsewhere (outside the best's window half-width).
std::optional<double> SearchRow(const rig::CameraView& from, const rig::CameraView& to,
                                const ServoOptions& o, int lo, int hi, double unique_ratio) {
  const cv::Mat& l = from.gray;
  const cv::Mat& r = to.gray;
  const int xl = static_cast<int>(std::lround(from.intrinsics.cx_px));
  const int yl = static_cast<int>(std::lround(from.intrinsics.cy_px));
  const int xr0 = static_cast<int>(std::lround(to.intrinsics.cx_px));
  const int h = o.window_half_px;
  if (xl - h < 0 || yl - h < 0 || xl + h >= l.cols || yl + h >= l.rows || yl + h >= r.rows ||
      hi <= lo)
    return std::nullopt;
  if (!Textured(l, xl, yl, h)) return std::nullopt;  // nothing to servo on
  const int n = hi - lo + 1;
  std::vector<double> cost(n, 1e300);
  for (int i = 0; i < n; ++i) {
    const int xr = xr0 + lo + i;
    if (xr - h < 0 || xr + h >= r.cols) continue;
    cost[i] = NormalizedL1(l, xl, yl, r, xr, yl, h);
  }
  const std::optional<int> found = UniqueMinimum(cost, h, unique_ratio);
  if (!found) return std::nullopt;
  const int best = *found;
  const double c0 = cost[best - 1], c1 = cost[best], c2 = cost[best + 1];
  const double denom = c0 - 2 * c1 + c2;
  const double sub = denom > 0 ? 0.5 * (c0 - c2) / denom : 0.0;
  return (xr0 + lo + best + sub) - to.intrinsics.cx_px;
}

}  // namespace

std::optional<double> CentreDisparity(const rig::StereoFrame& frame, const ServoOptions& o,
                                      int search_px) {
  return SearchRow(frame.left, frame.right, o, -search_px, search_px, 1.0);
}

std::optional<double> MutualMismatch(const rig::StereoFrame& frame, const ServoOptions& o,
                                     double residual_px) {
  const auto reverse = SearchRow(frame.right, frame.left, o, -o.search_px, o.search_px, 1.0);
  if (!reverse) return std::nullopt;
  // Both searches centre their windows on the principal points' rounded
  // pixels: the left one's match lies residual_px right of the right
  // principal point, so the right one's lies as far left of the left one's,
  // shifted by the two roundings.
  const auto& kl = frame.left.intrinsics;
  const auto& kr = frame.right.intrinsics;
  const double expected =
      (std::lround(kl.cx_px) - kl.cx_px) + (std::lround(kr.cx_px) - kr.cx_px) - residual_px;
  return *reverse - expected;
}

std::optional<double> CentreDisparity(const rig::StereoFrame& frame, const ServoOptions& o,
                                      const DepthRange& depths) {
  if (!(depths.near_m > 0) || !(depths.far_m >= depths.near_m))
    throw std::invalid_argument("servo: depth range must have 0 < near_m <= far_m");
  const Eigen::Isometry3d right_T_left =
      frame.right.world_T_camera.inverse() * frame.left.world_T_camera;
  const rig::CameraIntrinsics& kl = frame.left.intrinsics;
  const rig::CameraIntrinsics& kr = frame.right.intrinsics;
  double lo = 1e300, hi = -1e300;
  for (const double z : {depths.near_m, depths.far_m}) {
    const double d = DisparityAtDepth(frame.left, frame.right, right_T_left, kl.cx_px, kl.cy_px, z);
    if (!std::isfinite(d)) continue;  // behind the right camera: the search ends at the image edge
    // Where the point appears in the right image, from its principal point.
    const double offset = kl.cx_px - d - kr.cx_px;
    lo = std::min(lo, offset);
    hi = std::max(hi, offset);
  }
  if (lo > hi) return std::nullopt;
  // Within the image: a window centred further out could not be compared.
  const double edge = std::max(kr.cx_px, kr.width_px - kr.cx_px);
  lo = std::max(lo, -edge);
  hi = std::min(hi, edge);
  return SearchRow(frame.left, frame.right, o, static_cast<int>(std::floor(lo)) - 1,
                   static_cast<int>(std::ceil(hi)) + 1, o.unique_ratio);
}

namespace {

// The costs of `from`'s window at `pixel` against `to`'s windows at the
// projections of the depths [near, far] along its ray, sampled by inverse
// depth about a pixel apart in `to`, with the pixels compared (1e300 where a
// window leaves the image). Empty when the range does not project.
struct RayCosts {
  std::vector<double> cost;
  std::vector<cv::Point> at;
};
RayCosts CostsAlongRay(const rig::CameraView& from, const rig::CameraView& to, cv::Point pixel,
                       const DepthRange& depths, int h) {
  const cv::Mat& l = from.gray;
  const cv::Mat& r = to.gray;
  const Eigen::Vector3d ray = from.intrinsics.Ray(Eigen::Vector2d(pixel.x, pixel.y));
  const Eigen::Isometry3d to_T_from = to.world_T_camera.inverse() * from.world_T_camera;
  auto project = [&](double inverse_depth) -> std::optional<Eigen::Vector2d> {
    const Eigen::Vector3d p = to_T_from * (ray / std::max(inverse_depth, 1e-9));
    if (p.z() <= 1e-6) return std::nullopt;
    return to.intrinsics.Project(p);
  };
  const double w_near = 1 / depths.near_m, w_far = 1 / depths.far_m;
  const auto a = project(w_near), b = project(w_far);
  if (!a || !b) return {};
  const int n = std::clamp(static_cast<int>(std::ceil((*a - *b).norm())) + 1, 3, 2000);
  RayCosts c{std::vector<double>(n, 1e300), std::vector<cv::Point>(n, cv::Point(-1, -1))};
  for (int i = 0; i < n; ++i) {
    const auto uv = project(w_far + (w_near - w_far) * i / (n - 1));
    if (!uv) continue;
    const int xr = static_cast<int>(std::lround(uv->x())),
              yr = static_cast<int>(std::lround(uv->y()));
    if (xr - h < 0 || yr - h < 0 || xr + h >= r.cols || yr + h >= r.rows) continue;
    c.at[i] = {xr, yr};
    c.cost[i] = NormalizedL1(l, pixel.x, pixel.y, r, xr, yr, h);
  }
  return c;
}

}  // namespace

bool UniqueAlongRay(const rig::StereoFrame& frame, const Eigen::Vector2d& pixel,
                    const DepthRange& depths, const ServoOptions& o) {
  const cv::Mat& l = frame.left.gray;
  const int h = o.window_half_px;
  const cv::Point p(static_cast<int>(std::lround(pixel.x())),
                    static_cast<int>(std::lround(pixel.y())));
  if (p.x - h < 0 || p.y - h < 0 || p.x + h >= l.cols || p.y + h >= l.rows) return false;
  if (!Textured(l, p.x, p.y, h)) return false;
  const RayCosts forward = CostsAlongRay(frame.left, frame.right, p, depths, h);
  const std::optional<int> best = UniqueMinimum(forward.cost, h, o.unique_ratio);
  if (!best) return false;
  if (!(o.mutual_tolerance_px > 0)) return true;
  // Mutual, as the servo will ask once verged: the right window's best match
  // along its own ray over the same depths falls back on the left pixel.
  const RayCosts back = CostsAlongRay(frame.right, frame.left, forward.at[*best], depths, h);
  const std::optional<int> back_best = UniqueMinimum(back.cost, h, 1.0);
  if (!back_best) return false;
  const cv::Point d = back.at[*back_best] - p;
  return std::hypot(d.x, d.y) < o.mutual_tolerance_px;
}

ServoResult Servo(rig::Rig& rig, const rig::StageState& start, const ServoOptions& o,
                  const std::optional<DepthRange>& first_depths) {
  ServoResult result;
  rig::StageState state = start;
  result.motion_time_s += rig.MoveTo(state).motion_time_s;
  for (int step = 0;; ++step) {
    result.frame = rig.Capture();
    result.state = result.frame.state;
    // Measured in the frame the foveal stereo will match in.
    result.measured = o.rectify ? ToFixationFrame(result.frame) : OriginalFrame(result.frame);
    const rig::StereoFrame& view = result.measured.views;
    const int refine =
        std::max(o.refine_px, static_cast<int>(std::ceil(std::abs(result.residual_px) / 4)));
    const auto d = step > 0       ? CentreDisparity(view, o, refine)
                   : first_depths ? CentreDisparity(view, o, *first_depths)
                                  : CentreDisparity(view, o, o.search_px);
    if (!d) break;
    result.residual_px = *d;
    result.residuals_px.push_back(*d);
    if (std::abs(*d) < o.tolerance_px) {
      result.converged = true;
      if (o.mutual_tolerance_px > 0) {
        result.mutual_mismatch_px = MutualMismatch(view, o, *d);
        result.mutual = result.mutual_mismatch_px &&
                        std::abs(*result.mutual_mismatch_px) < o.mutual_tolerance_px;
        result.converged = result.mutual;
      }
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
