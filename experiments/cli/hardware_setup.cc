#include "hardware_setup.h"

#include <chrono>

#include "experiments/usage_error.h"

namespace experiments {

std::unique_ptr<rig::HardwareRig> MakeHardwareRig(const RunConfig& c,
                                                  std::unique_ptr<rig::IndexerEmulator>* emulator) {
  const RunConfig::Hardware& h = c.hardware;
  rig::HardwareRigConfig hw;
  hw.calibration = rig::LoadCalibration(c.rig.calibration);
  rig::CheckCalibrationSize(hw.calibration, c.rig.calibration, c.rig.width_px, c.rig.height_px);
  const double lin = c.rig.baseline_steps_per_mm * 1000,
               ang = c.rig.pan_tilt_steps_per_deg * 180 / M_PI;
  const double pan = c.rig.pan_limit_deg * M_PI / 180, tilt = c.rig.tilt_limit_deg * M_PI / 180;
  const auto units = SixInts(h.units, "rig.units"),
             directions = SixInts(h.directions, "rig.directions");
  for (int i = 0; i < rig::kNumAxes; ++i) {
    rig::IndexerAxis& a = hw.stages.axes[i];
    const auto axis = static_cast<rig::Axis>(i);
    a.unit = units[i];
    a.sign = directions[i];
    const bool baseline = axis == rig::Axis::kLeftBaseline || axis == rig::Axis::kRightBaseline;
    a.steps_per_unit = baseline ? lin : ang;
    a.velocity = baseline ? h.baseline_velocity_m_s : h.pan_tilt_velocity_rad_s;
    a.acceleration = 10 * a.velocity;
    if (axis == rig::Axis::kLeftBaseline)
      a.min = -c.rig.carriage_max_m, a.max = -c.rig.carriage_min_m;
    else if (axis == rig::Axis::kRightBaseline)
      a.min = c.rig.carriage_min_m, a.max = c.rig.carriage_max_m;
    else if (axis == rig::Axis::kLeftPan || axis == rig::Axis::kRightPan)
      a.min = -pan, a.max = pan;
    else
      a.min = -tilt, a.max = tilt;
  }
  std::string port = h.port;
  if (h.emulate_stages) {
    *emulator =
        std::make_unique<rig::IndexerEmulator>(std::vector<int>(units.begin(), units.end()));
    port = (*emulator)->Path();
  }
  hw.line = rig::OpenSerialPort(port, h.baud);
  hw.left_camera = h.left_camera;
  hw.right_camera = h.right_camera;
  hw.home_baseline_m = c.rig.home_baseline_m;
  hw.frame_timeout = std::chrono::milliseconds(static_cast<long>(1000 * h.frame_timeout_s));
  return std::make_unique<rig::HardwareRig>(std::move(hw));
}

}  // namespace experiments
