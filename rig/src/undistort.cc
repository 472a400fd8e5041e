#include "rig/undistort.h"

#include <algorithm>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>

namespace rig {

Undistorter::Undistorter(const CameraIntrinsics& raw, const Eigen::Matrix3d& delivered_R_raw,
                         const CameraIntrinsics& delivered) {
  const bool distorted =
      std::any_of(raw.distortion.begin(), raw.distortion.end(), [](double d) { return d != 0; });
  const bool same_k = raw.fx_px == delivered.fx_px && raw.fy_px == delivered.fy_px &&
                      raw.cx_px == delivered.cx_px && raw.cy_px == delivered.cy_px &&
                      raw.width_px == delivered.width_px && raw.height_px == delivered.height_px;
  if (!distorted && same_k && delivered_R_raw.isIdentity(0)) return;
  cv::Mat R;
  cv::eigen2cv(delivered_R_raw, R);
  cv::initUndistortRectifyMap(cv::Mat(raw.K()), raw.distortion, R, cv::Mat(delivered.K()),
                              cv::Size(delivered.width_px, delivered.height_px), CV_32FC1, map_x_,
                              map_y_);
}

cv::Mat Undistorter::Apply(const cv::Mat& raw) const {
  if (!Active()) return raw;
  cv::Mat out;
  // Bicubic: bilinear's blur at half-pixel offsets costs the matchers fine
  // texture (on the imperfect simulated rig with its exact calibration, 12%
  // more median depth error on cylinder_planes than bicubic).
  cv::remap(raw, out, map_x_, map_y_, cv::INTER_CUBIC, cv::BORDER_CONSTANT);
  return out;
}

CameraIntrinsics Undistorter::Pinhole(const CameraIntrinsics& k) {
  CameraIntrinsics p = k;
  p.distortion.clear();
  return p;
}

DeliveredPair::DeliveredPair(const RigCalibration& calibration)
    : raw_geometry(calibration.Geometry()),
      geometry(raw_geometry),
      intrinsics(Undistorter::Pinhole(calibration.left)) {
  for (const Side side : {Side::kLeft, Side::kRight}) {
    HeadGeometry& head = side == Side::kLeft ? geometry.left : geometry.right;
    // In the head frame the delivered camera's axes are R_hc, the raw
    // camera's M R_hc: a raw camera vector x is R_hc' M R_hc x delivered.
    const int s = static_cast<int>(side);
    delivered_R_raw[s] =
        HeadFromCameraRotation().transpose() * head.MountRotation() * HeadFromCameraRotation();
    head.mount_rpy_rad.setZero();
    undistort[s] = Undistorter(calibration.Intrinsics(side), delivered_R_raw[s], intrinsics);
  }
}

}  // namespace rig
