#include "sim/sim_rig.h"

#include <cmath>
#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

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

}  // namespace

SimRig::SimRig(World* world, const SimRigConfig& config) : world_(world), config_(config) {
  using rig::Axis;
  const double lin_steps = config.baseline_steps_per_mm * 1000.0;
  const double ang_steps = config.pan_tilt_steps_per_deg / kDegToRad;
  const double pan = config.pan_limit_deg * kDegToRad, tilt = config.tilt_limit_deg * kDegToRad;
  limits_[Axis::kLeftBaseline] = {-config.carriage_max_m, -config.carriage_min_m, lin_steps};
  limits_[Axis::kRightBaseline] = {config.carriage_min_m, config.carriage_max_m, lin_steps};
  limits_[Axis::kLeftPan] = limits_[Axis::kRightPan] = {-pan, pan, ang_steps};
  limits_[Axis::kLeftTilt] = limits_[Axis::kRightTilt] = {-tilt, tilt, ang_steps};
  for (rig::Side side : {rig::Side::kLeft, rig::Side::kRight}) {
    rig::HeadGeometry& head = side == rig::Side::kLeft ? geometry_.left : geometry_.right;
    head.rail_zero_W = Eigen::Vector3d::Zero();
    head.optical_centre_H = config.optical_centre_offset_m;
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
  const auto q_cmd = command.ToArray();

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
    q[i] = world_->d->qpos[world_->m->jnt_qposadr[world_->joint_ids[i]]];
  return rig::StageState::FromArray(q);
}

rig::CameraIntrinsics SimRig::Intrinsics(rig::Side) const {
  return rig::CameraIntrinsics::FromHorizontalFov(config_.width_px, config_.height_px,
                                                  config_.horizontal_fov_deg * kDegToRad);
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
    world_->renderer->Render(world_->m, world_->d, world_->camera_ids[s], config_.width_px,
                             config_.height_px, &rgb, nullptr);
    cv::cvtColor(rgb, view.gray, cv::COLOR_RGB2GRAY);
    ApplySensorModel(config_.noise, base + 2 * s, &view.gray);
    if (options.color) {
      cv::cvtColor(rgb, view.bgr, cv::COLOR_RGB2BGR);
      ApplySensorModel(config_.noise, base + 2 * s + 1, &view.bgr);
    }
    view.intrinsics = Intrinsics(side);
    view.world_T_camera = CameraPoseFromMujoco(world_->d, world_->camera_ids[s]);
    if (!config_.record_dir.empty()) {
      // Numbered from 0 in capture order: OpenCV's image-sequence reader
      // (and a HardwareRig camera) replays them.
      char name[64];
      std::snprintf(name, sizeof name, "/%s_%05llu.png", s == 0 ? "left" : "right",
                    static_cast<unsigned long long>(capture_count_ - 1));
      if (!cv::imwrite(config_.record_dir + name, view.gray))
        throw rig::RigError("cannot record a capture to '" + config_.record_dir + name + "'");
    }
  }
  return frame;
}

}  // namespace sim
