// The simulated TAVT behind the rig interface.
#pragma once

#include <array>
#include <cstdint>
#include <random>

#include "rig/rig.h"
#include "rig/undistort.h"
#include "sim/config.h"

namespace sim {

struct World;

/// Six position-servoed joints (slide, pan hinge, tilt hinge per camera) with
/// rotor inertia, damping and force limits, so a move takes physical time.
/// Commands are quantized to motor steps; MoveTo steps the physics until the
/// stages settle. Capture renders both cameras offscreen (OSMesa) and applies
/// the lens and sensor models: distortion, vignetting, gain and offset, blur,
/// seeded read noise.
///
/// What the rig is (SimRigConfig::imperfections) and what it believes it is
/// (SimRigConfig::calibration, else its design) are kept apart, as on a real
/// rig: State, Geometry, Intrinsics and the poses Capture reports are its
/// belief; the renderer images the truth (TrueCamera).
class SimRig : public rig::Rig {
 public:
  SimRig(World* world, const SimRigConfig& config);

  rig::MoveResult MoveTo(const rig::StageState& target) override;
  rig::StageState State() const override;
  rig::StereoFrame Capture(const rig::CaptureOptions& options = {}) override;
  const rig::RigLimits& Limits() const override { return limits_; }
  const rig::RigGeometry& Geometry() const override { return delivered_.geometry; }
  rig::CameraIntrinsics Intrinsics(rig::Side side) const override;
  rig::StageState Home() const override { return home_; }

  /// Simulated time since load, seconds.
  double TimeS() const;

  /// What a delivered image of one camera (rig::DeliveredPair) really
  /// shows: the camera's true pose now, its ideal pinhole intrinsics (the
  /// configuration's), and for every delivered pixel the pixel of that ideal
  /// camera that shows the same ray (CV_32FC1 maps; empty when the two are
  /// the same pixel, as on a rig without distortion that believes its true K
  /// and no mount). The delivered image is that of a camera at the same
  /// optical centre turned by `delivered_R_camera` (the believed mount,
  /// taken off on capture): a point p in the true camera's frame is
  /// delivered_R_camera * p in the delivered camera's.
  struct TrueCamera {
    Eigen::Isometry3d world_T_camera = Eigen::Isometry3d::Identity();
    rig::CameraIntrinsics ideal;
    cv::Mat map_x, map_y;
    Eigen::Matrix3d delivered_R_camera = Eigen::Matrix3d::Identity();

    /// The ideal camera's pixel that shows delivered pixel (x, y).
    Eigen::Vector2d IdealPixel(int x, int y) const {
      return map_x.empty() ? Eigen::Vector2d(x, y)
                           : Eigen::Vector2d(map_x.at<float>(y, x), map_y.at<float>(y, x));
    }
  };
  TrueCamera True(rig::Side side) const;

 private:
  World* world_;
  SimRigConfig config_;
  rig::RigLimits limits_;
  rig::RigCalibration belief_;     ///< what it believes it is: raw cameras and heads
  rig::DeliveredPair delivered_;   ///< what Capture delivers, from the belief
  cv::Size render_size_;           ///< RenderSize(config)
  cv::Mat distort_x_, distort_y_;  ///< render -> distorted image; empty for ideal lenses
  std::array<cv::Mat, 2> gain_;    ///< per pixel: gain x vignetting; empty when ideal
  std::array<cv::Mat, 2> delivered_x_, delivered_y_;  ///< see TrueCamera
  rig::StageState home_;
  std::array<double, rig::kNumAxes> position_error_{};  ///< true - encoder reading, per axis
  std::mt19937_64 stage_rng_;
  uint64_t capture_count_ = 0;

  /// The rendered image of one camera through the lens and sensor models.
  void ApplyOptics(int side, cv::Mat* image) const;
};

}  // namespace sim
