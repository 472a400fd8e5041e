#include "fovea/tessellation.h"

#include <catch2/catch.hpp>
#include <cmath>

#include "fovea/fixation_frame.h"
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

namespace {

// A verged pair of the TAVT's kinematics (optical centres off the pan/tilt
// axes) fixating p_W, with blank images of the camera's size.
rig::StereoFrame VergedFrame(const Eigen::Vector3d& p_W, double b) {
  const Pair pair = Verged(p_W, b);
  rig::StereoFrame f;
  f.left = pair.left;
  f.right = pair.right;
  for (rig::CameraView* v : {&f.left, &f.right})
    v->gray = cv::Mat(v->intrinsics.height_px, v->intrinsics.width_px, CV_8U, cv::Scalar(128));
  return f;
}

Eigen::Vector3d AtElevation(double distance_m, double elevation_deg) {
  const double e = elevation_deg * M_PI / 180;
  return {0.02, distance_m * std::cos(e), distance_m * std::sin(e)};
}

}  // namespace

TEST_CASE("the fixation frame of a tilted verged pair is a level pair's",
          "[fovea][tessellation][fixation_frame]") {
  const double b = 0.12;
  const rig::StereoFrame tilted = VergedFrame(AtElevation(0.9, 15), b);
  const fovea::FixationFrame f = fovea::ToFixationFrame(tilted);
  REQUIRE(f.resampled);
  // Pan-then-tilt heads twist each image against the other by about
  // vergence x sin(elevation): a few tenths of a degree each, in opposite senses.
  CHECK(f.left_roll_rad * f.right_roll_rad < 0);
  CHECK(std::abs(f.left_roll_rad - f.right_roll_rad) > 0.005);
  // Axes that meet are already in the plane: only rolls; centres stay.
  CHECK(std::abs(f.right_turn_rad) < 1e-6);
  for (auto [a, o] : {std::pair(&f.views.left, &tilted.left), {&f.views.right, &tilted.right}}) {
    CHECK((a->world_T_camera.translation() - o->world_T_camera.translation()).norm() < 1e-12);
    CHECK(a->world_T_camera.linear().col(2).isApprox(o->world_T_camera.linear().col(2), 1e-6));
  }
  // H maps where a world point appears in the original image to where it
  // appears in the rolled one.
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(0.1, 0.95, 0.3), Eigen::Vector3d(-0.2, 0.7, 0.1),
                                   Eigen::Vector3d(0.05, 1.4, 0.5)}) {
    for (int side = 0; side < 2; ++side) {
      const rig::CameraView& o = side ? tilted.right : tilted.left;
      const rig::CameraView& v = side ? f.views.right : f.views.left;
      const auto uv = fovea::ProjectWorldPoint(o.world_T_camera, o.intrinsics, p);
      const auto uv_v = fovea::ProjectWorldPoint(v.world_T_camera, v.intrinsics, p);
      REQUIRE((uv && uv_v));
      const cv::Point2d mapped =
          fovea::MapPixels(side ? f.right_H : f.left_H, {{uv->x(), uv->y()}})[0];
      CHECK(mapped.x == Approx(uv_v->x()).margin(1e-6));
      CHECK(mapped.y == Approx(uv_v->y()).margin(1e-6));
    }
  }
  // Both rolled cameras' rows lie in one plane with the baseline: the
  // fixation point and every point of that plane have no vertical disparity.
  const Eigen::Vector3d n = f.views.left.world_T_camera.linear().col(1);
  CHECK(std::abs(n.dot(f.views.right.world_T_camera.linear().col(1))) == Approx(1).margin(1e-6));
  // The tessellation there is the level fixation's; the original pair's collapses.
  const rig::StereoFrame level = VergedFrame(AtElevation(0.9, 0.6), b);  // tilt ~0: see below
  const fovea::FixationFrame level_frame = fovea::ToFixationFrame(level);
  auto fovea_area = [](const rig::StereoFrame& s, const Eigen::Vector3d& p) {
    return fovea::Tessellate(s.left, s.right, p, {}, {}).rects.at(0).area();
  };
  const int level_area = fovea_area(level_frame.views, AtElevation(0.9, 0.6));
  const int rolled_area = fovea_area(f.views, AtElevation(0.9, 15));
  const int original_area = fovea_area(tilted, AtElevation(0.9, 15));
  INFO("fovea: level " << level_area << " px, tilted 15 deg: " << rolled_area
                       << " px in the fixation frame, " << original_area << " px unrectified");
  CHECK(rolled_area >= 0.95 * level_area);
  CHECK(original_area < 0.3 * level_area);
}

