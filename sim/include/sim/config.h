// Configuration of the simulated Texas Active Vision Testbed (TAVT).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "rig/input_file.h"

namespace sim {

/// Thrown for a scene that cannot be loaded or breaks the scene rules, and for
/// an invalid simulator configuration: input the user gave (the command line
/// exits with 2). The message names the file or key.
class SceneError : public rig::InputError {
 public:
  using rig::InputError::InputError;
};

/// Sensor model applied to every captured image, in this order: Gaussian blur
/// (optics), then additive Gaussian read noise, rounded and saturated to 8 bits.
/// Off by default (tests); experiment configs turn it on.
struct NoiseConfig {
  double read_noise_sigma_dn = 0;  ///< standard deviation in 8-bit grey levels
  double blur_sigma_px = 0;        ///< 0 disables the blur
  void Check() const;              ///< throws SceneError on negative values
};

/// Everything that defines the simulated rig. Defaults follow the paper's
/// TAVT with its 16 mm lens (about 30 degrees across).
struct SimRigConfig {
  int width_px = 640;
  int height_px = 480;
  double horizontal_fov_deg = 30;  ///< edge to edge; the 35 mm lens is 15

  /// Optical centre relative to the pan/tilt axes intersection, in the head
  /// frame (x right, y forward, z up at pan = tilt = 0), metres.
  Eigen::Vector3d optical_centre_offset_m{0.0, 0.03, 0.01};

  /// Carriage travel: the left carriage moves in [-max, -min], the right one
  /// in [min, max], measured from the rail centre (the world origin).
  double carriage_min_m = 0.0005;
  double carriage_max_m = 0.30;
  double pan_limit_deg = 60;   ///< symmetric
  double tilt_limit_deg = 30;  ///< symmetric
  double home_baseline_m = 0.10;

  double baseline_steps_per_mm = 400;    ///< 2.5 micrometre steps
  double pan_tilt_steps_per_deg = 6400;  ///< the TAVT's Compumotor stages

  /// A move has settled when every axis is within this many steps of its
  /// command and moving slower than that per 50 ms.
  double settle_tolerance_steps = 1.0;
  double move_timeout_s = 30;  ///< simulated seconds

  NoiseConfig noise;
  uint64_t seed = 0;  ///< seeds the sensor noise

  /// When set, every capture's grey images are also written to this folder
  /// as left_NNNNN.png / right_NNNNN.png in capture order (for replaying a
  /// session through a HardwareRig's cameras).
  std::string record_dir;

  /// Throws SceneError naming the first invalid field.
  void Check() const;
};

}  // namespace sim
