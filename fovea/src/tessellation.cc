#include "fovea/tessellation.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "fovea/params.h"

namespace fovea {

void TessellationOptions::Check() const {
  rig::CheckParam(params::kFovealHorizontalDisparityLimitPx, horizontal_disparity_limit_px);
  rig::CheckParam(params::kFovealMaxLevels, max_levels);
  rig::CheckParam(params::kFovealMinFoveaPx, min_fovea_px);
}

int Tessellation::LevelAt(int u, int v) const {
  for (size_t k = 0; k < rects.size(); ++k)
    if (rects[k].contains({u, v})) return static_cast<int>(k);
  return static_cast<int>(rects.size()) - 1;
}

double AxisHorizontalDisparity(const rig::CameraView& left, const rig::CameraView& right,
                               double z) {
  const Eigen::Vector3d p_W = left.world_T_camera * Eigen::Vector3d(0, 0, z);
  const Eigen::Vector3d p_R = right.world_T_camera.inverse() * p_W;
  return right.intrinsics.fx_px * p_R.x() / p_R.z();
}

namespace {

// Worst-case |vertical disparity| of left pixel (u, v), px: over the points
// where its ray meets the left-camera fronto-parallel planes at `depths`,
// by real projection into the right camera.
float PixelVerticalDisparity(const rig::CameraIntrinsics& kl, const rig::CameraIntrinsics& kr,
                             const Eigen::Isometry3d& right_T_left,
                             const std::vector<double>& depths, int u, int v) {
  float worst = 0;
  const Eigen::Vector3d ray = kl.Ray({u, v});  // z = 1
  for (double z : depths) {
    const Eigen::Vector3d p_R = right_T_left * (z * ray);
    if (p_R.z() <= 0) continue;
    const double vr = kr.fy_px * p_R.y() / p_R.z() + kr.cy_px;
    worst = std::max(worst, static_cast<float>(std::abs(vr - v)));
  }
  return worst;
}

// Per threshold, the smallest ring max(|u - cx| / hw, |v - cy| / hh) of a
// left pixel whose worst |vertical disparity| reaches it, 1 if none: the
// scale of the largest centred rectangle of the image's shape that excludes
// every such pixel. Vertical disparity is only computed where it can lower
// a scale: a grid every kGridPx pixels bounds the scales from above, then
// only the pixels within the largest bound's ring are visited. The same
// minimum as a visit of every pixel: a pixel outside the bound's ring
// cannot lower it, and the bound is itself a violating pixel's ring.
std::vector<double> ViolationScales(const rig::CameraView& left, const rig::CameraView& right,
                                    const std::vector<double>& depths,
                                    const std::vector<float>& thresholds) {
  constexpr int kGridPx = 8;
  const rig::CameraIntrinsics& k = left.intrinsics;
  const Eigen::Isometry3d right_T_left = right.world_T_camera.inverse() * left.world_T_camera;
  const double cx = k.cx_px, cy = k.cy_px, hw = 0.5 * k.width_px, hh = 0.5 * k.height_px;
  std::vector<double> scales(thresholds.size(), 1.0);
  if (thresholds.empty()) return scales;
  auto visit = [&](int u, int v, double ring) {
    const float worst = PixelVerticalDisparity(k, right.intrinsics, right_T_left, depths, u, v);
    for (size_t i = 0; i < thresholds.size(); ++i)
      if (worst >= thresholds[i]) scales[i] = std::min(scales[i], ring);
  };
  auto ring = [&](int u, int v) { return std::max(std::abs(u - cx) / hw, std::abs(v - cy) / hh); };
  for (int v = 0; v < k.height_px; v += kGridPx)
    for (int u = 0; u < k.width_px; u += kGridPx) visit(u, v, ring(u, v));
  const double bound = *std::max_element(scales.begin(), scales.end());
  const int u0 = std::max(0, static_cast<int>(std::floor(cx - bound * hw)) - 1),
            u1 = std::min(k.width_px - 1, static_cast<int>(std::ceil(cx + bound * hw)) + 1),
            v0 = std::max(0, static_cast<int>(std::floor(cy - bound * hh)) - 1),
            v1 = std::min(k.height_px - 1, static_cast<int>(std::ceil(cy + bound * hh)) + 1);
  for (int v = v0; v <= v1; ++v)
    for (int u = u0; u <= u1; ++u)
      if (const double r = ring(u, v); r <= bound) visit(u, v, r);
  return scales;
}

// `r` grown, centred on the principal point, to at least `size` pixels wide
// and high (within the image).
cv::Rect AtLeast(const cv::Rect& r, int size, double cx, double cy,
                 const rig::CameraIntrinsics& k) {
  cv::Rect out = r;
  if (r.width < size) {
    out.x = std::max(0, static_cast<int>(std::lround(cx - 0.5 * size)));
    out.width = std::min(size, k.width_px - out.x);
  }
  if (r.height < size) {
    out.y = std::max(0, static_cast<int>(std::lround(cy - 0.5 * size)));
    out.height = std::min(size, k.height_px - out.y);
  }
  return out;
}

}  // namespace

Tessellation Tessellate(const rig::CameraView& left, const rig::CameraView& right,
                        const Eigen::Vector3d& fixation_W, const PatchMap& map,
                        const TessellationOptions& options) {
  cv::Mat depth;
  map.Render(left.world_T_camera, left.intrinsics, &depth, nullptr);
  return TessellateFromDepth(left, right, fixation_W, depth, options);
}

Tessellation TessellateFromDepth(const rig::CameraView& left, const rig::CameraView& right,
                                 const Eigen::Vector3d& fixation_W, const cv::Mat& depth,
                                 const TessellationOptions& options) {
  Tessellation t;
  const rig::CameraIntrinsics& k = left.intrinsics;
  t.fixation_depth_m = (left.world_T_camera.inverse() * fixation_W).z();
  const double z0 = t.fixation_depth_m;
  const double d0 = AxisHorizontalDisparity(left, right, z0);
  const double half_limit = 0.5 * options.horizontal_disparity_limit_px;
  // Z_T on each side by bisection on the real projection.
  auto solve = [&](double sign, double max_offset) {
    double lo = 0, hi = max_offset;
    if (std::abs(AxisHorizontalDisparity(left, right, z0 + sign * hi) - d0) < half_limit) return hi;
    for (int i = 0; i < 60; ++i) {
      const double mid = 0.5 * (lo + hi);
      (std::abs(AxisHorizontalDisparity(left, right, z0 + sign * mid) - d0) < half_limit ? lo
                                                                                         : hi) =
          mid;
    }
    return 0.5 * (lo + hi);
  };
  t.z_t_far_m = solve(+1, 20.0);
  t.z_t_near_m = solve(-1, std::max(0.0, z0 - 0.05));

  // Z_max from the map in view, limited to Z_T; the mask from the same depths.
  t.mask = cv::Mat(k.height_px, k.width_px, CV_8U, cv::Scalar(255));
  for (int v = 0; v < k.height_px; ++v)
    for (int u = 0; u < k.width_px; ++u) {
      const float z = depth.at<float>(v, u);
      if (z <= 0) continue;
      if (t.BeyondZt(z)) {
        t.mask.at<uchar>(v, u) = 0;
        continue;
      }
      const double off = z - z0;
      t.z_max_far_m = std::max(t.z_max_far_m, off);
      t.z_max_near_m = std::max(t.z_max_near_m, -off);
    }
  // Level k holds where |vertical disparity| < 0.5 * 2^k: the largest centred
  // rectangle of the image's shape that excludes every violating pixel. The
  // last level is the whole image: its threshold is not needed.
  std::vector<float> thresholds;
  for (int level = 0; level + 1 < options.max_levels; ++level)
    thresholds.push_back(static_cast<float>(0.5 * std::pow(2.0, level)));
  const std::vector<double> scales =
      ViolationScales(left, right, {z0 - t.z_max_near_m, z0, z0 + t.z_max_far_m}, thresholds);
  const double cx = k.cx_px, cy = k.cy_px, hw = 0.5 * k.width_px, hh = 0.5 * k.height_px;
  for (int level = 0; level < options.max_levels; ++level) {
    double scale = level < static_cast<int>(scales.size()) ? scales[level] : 1.0;
    const bool last = level + 1 == options.max_levels || scale >= 1.0;
    if (last) scale = 1.0;
    // Pixels strictly inside |u - cx| < scale hw, |v - cy| < scale hh.
    const int x0 = static_cast<int>(std::floor(cx - scale * hw)) + 1,
              x1 = static_cast<int>(std::ceil(cx + scale * hw)) - 1;
    const int y0 = static_cast<int>(std::floor(cy - scale * hh)) + 1,
              y1 = static_cast<int>(std::ceil(cy + scale * hh)) - 1;
    cv::Rect r(std::max(0, x0), std::max(0, y0), 0, 0);
    r.width = std::min(k.width_px - 1, x1) - r.x + 1;
    r.height = std::min(k.height_px - 1, y1) - r.y + 1;
    if (last) r = cv::Rect(0, 0, k.width_px, k.height_px);
    if (level == 0) r = AtLeast(r, options.min_fovea_px, cx, cy, k);
    if (level > 0) r |= t.rects.back();  // nested
    t.rects.push_back(r);
    if (last) break;
  }
  return t;
}

}  // namespace fovea