TEST_CASE("the rectified frame of a near, tilted verged pair has no vertical disparity",
          "[fovea][tessellation][fixation_frame]") {
  // A near fixation, tilted: the verged pair's vertical disparity reaches
  // several pixels towards the corners.
  const Eigen::Vector3d fixation = AtElevation(0.6, 12);
  const rig::StereoFrame verged = VergedFrame(fixation, 0.06);
  const fovea::FixationFrame f = fovea::ToFixationFrame(verged);
  const fovea::FixationFrame r = fovea::ToRectifiedFrame(verged);
  REQUIRE(r.resampled);
  // Centres stay; both views share one orientation and one camera matrix.
  for (auto [a, o] : {std::pair(&r.views.left, &verged.left), {&r.views.right, &verged.right}})
    CHECK((a->world_T_camera.translation() - o->world_T_camera.translation()).norm() < 1e-12);
  CHECK(
      r.views.left.world_T_camera.linear().isApprox(r.views.right.world_T_camera.linear(), 1e-12));
  CHECK(r.views.left.intrinsics.cx_px == r.views.right.intrinsics.cx_px);
  // The left optical axis keeps its pixel.
  const auto& k = verged.left.intrinsics;
  const cv::Point2d centre = fovea::MapPixels(r.left_H, {{k.cx_px, k.cy_px}})[0];
  CHECK(centre.x == Approx(k.cx_px).margin(1e-6));
  CHECK(centre.y == Approx(k.cy_px).margin(1e-6));
  CHECK(cv::countNonZero(r.left_valid) > 0.97 * r.left_valid.total());
  // Points near the image's corners at depths from 0.4 to 1.6 m: the same
  // row in both rectified views, where the fixation frame's rows differ by
  // pixels; H maps the original pixels to the rectified ones.
  double worst_fixation_frame = 0;
  const Eigen::Isometry3d& left_W = verged.left.world_T_camera;
  for (const double z : {0.4, 0.6, 1.0, 1.6})
    for (const double u : {30.0, 320.0, 610.0})
      for (const double v : {30.0, 450.0}) {
        const Eigen::Vector3d p = left_W * (z * k.Ray({u, v}));
        for (const fovea::FixationFrame* frame : {&f, &r}) {
          const auto l = fovea::ProjectWorldPoint(frame->views.left.world_T_camera,
                                                  frame->views.left.intrinsics, p);
          const auto rr = fovea::ProjectWorldPoint(frame->views.right.world_T_camera,
                                                   frame->views.right.intrinsics, p);
          REQUIRE((l && rr));
          if (frame == &r)
            CHECK(l->y() == Approx(rr->y()).margin(1e-6));
          else
            worst_fixation_frame = std::max(worst_fixation_frame, std::abs(l->y() - rr->y()));
        }
        const auto o =
            fovea::ProjectWorldPoint(verged.right.world_T_camera, verged.right.intrinsics, p);
        const auto rr =
            fovea::ProjectWorldPoint(r.views.right.world_T_camera, r.views.right.intrinsics, p);
        REQUIRE((o && rr));
        const cv::Point2d mapped = fovea::MapPixels(r.right_H, {{o->x(), o->y()}})[0];
        CHECK(mapped.x == Approx(rr->x()).margin(1e-6));
        CHECK(mapped.y == Approx(rr->y()).margin(1e-6));
      }
  INFO("fixation frame's largest vertical disparity: " << worst_fixation_frame << " px");
  CHECK(worst_fixation_frame > 2);
}

