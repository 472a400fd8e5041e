#include "sim/sim_rig.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <utility>
#include <vector>

#include "rig/calibration.h"
#include "sim/simulation.h"
#include "world.h"

namespace sim {
namespace {

constexpr double kDegToRad = M_PI / 180;

uint64_t SplitMix64(uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// Blur, then additive Gaussian noise, in place; `stream` selects an
// independent, reproducible noise sequence.
void ApplySensorModel(const NoiseConfig& noise, uint64_t stream, cv::Mat* image) {
  if (noise.blur_sigma_px > 0)
    cv::GaussianBlur(*image, *image, cv::Size(0, 0), noise.blur_sigma_px);
  if (noise.read_noise_sigma_dn > 0) {
    cv::RNG rng(SplitMix64(stream));
    cv::Mat n(image->size(), CV_32FC(image->channels()));
    rng.fill(n, cv::RNG::NORMAL, 0.0, noise.read_noise_sigma_dn);
    cv::Mat f;
    image->convertTo(f, CV_32F);
    f += n;
    f.convertTo(*image, CV_8U);  // rounds and saturates
  }
}

// Pixels of camera `from` to the pixels of camera `to` (same pose) that
// show the same rays, OpenCV's lens models: undistort with from's, project
// through to's.
std::vector<cv::Point2f> SameRays(const std::vector<cv::Point2f>& pixels,
                                  const rig::CameraIntrinsics& from,
                                  const rig::CameraIntrinsics& to) {
  std::vector<cv::Point2f> normalized, out;
  cv::undistortPoints(pixels, normalized, cv::Mat(from.K()), from.distortion);
  std::vector<cv::Point3f> rays;
  rays.reserve(normalized.size());
  for (const cv::Point2f& n : normalized) rays.emplace_back(n.x, n.y, 1.f);
  cv::projectPoints(rays, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cv::Mat(to.K()), to.distortion,
                    out);
  return out;
}

bool SameCamera(const rig::CameraIntrinsics& a, const rig::CameraIntrinsics& b) {
  auto distortion = [](const rig::CameraIntrinsics& k) {
    std::vector<double> d = k.distortion;
    while (!d.empty() && d.back() == 0) d.pop_back();
    return d;
  };
  return a.fx_px == b.fx_px && a.fy_px == b.fy_px && a.cx_px == b.cx_px && a.cy_px == b.cy_px &&
         distortion(a) == distortion(b);
}

// `pixels` (row by row, rows x cols of them) as CV_32FC1 maps for cv::remap.
void ToMaps(const std::vector<cv::Point2f>& pixels, int rows, int cols, cv::Mat* map_x,
            cv::Mat* map_y) {
  map_x->create(rows, cols, CV_32FC1);
  map_y->create(rows, cols, CV_32FC1);
  for (int v = 0, i = 0; v < rows; ++v)
    for (int u = 0; u < cols; ++u, ++i) {
      map_x->at<float>(v, u) = pixels[i].x;
      map_y->at<float>(v, u) = pixels[i].y;
    }
}

// For every pixel of an image of `chain.front().first`'s size, where it
// lands after each (from, to) step of `chain` (CV_32FC1 maps for
// cv::remap); empty maps when every step maps a camera to itself.
void PixelMaps(const std::vector<std::pair<rig::CameraIntrinsics, rig::CameraIntrinsics>>& chain,
               cv::Mat* map_x, cv::Mat* map_y) {
  *map_x = cv::Mat();
  *map_y = cv::Mat();
  if (std::all_of(chain.begin(), chain.end(),
                  [](const auto& step) { return SameCamera(step.first, step.second); }))
    return;
  const rig::CameraIntrinsics& first = chain.front().first;
  std::vector<cv::Point2f> pixels;
  pixels.reserve(static_cast<size_t>(first.width_px) * first.height_px);
  for (int v = 0; v < first.height_px; ++v)
    for (int u = 0; u < first.width_px; ++u) pixels.emplace_back(float(u), float(v));
  for (const auto& [from, to] : chain)
    if (!SameCamera(from, to)) pixels = SameRays(pixels, from, to);
  ToMaps(pixels, first.height_px, first.width_px, map_x, map_y);
}

// For every delivered pixel of `undistort`'s camera, the pixel of the true
// camera's ideal pinhole that shows the same ray: the raw pixel the remap
// samples, through the true lens (`true_k` -> `ideal`). Empty maps when
// that is the pixel itself.
void DeliveredToTrue(const rig::Undistorter& undistort, const rig::CameraIntrinsics& true_k,
                     const rig::CameraIntrinsics& ideal, cv::Mat* map_x, cv::Mat* map_y) {
  if (!undistort.Active()) {
    PixelMaps({{true_k, ideal}}, map_x, map_y);
    return;
  }
  const cv::Mat &raw_x = undistort.MapX(), &raw_y = undistort.MapY();
  if (SameCamera(true_k, ideal)) {
    *map_x = raw_x.clone();
    *map_y = raw_y.clone();
    return;
  }
  std::vector<cv::Point2f> pixels;
  pixels.reserve(raw_x.total());
  for (int v = 0; v < raw_x.rows; ++v)
    for (int u = 0; u < raw_x.cols; ++u)
      pixels.emplace_back(raw_x.at<float>(v, u), raw_y.at<float>(v, u));
  ToMaps(SameRays(pixels, true_k, ideal), raw_x.rows, raw_x.cols, map_x, map_y);
}

// What the rig believes it is: its calibration file, else its design.
rig::RigCalibration Belief(const SimRigConfig& config) {
  rig::RigCalibration belief;
  if (!config.calibration.empty()) {
    belief = rig::LoadCalibration(config.calibration);
    rig::CheckCalibrationSize(belief, config.calibration, config.width_px, config.height_px);
  } else {
    belief.left = belief.right = rig::Undistorter::Pinhole(TrueIntrinsics(config));
    belief.left_head.optical_centre_H = belief.right_head.optical_centre_H =
        config.optical_centre_offset_m;
  }
  return belief;
}

}  // namespace

SimRig::SimRig(World* world, const SimRigConfig& config)
    : world_(world),
      config_(config),
      belief_(Belief(config)),
      delivered_(belief_),
      stage_rng_(SplitMix64(config.seed ^ 0x5eedULL)) {
  using rig::Axis;
  const double lin_steps = config.baseline_steps_per_mm * 1000.0;
  const double ang_steps = config.pan_tilt_steps_per_deg / kDegToRad;
  const double pan = config.pan_limit_deg * kDegToRad, tilt = config.tilt_limit_deg * kDegToRad;
  limits_[Axis::kLeftBaseline] = {-config.carriage_max_m, -config.carriage_min_m, lin_steps};
  limits_[Axis::kRightBaseline] = {config.carriage_min_m, config.carriage_max_m, lin_steps};
  limits_[Axis::kLeftPan] = limits_[Axis::kRightPan] = {-pan, pan, ang_steps};
  limits_[Axis::kLeftTilt] = limits_[Axis::kRightTilt] = {-tilt, tilt, ang_steps};

  // The truth's lens and sensor, and how delivered pixels relate to it.
  const rig::CameraIntrinsics true_k = TrueIntrinsics(config);
  const rig::CameraIntrinsics ideal = rig::Undistorter::Pinhole(true_k);
  render_size_ = RenderSize(config);
  if (!true_k.distortion.empty()) {
    rig::CameraIntrinsics wide = ideal;
    wide.width_px = render_size_.width;
    wide.height_px = render_size_.height;
    wide.cx_px = 0.5 * (render_size_.width - 1);
    wide.cy_px = 0.5 * (render_size_.height - 1);
    PixelMaps({{true_k, wide}}, &distort_x_, &distort_y_);
  }
  const Imperfections& im = config.imperfections;
  for (rig::Side side : {rig::Side::kLeft, rig::Side::kRight}) {
    const int s = static_cast<int>(side);
    // Delivered pixel -> raw pixel (the believed lens and mount) -> ideal
    // pinhole pixel (the ray the true lens images there).
    DeliveredToTrue(delivered_.undistort[s], true_k, ideal, &delivered_x_[s], &delivered_y_[s]);
    if (im[side].gain != 1 || im.vignetting != 0) {
      gain_[s].create(config.height_px, config.width_px, CV_32FC1);
      const double r2_max = ideal.cx_px * ideal.cx_px + ideal.cy_px * ideal.cy_px;
      for (int v = 0; v < config.height_px; ++v)
        for (int u = 0; u < config.width_px; ++u) {
          const double du = u - ideal.cx_px, dv = v - ideal.cy_px;
          gain_[s].at<float>(v, u) = static_cast<float>(
              im[side].gain * (1 - im.vignetting * (du * du + dv * dv) / r2_max));
        }
    }
  }

  // Joint limits and control ranges in SI units on the compiled model.
  mjModel* m = world_->m;
  for (int i = 0; i < rig::kNumAxes; ++i) {
    const rig::AxisLimit& a = limits_.axes[i];
    const int j = world_->joint_ids[i], u = world_->actuator_ids[i];
    m->jnt_limited[j] = 1;
    m->jnt_range[2 * j] = a.min;
    m->jnt_range[2 * j + 1] = a.max;
    m->actuator_ctrllimited[u] = 1;
    m->actuator_ctrlrange[2 * u] = a.min;
    m->actuator_ctrlrange[2 * u + 1] = a.max;
  }

  home_ = limits_.Quantize(rig::StageState::Parallel(config.home_baseline_m));
  mjData* d = world_->d;
  const auto q = home_.ToArray();
  for (int i = 0; i < rig::kNumAxes; ++i) {
    d->qpos[m->jnt_qposadr[world_->joint_ids[i]]] = q[i];
    d->ctrl[world_->actuator_ids[i]] = q[i];
  }
  mj_forward(m, d);
}

rig::MoveResult SimRig::MoveTo(const rig::StageState& target) {
  const std::string violation = limits_.Violation(target);
  if (!violation.empty()) throw rig::RigError("move refused: " + violation);
  const rig::StageState command = limits_.Quantize(target);
  // Where the stages really stop: within the positioning error of the
  // command, while the encoders read the command.
  auto q_cmd = command.ToArray();
  const double error_steps = config_.imperfections.position_error_steps;
  for (int i = 0; i < rig::kNumAxes; ++i) {
    position_error_[i] = error_steps > 0 ? std::uniform_real_distribution<double>(
                                               -error_steps, error_steps)(stage_rng_) /
                                               limits_.axes[i].steps_per_unit
                                         : 0.0;
    q_cmd[i] += position_error_[i];
  }

  mjModel* m = world_->m;
  mjData* d = world_->d;
  std::array<double, rig::kNumAxes> tolerance{};
  for (int i = 0; i < rig::kNumAxes; ++i) {
    d->ctrl[world_->actuator_ids[i]] = q_cmd[i];
    tolerance[i] = config_.settle_tolerance_steps / limits_.axes[i].steps_per_unit;
  }
  auto settled = [&] {
    for (int i = 0; i < rig::kNumAxes; ++i) {
      const int j = world_->joint_ids[i];
      if (std::abs(d->qpos[m->jnt_qposadr[j]] - q_cmd[i]) > tolerance[i]) return false;
      // No faster than one tolerance per 50 ms.
      if (std::abs(d->qvel[m->jnt_dofadr[j]]) > tolerance[i] / 0.05) return false;
    }
    return true;
  };
  const double t0 = d->time;
  while (!settled()) {
    if (d->time - t0 > config_.move_timeout_s) {
      throw rig::RigError("stages did not settle within " + std::to_string(config_.move_timeout_s) +
                          " s (simulated) moving to " + command.ToString());
    }
    mj_step(m, d);
  }
  mj_forward(m, d);  // poses and cameras for the settled state
  return {d->time - t0, State()};
}

rig::StageState SimRig::State() const {
  std::array<double, rig::kNumAxes> q{};
  for (int i = 0; i < rig::kNumAxes; ++i)
    q[i] = world_->d->qpos[world_->m->jnt_qposadr[world_->joint_ids[i]]] - position_error_[i];
  return rig::StageState::FromArray(q);
}

rig::CameraIntrinsics SimRig::Intrinsics(rig::Side) const {
  return delivered_.intrinsics;  // what Capture delivers
}

SimRig::TrueCamera SimRig::True(rig::Side side) const {
  const int s = static_cast<int>(side);
  TrueCamera t;
  t.world_T_camera = CameraPoseFromMujoco(world_->d, world_->camera_ids[s]);
  t.ideal = rig::Undistorter::Pinhole(TrueIntrinsics(config_));
  t.map_x = delivered_x_[s];
  t.map_y = delivered_y_[s];
  t.delivered_R_camera = delivered_.delivered_R_raw[s];
  return t;
}

void SimRig::ApplyOptics(int side, cv::Mat* image) const {
  if (!distort_x_.empty()) {
    cv::Mat distorted;
    // Bicubic: a lens does not blur as a bilinear resampling of the render
    // would, on top of the undistortion's own resampling.
    cv::remap(*image, distorted, distort_x_, distort_y_, cv::INTER_CUBIC, cv::BORDER_REPLICATE);
    *image = distorted;
  }
  const double offset = config_.imperfections[static_cast<rig::Side>(side)].offset_dn;
  if (!gain_[side].empty() || offset != 0) {
    cv::Mat f;
    image->convertTo(f, CV_32F);
    if (!gain_[side].empty()) {
      std::vector<cv::Mat> channels;
      cv::split(f, channels);
      for (cv::Mat& c : channels) cv::multiply(c, gain_[side], c);
      cv::merge(channels, f);
    }
    f.convertTo(*image, CV_8U, 1.0, offset);  // rounds and saturates
  }
}

double SimRig::TimeS() const { return world_->d->time; }

rig::StereoFrame SimRig::Capture(const rig::CaptureOptions& options) {
  rig::StereoFrame frame;
  frame.state = State();
  frame.timestamp_s = world_->d->time;
  const uint64_t base = SplitMix64(config_.seed) ^ (capture_count_++ * 8);
  for (rig::Side side : {rig::Side::kLeft, rig::Side::kRight}) {
    const int s = static_cast<int>(side);
    rig::CameraView& view = side == rig::Side::kLeft ? frame.left : frame.right;
    cv::Mat rgb;
    world_->renderer->Render(world_->m, world_->d, world_->camera_ids[s], render_size_.width,
                             render_size_.height, &rgb, nullptr);
    cv::cvtColor(rgb, view.gray, cv::COLOR_RGB2GRAY);
    ApplyOptics(s, &view.gray);
    ApplySensorModel(config_.noise, base + 2 * s, &view.gray);
    if (options.color) {
      cv::cvtColor(rgb, view.bgr, cv::COLOR_RGB2BGR);
      ApplyOptics(s, &view.bgr);
      ApplySensorModel(config_.noise, base + 2 * s + 1, &view.bgr);
    }
    const cv::Mat raw = view.gray;  // what a recording keeps: a hardware rig undistorts it
    if (!options.raw) {
      view.gray = delivered_.undistort[s].Apply(view.gray);
      if (options.color) view.bgr = delivered_.undistort[s].Apply(view.bgr);
    }
    view.intrinsics = options.raw ? belief_.Intrinsics(side) : Intrinsics(side);
    // Where the rig believes its camera is: its kinematics at the readings.
    view.world_T_camera = (options.raw ? delivered_.raw_geometry : delivered_.geometry)
                              .WorldFromCamera(side, frame.state[side]);
    if (!config_.record_dir.empty()) {
      // Numbered from 0 in capture order: OpenCV's image-sequence reader
      // (and a HardwareRig camera) replays them.
      char name[64];
      std::snprintf(name, sizeof name, "/%s_%05llu.png", s == 0 ? "left" : "right",
                    static_cast<unsigned long long>(capture_count_ - 1));
      if (!cv::imwrite(config_.record_dir + name, raw))
        throw rig::RigError("cannot record a capture to '" + config_.record_dir + name + "'");
    }
  }
  return frame;
}

}  // namespace sim
