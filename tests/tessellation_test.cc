#include "fovea/tessellation.h"

#include <catch2/catch.hpp>
#include <cmath>

#include "fovea/geometry.h"
#include "fovea/vergence.h"

namespace {

struct Pair {
  rig::CameraView left, right;
};

// A verged pair fixating p_W with baseline b.
Pair Verged(const Eigen::Vector3d& p_W, double b) {
  rig::RigGeometry g;
  g.left.optical_centre_H = g.right.optical_centre_H = {0.0, 0.03, 0.01};
  rig::RigLimits l;
  for (int i = 0; i < rig::kNumAxes; ++i) l.axes[i] = {-1.5, 1.5, 1e9};
  const auto k = rig::CameraIntrinsics::FromHorizontalFov(640, 480, 30 * M_PI / 180);
  const auto sol = fovea::Verge(g, l, k, k, rig::StageState::Parallel(b), p_W);
  REQUIRE(sol.ok);
  Pair pair;
  pair.left.intrinsics = pair.right.intrinsics = k;
  pair.left.world_T_camera = g.WorldFromCamera(rig::Side::kLeft, sol.state.left);
  pair.right.world_T_camera = g.WorldFromCamera(rig::Side::kRight, sol.state.right);
  return pair;
}

// A large patch on the left camera's fronto-parallel plane at depth z.
fovea::Patch FrontoPatch(const rig::CameraView& left, double z) {
  fovea::Patch p;
  const double h = 2.0;
  p.corners_W = {left.world_T_camera * Eigen::Vector3d(-h, -h, z),
                 left.world_T_camera * Eigen::Vector3d(h, -h, z),
                 left.world_T_camera * Eigen::Vector3d(h, h, z),
                 left.world_T_camera * Eigen::Vector3d(-h, h, z)};
  return p;
}

// Brute force, independent of the library's code: |v_right - v_left| for the
// point where each left pixel's ray meets the plane at depth z.
double BruteVerticalDisparity(const Pair& pair, double z, int u, int v) {
  const auto& k = pair.left.intrinsics;
  const Eigen::Vector3d p_C((u - k.cx_px) / k.fx_px * z, (v - k.cy_px) / k.fy_px * z, z);
  const auto uv =
      fovea::ProjectWorldPoint(pair.right.world_T_camera, k, pair.left.world_T_camera * p_C);
  return std::abs(uv->y() - v);
}

}  // namespace

TEST_CASE("tessellation of a fronto-parallel plane through the fixation point",
          "[fovea][tessellation]") {
  const Eigen::Vector3d fixation(0.05, 0.9, 0.02);
  const Pair pair = Verged(fixation, 0.12);
  const double z0 = (pair.left.world_T_camera.inverse() * fixation).z();
  fovea::PatchMap map;
  map.Add(FrontoPatch(pair.left, z0));
  const fovea::Tessellation t = fovea::Tessellate(pair.left, pair.right, fixation, map, {});
  CHECK(t.fixation_depth_m == Approx(z0));
  CHECK(t.z_max_far_m < 1e-6);
  CHECK(t.z_max_near_m < 1e-6);
  REQUIRE(t.rects.size() >= 2);
  const auto& k = pair.left.intrinsics;
  // Brute force: the largest centred rectangle of the image's shape whose
  // pixels all have vertical disparity under half a pixel.
  double scale = 1;
  for (int v = 0; v < k.height_px; ++v)
    for (int u = 0; u < k.width_px; ++u)
      if (BruteVerticalDisparity(pair, z0, u, v) >= 0.5)
        scale = std::min(scale, std::max(std::abs(u - k.cx_px) / (0.5 * k.width_px),
                                         std::abs(v - k.cy_px) / (0.5 * k.height_px)));
  const cv::Rect& fovea = t.rects[0];
  CHECK(fovea.width == Approx(scale * k.width_px).margin(2.0));
  CHECK(fovea.height == Approx(scale * k.height_px).margin(2.0));
  CHECK(fovea.width < k.width_px);  // vergence does bring vertical disparity
  // Inside each level, vertical disparity stays under half a pixel of it.
  for (size_t level = 0; level < t.rects.size(); ++level) {
    double worst = 0;
    const cv::Rect& r = t.rects[level];
    for (int v = r.y; v < r.y + r.height; v += 3)
      for (int u = r.x; u < r.x + r.width; u += 3)
        worst = std::max(worst, BruteVerticalDisparity(pair, z0, u, v));
    INFO("level " << level << " rect " << r << " worst " << worst);
    if (level + 1 < t.rects.size()) CHECK(worst < 0.5 * std::pow(2.0, level));
    if (level > 0) CHECK((r & t.rects[level - 1]) == t.rects[level - 1]);  // nested
  }
}

TEST_CASE("Z_T, Z_max and the depth mask follow the map", "[fovea][tessellation]") {
  const Eigen::Vector3d fixation(0, 1.0, 0);
  const Pair pair = Verged(fixation, 0.12);
  const double z0 = (pair.left.world_T_camera.inverse() * fixation).z();
  fovea::TessellationOptions options;
  const fovea::Tessellation flat = fovea::Tessellate(pair.left, pair.right, fixation, {}, options);
  // At Z_T the axis point's horizontal disparity is half the limit.
  const double d0 = fovea::AxisHorizontalDisparity(pair.left, pair.right, z0);
  CHECK(std::abs(fovea::AxisHorizontalDisparity(pair.left, pair.right, z0 + flat.z_t_far_m) - d0) ==
        Approx(0.5 * options.horizontal_disparity_limit_px).epsilon(1e-6));
  CHECK(std::abs(fovea::AxisHorizontalDisparity(pair.left, pair.right, z0 - flat.z_t_near_m) -
                 d0) == Approx(0.5 * options.horizontal_disparity_limit_px).epsilon(1e-6));
  CHECK(flat.z_t_near_m < flat.z_t_far_m);  // disparity changes faster in front
  // A map with a surface 2 cm behind, and one far beyond Z_T.
  fovea::PatchMap map;
  fovea::Patch behind = FrontoPatch(pair.left, z0 + 0.02);
  for (auto& c : behind.corners_W)
    c = pair.left.world_T_camera *
        Eigen::Vector3d((pair.left.world_T_camera.inverse() * c).x() > 0 ? 0.3 : 0.0,
                        (pair.left.world_T_camera.inverse() * c).y(), z0 + 0.02);
  map.Add(behind);
  fovea::Patch far = FrontoPatch(pair.left, z0 + 5.0);
  map.Add(far);
  const fovea::Tessellation t = fovea::Tessellate(pair.left, pair.right, fixation, map, options);
  CHECK(t.z_max_far_m == Approx(0.02).margin(1e-6));
  // The fovea shrinks for a surface off the fixation plane.
  CHECK(t.rects[0].area() < flat.rects[0].area());
  // Pixels showing only the far surface are masked; the near one's are not.
  const int u_right = 600, u_left = 40;
  CHECK(t.mask.at<uchar>(240, u_right) == 255);
  CHECK(t.mask.at<uchar>(240, u_left) == 0);
}
