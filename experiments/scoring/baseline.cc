#include "experiments/scoring/baseline.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "fovea/geometry.h"
#include "fovea/sgbm.h"

namespace experiments {

double StaticBaseline(const rig::Rig& rig, double min_depth_m) {
  const rig::CameraIntrinsics k = rig.Intrinsics(rig::Side::kLeft);
  const double useful = 0.5 * k.width_px * min_depth_m / k.fx_px;
  const rig::RigLimits& limits = rig.Limits();
  const double widest =
      limits[rig::Axis::kRightBaseline].max - limits[rig::Axis::kLeftBaseline].min;
  return std::min(useful, widest);
}

fovea::PatchMap DepthToPatches(const rig::CameraView& view, const cv::Mat& depth_m, double fb_px,
                               int block_px) {
  fovea::PatchMap map;
  fovea::PlaneFitOptions fit_options{/*min_support=*/(3 * block_px * block_px) / 4,
                                     /*fit_tolerance_px=*/1.0,
                                     /*min_inlier_share=*/0.8, /*require_quadrants=*/true};
  const rig::CameraIntrinsics& k = view.intrinsics;
  for (int by = 0; by + block_px <= depth_m.rows; by += block_px)
    for (int bx = 0; bx + block_px <= depth_m.cols; bx += block_px) {
      std::vector<fovea::DisparitySample> samples;
      for (int y = by; y < by + block_px; ++y)
        for (int x = bx; x < bx + block_px; ++x) {
          const float z = depth_m.at<float>(y, x);
          if (z > 0) samples.push_back({double(x), double(y), fb_px / z});
        }
      Eigen::Vector4d box;
      const auto fit =
          fovea::FitDisparityPlane(samples, bx, by, block_px, block_px, fit_options, &box);
      if (!fit) continue;
      const double x0 = std::max(bx - 0.5, box(0) - 0.5), y0 = std::max(by - 0.5, box(1) - 0.5);
      const double x1 = std::min(bx + block_px - 0.5, box(2) + 0.5),
                   y1 = std::min(by + block_px - 0.5, box(3) + 0.5);
      fovea::Patch p;
      p.level = fovea::PatchLevel::kFoveal;
      p.resolution_level = 0;
      p.fit_rms_px = fit->rms_px;
      p.support = fit->support;
      const double xs[4] = {x0, x1, x1, x0}, ys[4] = {y0, y0, y1, y1};
      bool ok = true;
      for (int c = 0; c < 4 && ok; ++c) {
        const double d = (*fit)(xs[c], ys[c]);
        ok = d > 0;
        if (ok) p.corners_W[c] = view.world_T_camera * ((fb_px / d) * k.Ray({xs[c], ys[c]}));
      }
      if (!ok) continue;
      const Eigen::Vector3d right_W = view.world_T_camera.translation() +
                                      (fb_px / k.fx_px) * view.world_T_camera.linear().col(0);
      fovea::SetDepthSigma(&p, view, right_W, std::max(fovea::kMatchSigmaPx, fit->rms_px));
      map.Add(p);
    }
  return map;
}

StaticSgbmResult RunStaticSgbm(rig::Rig& rig, const StaticSgbmOptions& options) {
  StaticSgbmResult r;
  r.baseline_m =
      options.baseline_m > 0 ? options.baseline_m : StaticBaseline(rig, options.min_depth_m);
  rig::StageState state = rig.Home();
  const double centre = 0.5 * (state.left.carriage_m + state.right.carriage_m);
  state.left.carriage_m = centre - 0.5 * r.baseline_m;
  state.right.carriage_m = centre + 0.5 * r.baseline_m;
  state.left.pan_rad = state.right.pan_rad = 0;
  state.left.tilt_rad = state.right.tilt_rad = 0;
  const rig::MoveResult move = rig.MoveTo(state);
  r.motion_time_s = move.motion_time_s;
  const rig::StereoFrame frame = rig.Capture();
  const auto t0 = std::chrono::steady_clock::now();
  const cv::Mat depth =
      fovea::RectifiedSgbmDepth(frame.left, frame.right, options.min_depth_m, 100.0);
  r.depth_pixels = cv::countNonZero(depth);
  const double b =
      (frame.right.world_T_camera.translation() - frame.left.world_T_camera.translation()).norm();
  r.map = DepthToPatches(frame.left, depth, frame.left.intrinsics.fx_px * b, options.block_px);
  r.compute_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

}  // namespace experiments
