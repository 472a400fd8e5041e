// Configuration of the simulated Texas Active Vision Testbed (TAVT).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "rig/input_file.h"
#include "rig/kinematics.h"
#include "rig/param.h"
#include "rig/types.h"

namespace sim {

/// Thrown for a scene that cannot be loaded or breaks the scene rules, and for
/// an invalid simulator configuration: input the user gave (the command line
/// exits with 2). The message names the file or key.
class SceneError : public rig::InputError {
 public:
  using rig::InputError::InputError;
};

/// Every parameter of the simulated rig: its YAML key, meaning and range
/// (see rig/param.h). SimRigConfig::Check() checks against these and the run
/// configuration binds each to its field.
namespace params {
using rig::ParamSpec;
inline constexpr ParamSpec kWidthPx{"rig.width_px", "image width, pixels", 64, 4096};
inline constexpr ParamSpec kHeightPx{"rig.height_px", "image height, pixels", 48, 4096};
inline constexpr ParamSpec kHorizontalFovDeg{
    "rig.horizontal_fov_deg",
    "lens: horizontal field of view edge to edge, degrees (16 mm lens: 30)", 5, 100};
inline constexpr ParamSpec kOpticalCentreXM{"rig.optical_centre_x_m",
                                            "each optical centre's offset from its pan/tilt axes' "
                                            "intersection, head frame x (right), metres",
                                            -0.15, 0.15};
inline constexpr ParamSpec kOpticalCentreYM{
    "rig.optical_centre_y_m", "the same, head frame y (forward), metres", -0.15, 0.15};
inline constexpr ParamSpec kOpticalCentreZM{"rig.optical_centre_z_m",
                                            "the same, head frame z (up), metres", -0.15, 0.15};
inline constexpr ParamSpec kCarriageMinM{
    "rig.carriage_min_m",
    "baseline axes: each carriage's nearest approach to the rail centre, metres", 0, 0.05};
inline constexpr ParamSpec kCarriageMaxM{
    "rig.carriage_max_m", "baseline axes: each carriage's travel from the rail centre, metres",
    0.01, 2};
inline constexpr ParamSpec kHomeBaselineM{"rig.home_baseline_m",
                                          "baseline at the home pose (the reference view's pose), "
                                          "metres (within 2 x the carriages' travel)",
                                          0.002, 4};
inline constexpr ParamSpec kPanLimitDeg{"rig.pan_limit_deg",
                                        "pan axes: symmetric travel limit, degrees", 1, 179};
inline constexpr ParamSpec kTiltLimitDeg{"rig.tilt_limit_deg",
                                         "tilt axes: symmetric travel limit, degrees", 1, 89};
inline constexpr ParamSpec kBaselineStepsPerMm{"rig.baseline_steps_per_mm",
                                               "baseline axes: motor steps per millimetre", 1, 1e6};
inline constexpr ParamSpec kPanTiltStepsPerDeg{"rig.pan_tilt_steps_per_deg",
                                               "pan and tilt axes: motor steps per degree", 1, 1e6};
inline constexpr ParamSpec kSettleToleranceSteps{
    "rig.settle_tolerance_steps",
    "a move has settled when every axis is within this many steps of its command and slower than "
    "that per 50 ms",
    0.5, 100};
inline constexpr ParamSpec kMoveTimeoutS{
    "rig.move_timeout_s", "a move must settle within this, simulated seconds", 0.1, 600};
inline constexpr ParamSpec kNoiseSigmaDn{"rig.noise_sigma_dn",
                                         "sensor read noise, grey levels (0 = off)", 0, 50};
inline constexpr ParamSpec kBlurSigmaPx{"rig.blur_sigma_px",
                                        "optical blur before the noise, pixels (0 = off)", 0, 10};
// The imperfections of a real rig (issue 22); all off by default.
inline constexpr ParamSpec kLeftMountRollDeg{
    "rig.left_mount_roll_deg",
    "left camera's mounting rotation against its head about its optical axis, degrees", -10, 10};
inline constexpr ParamSpec kLeftMountPitchDeg{"rig.left_mount_pitch_deg",
                                              "the same about the head's x axis, degrees", -10, 10};
inline constexpr ParamSpec kLeftMountYawDeg{"rig.left_mount_yaw_deg",
                                            "the same about the head's z axis, degrees", -10, 10};
inline constexpr ParamSpec kRightMountRollDeg{
    "rig.right_mount_roll_deg", "right camera's mounting rotation, roll, degrees", -10, 10};
inline constexpr ParamSpec kRightMountPitchDeg{
    "rig.right_mount_pitch_deg", "right camera's mounting rotation, pitch, degrees", -10, 10};
inline constexpr ParamSpec kRightMountYawDeg{
    "rig.right_mount_yaw_deg", "right camera's mounting rotation, yaw, degrees", -10, 10};
inline constexpr ParamSpec kLeftPanZeroDeg{
    "rig.left_pan_zero_deg",
    "left pan encoder's home error: the true angle is the reading plus this, degrees", -5, 5};
inline constexpr ParamSpec kLeftTiltZeroDeg{"rig.left_tilt_zero_deg",
                                            "left tilt encoder's home error, degrees", -5, 5};
inline constexpr ParamSpec kRightPanZeroDeg{"rig.right_pan_zero_deg",
                                            "right pan encoder's home error, degrees", -5, 5};
inline constexpr ParamSpec kRightTiltZeroDeg{"rig.right_tilt_zero_deg",
                                             "right tilt encoder's home error, degrees", -5, 5};
inline constexpr ParamSpec kDistortionK1{
    "rig.distortion_k1", "both lenses: radial distortion k1 (OpenCV's model; barrel < 0)", -0.5,
    0.5};
inline constexpr ParamSpec kDistortionK2{"rig.distortion_k2", "both lenses: radial k2", -0.5, 0.5};
inline constexpr ParamSpec kDistortionP1{"rig.distortion_p1", "both lenses: tangential p1", -0.01,
                                         0.01};
inline constexpr ParamSpec kDistortionP2{"rig.distortion_p2", "both lenses: tangential p2", -0.01,
                                         0.01};
inline constexpr ParamSpec kLeftGain{"rig.left_gain", "left sensor's gain (1 = ideal)", 0.5, 2};
inline constexpr ParamSpec kRightGain{"rig.right_gain", "right sensor's gain", 0.5, 2};
inline constexpr ParamSpec kLeftOffsetDn{"rig.left_offset_dn",
                                         "left sensor's black-level offset, grey levels", -50, 50};
inline constexpr ParamSpec kRightOffsetDn{
    "rig.right_offset_dn", "right sensor's black-level offset, grey levels", -50, 50};
inline constexpr ParamSpec kVignetting{
    "rig.vignetting",
    "both lenses: share of brightness lost at the image corners, falling off as radius squared", 0,
    0.8};
inline constexpr ParamSpec kPositionErrorSteps{
    "rig.position_error_steps",
    "each axis stops uniformly within +- this many motor steps of its command while its encoder "
    "reads the command (backlash, missed steps; 0 = exact)",
    0, 10000};
inline constexpr ParamSpec kRecordDir{
    "rig.record_dir",
    "sim: also write every capture to this folder (left_NNNNN.png, right_NNNNN.png) for replay"};
}  // namespace params

/// Sensor model applied to every captured image, in this order: Gaussian blur
/// (optics), then additive Gaussian read noise, rounded and saturated to 8 bits.
/// Off by default (tests); experiment configs turn it on.
struct NoiseConfig {
  double read_noise_sigma_dn = 0;  ///< standard deviation in 8-bit grey levels
  double blur_sigma_px = 0;        ///< 0 disables the blur
  void Check() const;              ///< throws rig::InputError naming the key (params)
};

/// One camera's departures from the ideal head (see rig::HeadGeometry).
struct CameraImperfections {
  Eigen::Vector3d mount_rpy_deg = Eigen::Vector3d::Zero();  ///< roll, pitch, yaw
  double pan_zero_deg = 0, tilt_zero_deg = 0;
  double gain = 1, offset_dn = 0;
};

/// What makes the simulated rig a real one. Off by default: the rig is then
/// ideal and believes itself exactly.
struct Imperfections {
  CameraImperfections left, right;
  double k1 = 0, k2 = 0, p1 = 0, p2 = 0;  ///< both lenses, OpenCV's model
  double vignetting = 0;
  double position_error_steps = 0;

  const CameraImperfections& operator[](rig::Side side) const {
    return side == rig::Side::kLeft ? left : right;
  }
  bool Distorted() const { return k1 != 0 || k2 != 0 || p1 != 0 || p2 != 0; }
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
  uint64_t seed = 0;  ///< seeds the sensor noise and the stages' positioning error

  /// What the rig is, beyond its design (the rig renders this).
  Imperfections imperfections;
  /// What the rig believes it is: a calibration file (rig.calibration). Empty:
  /// its design (the intrinsics of horizontal_fov_deg, the optical-centre
  /// offset above, no distortion, no mount rotation, zero encoder errors).
  std::string calibration;

  /// When set, every capture's grey images are also written to this folder
  /// as left_NNNNN.png / right_NNNNN.png in capture order (for replaying a
  /// session through a HardwareRig's cameras).
  std::string record_dir;

  /// Throws rig::InputError naming the key of the first invalid field.
  void Check() const;
};

}  // namespace sim
