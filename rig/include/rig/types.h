// Value types shared by every rig implementation and by the algorithms.
//
// Frames and units, used everywhere in rig/, fovea/ and experiments/:
//  - World frame W: MuJoCo's, Z up, X along the rail, Y forward (towards the
//    scene); the origin lies midway between the two baseline stages' zero
//    points (which coincide: both carriages measure from the rail's centre).
//  - Camera frame C: OpenCV's, x right, y down, z forward along the optical
//    axis, origin at the optical centre.
//  - Pixels: OpenCV's, (0, 0) is the centre of the top-left pixel, u right,
//    v down.
//  - Lengths in metres, angles in radians, unless a name says otherwise.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <opencv2/core.hpp>
#include <stdexcept>
#include <string>
#include <vector>

namespace rig {

/// Thrown by rigs and rig value types for input they refuse (a target outside
/// the axis limits, inconsistent intrinsics) and for device failures. The
/// message names the input and the problem.
class RigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class Side { kLeft = 0, kRight = 1 };
const char* SideName(Side side);

/// Pinhole camera model. fx, fy, cx, cy in pixels (OpenCV convention); the
/// optional distortion uses OpenCV's order (k1, k2, p1, p2[, k3]).
struct CameraIntrinsics {
  double fx_px = 0, fy_px = 0, cx_px = 0, cy_px = 0;
  int width_px = 0, height_px = 0;
  std::vector<double> distortion;

  /// Ideal camera with square pixels and the principal point at the image
  /// centre, ((W - 1) / 2, (H - 1) / 2), whose image spans `horizontal_fov_rad`
  /// edge to edge. This is exactly what an OpenGL frustum of that field renders.
  static CameraIntrinsics FromHorizontalFov(int width_px, int height_px, double horizontal_fov_rad);

  /// Throws RigError unless sizes and focal lengths are positive and the
  /// distortion has 0, 4, 5 or 8 coefficients.
  void Check() const;

  /// Vertical field of view, edge to edge, of an undistorted camera.
  double VerticalFovRad() const;

  /// Pixel where the camera-frame point p_C (z > 0) projects, distortion
  /// applied. Undefined for z <= 0. (Inline without distortion: the
  /// per-pixel loops call it.)
  Eigen::Vector2d Project(const Eigen::Vector3d& p_C) const {
    if (!distortion.empty()) return ProjectDistorted(p_C);
    return {fx_px * (p_C.x() / p_C.z()) + cx_px, fy_px * (p_C.y() / p_C.z()) + cy_px};
  }

  /// Direction in the camera frame, scaled so that z = 1, of the ray through
  /// pixel uv (distortion removed by fixed-point iteration).
  Eigen::Vector3d Ray(const Eigen::Vector2d& uv) const {
    if (!distortion.empty()) return RayDistorted(uv);
    return {(uv.x() - cx_px) / fx_px, (uv.y() - cy_px) / fy_px, 1.0};
  }

  /// Project and Ray with the distortion (Project and Ray call them).
  Eigen::Vector2d ProjectDistorted(const Eigen::Vector3d& p_C) const;
  Eigen::Vector3d RayDistorted(const Eigen::Vector2d& uv) const;

  bool InImage(const Eigen::Vector2d& uv) const;
  cv::Matx33d K() const;
};

/// The three stage positions of one camera platform: the carriage along the
/// rail (world X of the pan/tilt axis intersection, metres), pan about the
/// world Z axis (positive turns the camera to its left, counter-clockwise seen
/// from above) and tilt about the panned X axis (positive looks up).
struct CameraStage {
  /// The carriage's position along the rail from its centre (the world
  /// origin), metres: negative for the left carriage, positive for the right.
  /// (The baseline is the difference of the two carriages' positions.)
  double carriage_m = 0;
  double pan_rad = 0;
  double tilt_rad = 0;
};

/// One of the six axes, in the order StageState::ToArray uses.
enum class Axis { kLeftBaseline, kLeftPan, kLeftTilt, kRightBaseline, kRightPan, kRightTilt };
constexpr int kNumAxes = 6;
const char* AxisName(Axis axis);

/// Positions of all six axes.
struct StageState {
  CameraStage left, right;

  /// Cameras parallel and level, carriages symmetric about the rail centre,
  /// `baseline_m` apart.
  static StageState Parallel(double baseline_m);
  static StageState FromArray(const std::array<double, kNumAxes>& values);
  std::array<double, kNumAxes> ToArray() const;

  const CameraStage& operator[](Side side) const { return side == Side::kLeft ? left : right; }
  CameraStage& operator[](Side side) { return side == Side::kLeft ? left : right; }
  /// Distance between the two carriages along the rail.
  double BaselineM() const { return right.carriage_m - left.carriage_m; }
  std::string ToString() const;
};

/// Travel and resolution of one axis. Units: metres for baselines, radians for
/// pan and tilt; steps_per_unit is motor steps per metre or per radian.
struct AxisLimit {
  double min = 0, max = 0;
  double steps_per_unit = 1;
};

/// Limits and resolutions of all six axes.
struct RigLimits {
  std::array<AxisLimit, kNumAxes> axes;

  const AxisLimit& operator[](Axis axis) const { return axes[static_cast<int>(axis)]; }
  AxisLimit& operator[](Axis axis) { return axes[static_cast<int>(axis)]; }

  /// Empty if every axis of `state` is inside its travel; otherwise a message
  /// naming the first axis outside, its value and its range.
  std::string Violation(const StageState& state) const;
  /// Every axis rounded to its nearest whole motor step.
  StageState Quantize(const StageState& state) const;
  /// Whole motor steps of every axis (rounded).
  std::array<long long, kNumAxes> ToSteps(const StageState& state) const;
};

/// What a move did: how long the motion took (simulated seconds in the
/// simulator, wall seconds on hardware) and the state the stages settled at.
struct MoveResult {
  double motion_time_s = 0;
  StageState reached;
};

/// One camera's image with the model and pose it was taken with.
struct CameraView {
  cv::Mat gray;  ///< CV_8UC1, always present
  cv::Mat bgr;   ///< CV_8UC3 (OpenCV's BGR order); empty unless colour was asked for
  CameraIntrinsics intrinsics;
  Eigen::Isometry3d world_T_camera = Eigen::Isometry3d::Identity();
};

/// A synchronized pair of images and the stage state they were taken at.
struct StereoFrame {
  CameraView left, right;
  StageState state;
  double timestamp_s = 0;  ///< rig clock: simulated time, or wall time on hardware

  const CameraView& operator[](Side side) const { return side == Side::kLeft ? left : right; }
};

struct CaptureOptions {
  bool color = false;  ///< also return BGR images
  /// The images as the sensors give them, lens distortion kept (for
  /// calibration); the views' intrinsics then carry the distortion the rig
  /// believes. By default frames are undistorted to the pinhole camera of
  /// the same K.
  bool raw = false;
};

}  // namespace rig
