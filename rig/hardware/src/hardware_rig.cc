#include "rig/hardware/hardware_rig.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <future>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <thread>

#include "rig/input_file.h"

namespace rig {

CameraSource::CameraSource(const std::string& spec, int width_px, int height_px,
                           std::chrono::milliseconds timeout)
    : spec_(spec), width_px_(width_px), height_px_(height_px), timeout_(timeout) {
  const bool index = !spec.empty() && spec.find_first_not_of("0123456789") == std::string::npos;
  const bool sequence = spec.find('%') != std::string::npos;
  // What does not exist is said plainly (and the video backends, which log
  // on their own, are not asked).
  const std::string must_exist =
      sequence ? std::filesystem::path(spec).parent_path().string() : spec;
  if (!index && !must_exist.empty() && !std::filesystem::exists(must_exist))
    throw RigError("camera '" + spec + "' cannot be opened: no such " +
                   (sequence ? "folder" : "file or device"));
  bool ok = false;
  try {
    ok = index ? capture_->open(std::stoi(spec), cv::CAP_V4L2)
               : capture_->open(spec, sequence ? cv::CAP_IMAGES : cv::CAP_ANY);
  } catch (const cv::Exception&) {
    ok = false;
  }
  if (!ok || !capture_->isOpened()) throw RigError("camera '" + spec + "' cannot be opened");
  if (index) {
    capture_->set(cv::CAP_PROP_FRAME_WIDTH, width_px);
    capture_->set(cv::CAP_PROP_FRAME_HEIGHT, height_px);
  }
  // Check the size before the first frame is taken (a source that does not
  // tell is checked at every Grab).
  const int w = static_cast<int>(capture_->get(cv::CAP_PROP_FRAME_WIDTH));
  const int h = static_cast<int>(capture_->get(cv::CAP_PROP_FRAME_HEIGHT));
  if (w > 0 && h > 0 && (w != width_px || h != height_px))
    throw RigError("camera '" + spec + "' gives " + std::to_string(w) + "x" + std::to_string(h) +
                   " images, the calibration is for " + std::to_string(width_px) + "x" +
                   std::to_string(height_px));
}

cv::Mat CameraSource::Grab() {
  if (stalled_)
    throw RigError("camera '" + spec_ + "': stalled earlier (no frame within the timeout)");
  // VideoCapture::read blocks on a device that sends nothing: read on a
  // detached worker (which owns what it touches) and give up after the
  // timeout; a promise's future, unlike std::async's, does not wait for the
  // worker when it goes away.
  auto frame = std::make_shared<cv::Mat>();
  auto done = std::make_shared<std::promise<bool>>();
  std::future<bool> read = done->get_future();
  std::thread([capture = capture_, frame, done] {
    done->set_value(capture->read(*frame));
  }).detach();
  if (read.wait_for(timeout_) != std::future_status::ready) {
    stalled_ = true;
    throw RigError("camera '" + spec_ + "': no frame within " + std::to_string(timeout_.count()) +
                   " ms");
  }
  if (!read.get() || frame->empty()) throw RigError("camera '" + spec_ + "': no more frames");
  if (frame->cols != width_px_ || frame->rows != height_px_)
    throw RigError("camera '" + spec_ + "' gives " + std::to_string(frame->cols) + "x" +
                   std::to_string(frame->rows) + " images, the calibration is for " +
                   std::to_string(width_px_) + "x" + std::to_string(height_px_));
  cv::Mat gray;
  if (frame->channels() == 3)
    cv::cvtColor(*frame, gray, cv::COLOR_BGR2GRAY);
  else if (frame->channels() == 4)
    cv::cvtColor(*frame, gray, cv::COLOR_BGRA2GRAY);
  else
    gray = *frame;
  return gray;
}

HardwareRig::HardwareRig(HardwareRigConfig config)
    : calibration_(config.calibration), delivered_(calibration_) {
  for (int i = 0; i < kNumAxes; ++i) {
    const IndexerAxis& a = config.stages.axes[i];
    limits_.axes[i] = {a.min, a.max, a.steps_per_unit};
  }
  home_ = limits_.Quantize(StageState::Parallel(config.home_baseline_m));
  left_ = std::make_unique<CameraSource>(config.left_camera, calibration_.left.width_px,
                                         calibration_.left.height_px, config.frame_timeout);
  right_ = std::make_unique<CameraSource>(config.right_camera, calibration_.right.width_px,
                                          calibration_.right.height_px, config.frame_timeout);
  driver_ = std::make_unique<IndexerDriver>(std::move(config.line), config.stages);
  state_ = driver_->Position();
}

MoveResult HardwareRig::MoveTo(const StageState& target) {
  const std::string violation = limits_.Violation(target);
  if (!violation.empty()) throw RigError("move refused: " + violation);
  MoveResult r = driver_->MoveTo(limits_.Quantize(target));
  state_ = r.reached;
  return r;
}

StageState HardwareRig::State() const { return state_; }

CameraIntrinsics HardwareRig::Intrinsics(Side) const {
  return delivered_.intrinsics;  // what Capture delivers
}

StereoFrame HardwareRig::Capture(const CaptureOptions& options) {
  StereoFrame frame;
  frame.state = state_;
  frame.timestamp_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  for (const Side side : {Side::kLeft, Side::kRight}) {
    CameraView& view = side == Side::kLeft ? frame.left : frame.right;
    const cv::Mat raw = (side == Side::kLeft ? left_ : right_)->Grab();
    // Frames go out as DeliveredPair describes, unless asked for raw.
    view.gray = options.raw ? raw : delivered_.undistort[static_cast<int>(side)].Apply(raw);
    view.intrinsics = options.raw ? calibration_.Intrinsics(side) : Intrinsics(side);
    view.world_T_camera = (options.raw ? delivered_.raw_geometry : delivered_.geometry)
                              .WorldFromCamera(side, state_[side]);
  }
  return frame;
}

}  // namespace rig