TEST_CASE("a level verged pair is its own fixation frame",
          "[fovea][tessellation][fixation_frame]") {
  // The optical centres sit 1 cm above the tilt axes: a point at that height
  // needs no tilt, the rows stay in the baseline's plane, nothing is resampled.
  const rig::StereoFrame level = VergedFrame({0.02, 0.9, 0.01}, 0.12);
  const fovea::FixationFrame f = fovea::ToFixationFrame(level);
  CHECK_FALSE(f.resampled);
  CHECK(f.views.left.gray.data == level.left.gray.data);  // the same images, not copies
  CHECK(size_t(cv::countNonZero(f.left_valid)) == f.left_valid.total());
}

TEST_CASE("the fixation frame gives both cameras one pixel grid when their intrinsics differ",
          "[fovea][tessellation][fixation_frame]") {
  // A calibrated pair: the right principal point 0.7 px lower, its focal
  // length 0.1% longer. Rows of one image are no longer rows of the other:
  // the tessellation reads 0.7 px of vertical disparity at the fixation
  // and the fovea shrinks to its floor. The fixation frame resamples the
  // right image onto the left camera's grid.
  rig::StereoFrame level = VergedFrame({0.02, 0.9, 0.01}, 0.12);
  const Eigen::Vector3d fixation = {0.02, 0.9, 0.01};
  rig::CameraIntrinsics& kr = level.right.intrinsics;
  kr.cy_px += 0.7;
  kr.fx_px *= 1.001;
  kr.fy_px *= 1.001;
  const fovea::FixationFrame f = fovea::ToFixationFrame(level);
  REQUIRE(f.resampled);
  const rig::CameraIntrinsics& kl = f.views.left.intrinsics;
  for (const rig::CameraIntrinsics* k : {&f.views.left.intrinsics, &f.views.right.intrinsics}) {
    CHECK(k->fx_px == kl.fx_px);
    CHECK(k->fy_px == kl.fy_px);
    CHECK(k->cx_px == kl.cx_px);
    CHECK(k->cy_px == kl.cy_px);
  }
  // H still carries a world point's original pixel to its new one.
  const Eigen::Vector3d p(0.1, 1.0, 0.08);
  const auto uv = fovea::ProjectWorldPoint(level.right.world_T_camera, kr, p);
  const auto uv_f = fovea::ProjectWorldPoint(f.views.right.world_T_camera, kl, p);
  REQUIRE((uv && uv_f));
  const cv::Point2d mapped = fovea::MapPixels(f.right_H, {{uv->x(), uv->y()}})[0];
  CHECK(mapped.x == Approx(uv_f->x()).margin(1e-6));
  CHECK(mapped.y == Approx(uv_f->y()).margin(1e-6));
  auto fovea_area = [&](const rig::StereoFrame& s) {
    return fovea::Tessellate(s.left, s.right, fixation, {}, {}).rects.at(0).area();
  };
  const rig::StereoFrame same = VergedFrame(fixation, 0.12);
  INFO("fovea: equal intrinsics " << fovea_area(same) << " px, differing " << fovea_area(level)
                                  << " px unrectified, " << fovea_area(f.views)
                                  << " px in the fixation frame");
  CHECK(fovea_area(level) < 0.1 * fovea_area(same));
  CHECK(fovea_area(f.views) >= 0.95 * fovea_area(same));
}

TEST_CASE("in the fixation frame the optical axes meet after the right camera pans",
          "[fovea][tessellation][fixation_frame]") {
  // The servo pans the tilted right camera about the vertical: its axis
  // sweeps a cone and passes above or below the left one's, which shifts
  // every row by a constant. Turned into the fixation frame, points on the
  // left optical axis at any depth appear on the right image's middle row.
  rig::StereoFrame tilted = VergedFrame(AtElevation(0.9, 20), 0.12);
  Eigen::Isometry3d& right = tilted.right.world_T_camera;
  right.linear() = Eigen::AngleAxisd(2 * M_PI / 180, Eigen::Vector3d::UnitZ()) * right.linear();
  const fovea::FixationFrame f = fovea::ToFixationFrame(tilted);
  CHECK(std::abs(f.right_turn_rad) > 5e-4);  // 0.04 degrees out of the plane
  const auto& k = tilted.left.intrinsics;
  double original_worst = 0;
  for (const double z : {0.5, 0.9, 1.5, 5.0}) {
    const Eigen::Vector3d p_W = tilted.left.world_T_camera * Eigen::Vector3d(0, 0, z);
    const auto turned =
        fovea::ProjectWorldPoint(f.views.right.world_T_camera, f.views.right.intrinsics, p_W);
    const auto original = fovea::ProjectWorldPoint(right, tilted.right.intrinsics, p_W);
    REQUIRE((turned && original));
    CHECK(turned->y() == Approx(k.cy_px).margin(1e-6));
    original_worst = std::max(original_worst, std::abs(original->y() - k.cy_px));
  }
  CHECK(original_worst > 2);  // measured 3.8 px
}

