#include "fovea/foveal.h"

#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <utility>

#include "fovea/geometry.h"
#include "fovea/timing.h"
#include "rig/left_pair.h"

namespace fovea {

void FovealOptions::Check() const {
  tessellation.Check();
  if (fovea_patch_px < 3 || periphery_patch_px < 3)
    throw std::invalid_argument("foveal: patch sizes must be >= 3");
  if (!(map_margin_px > 0) || !(coarse_margin_px > 0))
    throw std::invalid_argument("foveal: margins must be positive");
  if (!(silent_near_m >= 0)) throw std::invalid_argument("foveal: silent_near_m must be >= 0");
}

void FixationOptions::Check() const {
  vergence.Check();
  servo.Check();
  foveal.Check();
  if (!(baseline_m > 0)) throw std::invalid_argument("fixation: baseline_m must be positive");
  if (!(min_depth_m >= 0)) throw std::invalid_argument("fixation: min_depth_m must be >= 0");
}

FovealResult FovealStereo(const rig::StereoFrame& frame, const Eigen::Vector3d& fixation_W,
                          const PatchMap& map, const StereoMatcher& matcher,
                          const FovealOptions& options, int fixation) {
  options.Check();
  const auto t_start = Clock::now();
  FovealResult result;
  const rig::CameraView& left = frame.left;
  const rig::CameraView& right = frame.right;
  const rig::CameraIntrinsics& k = left.intrinsics;
  result.tessellation = Tessellate(left, right, fixation_W, map, options.tessellation);
  const Tessellation& t = result.tessellation;
  const Eigen::Isometry3d right_T_left = right.world_T_camera.inverse() * left.world_T_camera;
  cv::Mat map_depth;
  map.Render(left.world_T_camera, k, &map_depth, nullptr);
  const double z0 = t.fixation_depth_m;

  const int levels = static_cast<int>(t.rects.size());
  result.disparity_px.resize(levels);
  result.levels.resize(levels);
  for (int level = levels - 1; level >= 0; --level) {
    const auto t0 = Clock::now();
    const double s = std::pow(2.0, level);
    cv::Mat l, r;
    if (level == 0) {
      l = left.gray;
      r = right.gray;
    } else {
      cv::resize(left.gray, l, cv::Size(), 1 / s, 1 / s, cv::INTER_AREA);
      cv::resize(right.gray, r, cv::Size(), 1 / s, 1 / s, cv::INTER_AREA);
    }
    const cv::Rect& rect = t.rects[level];
    cv::Mat lo(l.size(), CV_32F, cv::Scalar(1)),
        hi(l.size(), CV_32F, cv::Scalar(0));  // lo > hi: skip
    // Where the map is silent: the range from silent_near_m to infinity.
    cv::Mat wide_lo(l.size(), CV_32F, cv::Scalar(1)), wide_hi(l.size(), CV_32F, cv::Scalar(0));
    const cv::Mat* coarse = level + 1 < levels ? &result.disparity_px[level + 1] : nullptr;
    for (int y = 0; y < l.rows; ++y)
      for (int x = 0; x < l.cols; ++x) {
        const double u = (x + 0.5) * s - 0.5, v = (y + 0.5) * s - 0.5;
        const int ui = std::clamp(static_cast<int>(std::lround(u)), 0, k.width_px - 1);
        const int vi = std::clamp(static_cast<int>(std::lround(v)), 0, k.height_px - 1);
        if (!rect.contains({ui, vi}) || t.mask.at<uchar>(vi, ui) == 0) continue;
        double dlo, dhi;
        const float cd = coarse ? coarse->at<float>(std::min(coarse->rows - 1, y / 2),
                                                    std::min(coarse->cols - 1, x / 2))
                                : std::numeric_limits<float>::quiet_NaN();
        const float z = map_depth.at<float>(vi, ui);
        if (std::isfinite(cd)) {
          // The coarser level's estimate, in this level's pixels.
          dlo = 2 * cd - options.coarse_margin_px;
          dhi = 2 * cd + options.coarse_margin_px;
        } else if (z > 0) {
          const double d = DisparityAtDepth(left, right, right_T_left, u, v, z) / s;
          dlo = d - options.map_margin_px;
          dhi = d + options.map_margin_px;
        } else {
          // The map is silent: anything within Z_T of the fixation depth.
          const double a = DisparityAtDepth(left, right, right_T_left, u, v, z0 - t.z_t_near_m) / s;
          const double b = DisparityAtDepth(left, right, right_T_left, u, v, z0 + t.z_t_far_m) / s;
          dlo = std::min(a, b) - 1;
          dhi = std::max(a, b) + 1;
          if (options.silent_near_m > 0) {
            const double n =
                DisparityAtDepth(left, right, right_T_left, u, v, options.silent_near_m) / s;
            const double f = DisparityAtDepth(left, right, right_T_left, u, v, kFarDepthM) / s;
            if (std::isfinite(n) && std::isfinite(f)) {
              wide_lo.at<float>(y, x) = static_cast<float>(std::min({dlo, n, f}));
              wide_hi.at<float>(y, x) = static_cast<float>(std::max({dhi, n, f}));
            }
          }
        }
        if (!std::isfinite(dlo) || !std::isfinite(dhi)) continue;
        lo.at<float>(y, x) = static_cast<float>(dlo);
        hi.at<float>(y, x) = static_cast<float>(dhi);
      }
    DisparityMap dm = matcher.Match(l, r, lo, hi);
    // A band match where the wide search confidently matched outside Z_T is
    // a false match of a surface the band does not hold: dropped.
    int outside_band = 0;
    if (options.silent_near_m > 0) {
      // Only where the band matched is there anything to drop.
      for (int y = 0; y < l.rows; ++y)
        for (int x = 0; x < l.cols; ++x)
          if (!std::isfinite(dm.disparity_px.at<float>(y, x))) {
            wide_lo.at<float>(y, x) = 1;  // lo > hi: not searched
            wide_hi.at<float>(y, x) = 0;
          }
      const DisparityMap wide = matcher.Match(l, r, wide_lo, wide_hi);
      for (int y = 0; y < l.rows; ++y)
        for (int x = 0; x < l.cols; ++x) {
          float& d = dm.disparity_px.at<float>(y, x);
          const float w = wide.disparity_px.at<float>(y, x);
          if (!std::isfinite(d) || !std::isfinite(w) ||
              wide.confidence.at<float>(y, x) < options.silent_confidence)
            continue;
          if (w < lo.at<float>(y, x) - 1 || w > hi.at<float>(y, x) + 1) {
            d = std::numeric_limits<float>::quiet_NaN();
            ++outside_band;
          }
        }
    }
    result.disparity_px[level] = dm.disparity_px;
    LevelFigures& fig = result.levels[level];
    fig.level = level;
    fig.rect = rect;
    fig.searched = dm.searched;
    fig.matched = dm.matched - outside_band;
    fig.outside_band = outside_band;
    fig.match_time_s = Since(t0);

    // Patches over the part of the level not covered by the finer one.
    const cv::Rect inner = level > 0 ? t.rects[level - 1] : cv::Rect();
    // Peripheral patches keep about the same size in the image at every
    // level (the paper's were about twice the foveal ones), but never fewer
    // than 4 x 4 of the level's pixels; their fit tolerance shrinks with the
    // level so that it stays near a full-resolution pixel and a plane cannot
    // bridge a depth step.
    const int size =
        level == 0 ? options.fovea_patch_px : std::max(4, options.periphery_patch_px >> level);
    PlaneFitOptions fit_options = options.plane_fit;
    if (level > 0) {
      fit_options.fit_tolerance_px = std::max(0.25, options.plane_fit.fit_tolerance_px / s);
      fit_options.min_support = std::min(options.plane_fit.min_support, (3 * size * size) / 4);
    }
    for (int by = 0; by + size <= l.rows; by += size)
      for (int bx = 0; bx + size <= l.cols; bx += size) {
        const double cu = (bx + 0.5 * size) * s - 0.5, cv_ = (by + 0.5 * size) * s - 0.5;
        if (!rect.contains({static_cast<int>(cu), static_cast<int>(cv_)})) continue;
        if (level > 0 && inner.contains({static_cast<int>(cu), static_cast<int>(cv_)})) continue;
        std::vector<DisparitySample> samples;
        for (int y = by; y < by + size; ++y)
          for (int x = bx; x < bx + size; ++x) {
            const float d = dm.disparity_px.at<float>(y, x);
            if (std::isfinite(d)) samples.push_back({double(x), double(y), d});
          }
        const auto fit = FitDisparityPlane(samples, bx, by, size, fit_options);
        if (!fit) continue;
        // The patch spans its whole block: the fit has inliers in all four
        // quadrants, and blocks that tile the image leave no cracks between
        // their patches (shrinking to the inliers' extent left gaps of up to
        // a level pixel, 8 full-resolution pixels at level 3).
        const double ex0 = bx - 0.5, ey0 = by - 0.5, ex1 = bx + size - 0.5, ey1 = by + size - 0.5;
        Patch p;
        p.level = level == 0 ? PatchLevel::kFoveal : PatchLevel::kPeripheral;
        p.resolution_level = level;
        p.fixation = fixation;
        p.fit_rms_px = fit->rms_px;
        p.support = fit->support;
        const double xs[4] = {ex0, ex1, ex1, ex0}, ys[4] = {ey0, ey0, ey1, ey1};
        bool ok = true;
        for (int c = 0; c < 4 && ok; ++c) {
          const double d = (*fit)(xs[c], ys[c]) * s;
          const double u = (xs[c] + 0.5) * s - 0.5, v = (ys[c] + 0.5) * s - 0.5;
          const auto tri =
              TriangulateMidpoint(PixelRay(left.world_T_camera, k, {u, v}),
                                  PixelRay(right.world_T_camera, right.intrinsics, {u - d, v}));
          ok = tri.has_value();
          if (ok) p.corners_W[c] = tri->p_W;
        }
        if (!ok) continue;
        result.patches.Add(p);
        ++fig.patches;
      }
  }
  result.compute_time_s = Since(t_start);
  return result;
}

FixationResult Fixate(rig::Rig& rig, const PatchMap& map, const Eigen::Vector3d& p_W,
                      const StereoMatcher& matcher, const FixationOptions& options, int fixation,
                      const std::optional<DepthRange>& guessed_depths) {
  options.Check();
  FixationResult r;
  const auto t0 = Clock::now();
  if (options.choose_placement) {
    const PlacementChoice choice =
        ChoosePlacement(PlacementRig::Of(rig, options.left_pair), map, p_W, options.baseline_m,
                        options.vergence, guessed_depths);
    r.placement = choice.placement;
    r.vergence = choice.vergence;
  } else {
    r.vergence = Verge(rig.Geometry(), rig.Limits(), rig.Intrinsics(rig::Side::kLeft),
                       rig.Intrinsics(rig::Side::kRight),
                       rig::StageState::Parallel(options.baseline_m), p_W, options.vergence);
  }
  if (!r.vergence.ok) {
    r.why = r.vergence.why;
    return r;
  }
  const double verge_s = Since(t0);
  r.verge_time_s = verge_s;
  const auto t_servo = Clock::now();
  std::optional<rig::LeftCameraPair> left_pair;
  if (r.placement == Placement::kLeftPair) left_pair.emplace(rig);
  rig::Rig& pair = left_pair ? static_cast<rig::Rig&>(*left_pair) : rig;
  r.servo = Servo(pair, r.vergence.state, options.servo, guessed_depths);
  r.servo_wall_s = Since(t_servo);
  r.motion_time_s = r.servo.motion_time_s;
  // A point refused after servoing: nothing was matched, only the vergence computed.
  auto refuse = [&r, verge_s](std::string why) {
    r.why = std::move(why);
    r.compute_time_s = verge_s;
    return r;
  };
  if (!r.servo.mutual)
    return refuse(
        "servoing's match is not mutual: the right camera's centre matches elsewhere in the left "
        "image");
  if (guessed_depths && !r.servo.converged)
    return refuse("servoing found no unique match for a point of guessed depth");
  const rig::StereoFrame& frame = r.servo.frame;
  // Where the two optical axes (the principal points' rays) meet.
  const auto& kl = frame.left.intrinsics;
  const auto& kr = frame.right.intrinsics;
  const auto meet =
      TriangulateMidpoint(PixelRay(frame.left.world_T_camera, kl, {kl.cx_px, kl.cy_px}),
                          PixelRay(frame.right.world_T_camera, kr, {kr.cx_px, kr.cy_px}));
  r.fixation_W = meet ? meet->p_W : p_W;
  const double depth = (frame.left.world_T_camera.inverse() * r.fixation_W).z();
  if (depth < options.min_depth_m)
    return refuse("servoing settled at " + std::to_string(depth) +
                  " m, nearer than idr.z_min_m: a false match");
  r.foveal = FovealStereo(frame, r.fixation_W, map, matcher, options.foveal, fixation);
  r.compute_time_s = verge_s + r.foveal.compute_time_s;
  r.ok = true;
  return r;
}

}  // namespace fovea
