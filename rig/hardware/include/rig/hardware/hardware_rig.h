// The real rig behind rig::Rig: the serial stage driver, two cameras and a
// calibration file. `fovea run` drives it exactly as it drives the simulator.
#pragma once

#include <chrono>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>
#include <string>

#include "rig/calibration.h"
#include "rig/hardware/indexer.h"
#include "rig/rig.h"
#include "rig/undistort.h"

namespace rig {

/// A camera on OpenCV's VideoCapture: a V4L2 device index ("0") or path
/// ("/dev/video0"), a video file, or an image sequence ("rec/left_%05d.png",
/// for tests and for replaying recorded sessions). Frames come out grey.
class CameraSource {
 public:
  /// Throws RigError naming the source when it cannot be opened.
  CameraSource(const std::string& spec, int width_px, int height_px,
               std::chrono::milliseconds timeout);
  /// The next frame, CV_8UC1. Throws RigError when none comes within the
  /// timeout (the source is then given up), when the source has ended, or
  /// when its size is not the calibrated one.
  cv::Mat Grab();
  const std::string& spec() const { return spec_; }

 private:
  std::string spec_;
  int width_px_, height_px_;
  std::chrono::milliseconds timeout_;
  std::shared_ptr<cv::VideoCapture> capture_ = std::make_shared<cv::VideoCapture>();
  bool stalled_ = false;
};

struct HardwareRigConfig {
  std::unique_ptr<SerialLine> line;  ///< the stages' port, opened
  IndexerOptions stages;
  std::string left_camera, right_camera;
  RigCalibration calibration;
  double home_baseline_m = 0.10;
  std::chrono::milliseconds frame_timeout{2000};
};

class HardwareRig : public Rig {
 public:
  /// Opens both cameras and checks their frame size against the calibration.
  explicit HardwareRig(HardwareRigConfig config);
  MoveResult MoveTo(const StageState& target) override;
  StageState State() const override;
  StereoFrame Capture(const CaptureOptions& options = {}) override;
  const RigLimits& Limits() const override { return limits_; }
  const RigGeometry& Geometry() const override { return delivered_.geometry; }
  CameraIntrinsics Intrinsics(Side side) const override;
  StageState Home() const override { return home_; }

 private:
  RigCalibration calibration_;
  DeliveredPair delivered_;  // what Capture delivers, from the calibration
  std::unique_ptr<IndexerDriver> driver_;
  std::unique_ptr<CameraSource> left_, right_;
  RigLimits limits_;
  StageState home_;
  mutable StageState state_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

}  // namespace rig