TEST_CASE("the fovea has a floor of foveal.min_fovea_px, and the levels stay nested",
          "[fovea][tessellation]") {
  // A tilted verged pair, unrectified: the paper's rule leaves a few pixels.
  const Eigen::Vector3d fixation = AtElevation(0.6, 20);
  const Pair pair = Verged(fixation, 0.12);
  fovea::TessellationOptions paper;
  paper.min_fovea_px = 0;
  paper.max_levels = 4;
  const fovea::Tessellation bare = fovea::Tessellate(pair.left, pair.right, fixation, {}, paper);
  REQUIRE(bare.rects[0].width < 32);
  fovea::TessellationOptions floored = paper;
  floored.min_fovea_px = 32;
  const fovea::Tessellation t = fovea::Tessellate(pair.left, pair.right, fixation, {}, floored);
  CHECK(t.rects[0].width == 32);
  CHECK(t.rects[0].height == 32);
  const auto& k = pair.left.intrinsics;
  CHECK(std::abs(t.rects[0].x + 0.5 * t.rects[0].width - k.cx_px) <= 1);  // centred
  CHECK(std::abs(t.rects[0].y + 0.5 * t.rects[0].height - k.cy_px) <= 1);
  for (size_t level = 1; level < t.rects.size(); ++level)
    CHECK((t.rects[level] & t.rects[level - 1]) == t.rects[level - 1]);
}

TEST_CASE("every level's rectangle is the largest centred one its threshold allows",
          "[fovea][tessellation]") {
  // The paper's 4 levels on a tilted verged pair, where the levels differ:
  // each level but the last against a brute-force scan of every pixel (the
  // library visits only the pixels that can narrow a level).
  for (const double elevation_deg : {0.0, 20.0}) {
    const Eigen::Vector3d fixation = AtElevation(0.6, elevation_deg);
    const Pair pair = Verged(fixation, 0.12);
    const double z0 = (pair.left.world_T_camera.inverse() * fixation).z();
    fovea::TessellationOptions paper;
    paper.min_fovea_px = 0;
    paper.max_levels = 4;
    const fovea::Tessellation t = fovea::Tessellate(pair.left, pair.right, fixation, {}, paper);
    const auto& k = pair.left.intrinsics;
    std::vector<double> worst(k.width_px * k.height_px);
    for (int v = 0; v < k.height_px; ++v)
      for (int u = 0; u < k.width_px; ++u)
        worst[v * k.width_px + u] = BruteVerticalDisparity(pair, z0, u, v);
    REQUIRE(t.rects.size() >= 3);
    for (size_t level = 0; level + 1 < t.rects.size(); ++level) {
      double scale = 1;
      for (int v = 0; v < k.height_px; ++v)
        for (int u = 0; u < k.width_px; ++u)
          if (worst[v * k.width_px + u] >= 0.5 * std::pow(2.0, level))
            scale = std::min(scale, std::max(std::abs(u - k.cx_px) / (0.5 * k.width_px),
                                             std::abs(v - k.cy_px) / (0.5 * k.height_px)));
      INFO("elevation " << elevation_deg << " level " << level << " rect " << t.rects[level]);
      CHECK(t.rects[level].width == Approx(scale * k.width_px).margin(2.0));
      CHECK(t.rects[level].height == Approx(scale * k.height_px).margin(2.0));
    }
  }
}

TEST_CASE("the parallel frame turns a pair with turned mounts and differing intrinsics into rows",
          "[fovea][fixation_frame]") {
  // IDR's pair on an imperfect rig: both cameras pointed straight ahead
  // through the believed chain, yet each turned on its mount, and the right
  // camera with its own principal point and focal length. Rectified, a
  // point shows on one row of both images, where the images show it.
  rig::RigGeometry g;
  g.left.optical_centre_H = g.right.optical_centre_H = {0.02, 0.08, 0.02};
  g.left.mount_rpy_rad = {0.026, 0.026, 0.026};
  g.right.mount_rpy_rad = {-0.026, 0.026, -0.026};
  rig::StageState s;
  s.left = g.ParallelStage(rig::Side::kLeft, -0.04);
  s.right = g.ParallelStage(rig::Side::kRight, 0.04);
  rig::StereoFrame frame;
  frame.left.intrinsics = frame.right.intrinsics =
      rig::CameraIntrinsics::FromHorizontalFov(640, 480, 30 * M_PI / 180);
  frame.right.intrinsics.cy_px += 0.7;
  frame.right.intrinsics.cx_px -= 1.2;
  frame.right.intrinsics.fx_px *= 1.001;
  frame.right.intrinsics.fy_px *= 1.001;
  frame.left.world_T_camera = g.WorldFromCamera(rig::Side::kLeft, s.left);
  frame.right.world_T_camera = g.WorldFromCamera(rig::Side::kRight, s.right);
  // Each image: a blurred dot where it sees p.
  const Eigen::Vector3d p(0.15, 1.1, 0.12);
  for (rig::CameraView* v : {&frame.left, &frame.right}) {
    const auto uv = fovea::ProjectWorldPoint(v->world_T_camera, v->intrinsics, p);
    REQUIRE(uv);
    cv::Mat dot(480, 640, CV_32F, cv::Scalar(0));
    for (int y = 0; y < 480; ++y)
      for (int x = 0; x < 640; ++x)
        dot.at<float>(y, x) =
            200 *
            std::exp(-(std::pow(x - uv->x(), 2) + std::pow(y - uv->y(), 2)) / (2 * 2.0 * 2.0));
    dot.convertTo(v->gray, CV_8U);
  }
  const rig::StereoFrame rect = fovea::ToParallelFrame(frame);
  const rig::CameraIntrinsics& k = rect.left.intrinsics;
  CHECK(rect.right.intrinsics.cx_px == k.cx_px);
  CHECK(rect.right.intrinsics.cy_px == k.cy_px);
  CHECK(rect.right.intrinsics.fx_px == k.fx_px);
  CHECK(rect.left.world_T_camera.linear().isApprox(rect.right.world_T_camera.linear(), 1e-12));
  std::array<cv::Point2d, 2> seen;
  for (int side = 0; side < 2; ++side) {
    const rig::CameraView& v = side ? rect.right : rect.left;
    const auto uv = fovea::ProjectWorldPoint(v.world_T_camera, v.intrinsics, p);
    REQUIRE(uv);
    const cv::Moments m = cv::moments(v.gray);
    seen[side] = {m.m10 / m.m00, m.m01 / m.m00};
    INFO((side ? "right" : "left")
         << ": dot at " << seen[side] << ", projected at " << uv->transpose());
    CHECK(seen[side].x == Approx(uv->x()).margin(0.05));
    CHECK(seen[side].y == Approx(uv->y()).margin(0.05));
  }
  // The same row, but for the centres' offset off the rail (the heads turn
  // differently to point their turned cameras ahead: millimetres, 0.12 px
  // at 1.1 m). Unrectified, the rolls and principal points put the dot
  // rows apart.
  CHECK(std::abs(seen[0].y - seen[1].y) < 0.2);
  const auto l = fovea::ProjectWorldPoint(frame.left.world_T_camera, frame.left.intrinsics, p);
  const auto r = fovea::ProjectWorldPoint(frame.right.world_T_camera, frame.right.intrinsics, p);
  CHECK(std::abs(l->y() - r->y()) > 5);
}
