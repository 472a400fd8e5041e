#include "fovea/fixation_frame.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace fovea {
namespace {

cv::Matx33d CameraMatrix(const rig::CameraIntrinsics& k) {
  return {k.fx_px, 0, k.cx_px, 0, k.fy_px, k.cy_px, 0, 0, 1};
}

// The camera's orientation turned into the plane of unit normal `normal`:
// its optical axis projected onto the plane, its y axis along the normal
// (the sign nearest the original y axis). The roll about the optical axis
// and the axis's turn into the plane, original -> turned.
Eigen::Matrix3d IntoPlane(const Eigen::Matrix3d& R, const Eigen::Vector3d& normal, double* roll,
                          double* turn) {
  *roll = *turn = 0;
  Eigen::Vector3d z = R.col(2) - normal.dot(R.col(2)) * normal;
  if (z.norm() < 1e-9) return R;  // the axis lies along the normal: no plane to turn into
  z.normalize();
  *turn = std::asin(std::clamp(normal.dot(R.col(2)), -1.0, 1.0));
  const Eigen::Vector3d y = normal.dot(R.col(1)) < 0 ? Eigen::Vector3d(-normal) : normal;
  Eigen::Matrix3d out;
  out.col(0) = y.cross(z);
  out.col(1) = y;
  out.col(2) = z;
  // The turned x axis in the original camera's coordinates.
  const Eigen::Vector3d x_C = R.transpose() * out.col(0);
  *roll = std::atan2(x_C.y(), x_C.x());
  return out;
}

// The largest angle a rotation turns any vector by, radians.
double RotationAngle(const Eigen::Matrix3d& R) {
  return std::acos(std::clamp(0.5 * (R.trace() - 1), -1.0, 1.0));
}

// Whether resampling `frame` to turn its cameras by at most `angle`
// (radians) and give the right camera the left one's intrinsics would move
// no pixel by a hundredth of a pixel at the farthest corner: not worth it.
bool MovesNoPixel(const rig::StereoFrame& frame, double angle) {
  const rig::CameraIntrinsics& k = frame.left.intrinsics;
  const double corner =
      std::hypot(std::max(k.cx_px, k.width_px - k.cx_px), std::max(k.cy_px, k.height_px - k.cy_px));
  if (angle * std::max(corner, k.fx_px) >= 0.01) return false;
  // Where the right camera's corners land on the left camera's pixel grid.
  const rig::CameraIntrinsics& r = frame.right.intrinsics;
  const cv::Matx33d M = CameraMatrix(k) * CameraMatrix(r).inv();
  for (const double u : {0.0, r.width_px - 1.0})
    for (const double v : {0.0, r.height_px - 1.0}) {
      const cv::Vec3d q = M * cv::Vec3d(u, v, 1);
      if (std::hypot(q[0] / q[2] - u, q[1] / q[2] - v) >= 0.01) return false;
    }
  return true;
}

// `view` turned to orientation `rolled` (about its optical centre) and given
// the intrinsics `to`: both views of a pair get the left camera's, so that a
// row of one is the same row of the other even when the cameras' principal
// points or focal lengths differ (a calibrated pair's do, by a pixel).
rig::CameraView TurnView(const rig::CameraView& view, const Eigen::Matrix3d& rolled,
                         const rig::CameraIntrinsics& to, cv::Matx33d* H,
                         int border = cv::BORDER_CONSTANT) {
  const Eigen::Matrix3d R = rolled.transpose() * view.world_T_camera.linear();
  cv::Matx33d Rc;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) Rc(i, j) = R(i, j);
  *H = CameraMatrix(to) * Rc * CameraMatrix(view.intrinsics).inv();
  rig::CameraView out;
  out.intrinsics = to;
  out.world_T_camera = view.world_T_camera;
  out.world_T_camera.linear() = rolled;
  const cv::Size size(to.width_px, to.height_px);
  cv::warpPerspective(view.gray, out.gray, *H, size, cv::INTER_LINEAR, border);
  if (!view.bgr.empty()) cv::warpPerspective(view.bgr, out.bgr, *H, size, cv::INTER_LINEAR, border);
  return out;
}

// `view` without its colour image (the grey one and the pose shared).
rig::CameraView Grey(rig::CameraView view) {
  view.bgr = cv::Mat();
  return view;
}

// CV_8U, 255 where every source pixel of the bilinear sample through `H`
// (original -> turned) lies inside the original image of `size`.
cv::Mat ValidAfter(cv::Size size, const cv::Matx33d& H) {
  const cv::Mat ones(size, CV_8U, cv::Scalar(255));
  cv::Mat valid;
  cv::warpPerspective(ones, valid, H, size, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
  return valid == 255;
}

}  // namespace

FixationFrame OriginalFrame(const rig::StereoFrame& frame) {
  FixationFrame f;
  f.views = frame;
  f.original = frame;
  f.left_valid = cv::Mat(frame.left.gray.size(), CV_8U, cv::Scalar(255));
  return f;
}

FixationFrame ToFixationFrame(const rig::StereoFrame& frame) {
  const Eigen::Matrix3d& left = frame.left.world_T_camera.linear();
  const Eigen::Matrix3d& right = frame.right.world_T_camera.linear();
  const Eigen::Vector3d baseline =
      frame.right.world_T_camera.translation() - frame.left.world_T_camera.translation();
  const Eigen::Vector3d normal = baseline.cross(left.col(2));
  if (normal.norm() < 1e-12) return OriginalFrame(frame);
  FixationFrame f;
  double left_turn = 0;
  const Eigen::Matrix3d tl = IntoPlane(left, normal.normalized(), &f.left_roll_rad, &left_turn);
  const Eigen::Matrix3d tr =
      IntoPlane(right, normal.normalized(), &f.right_roll_rad, &f.right_turn_rad);
  const double angle =
      std::max(RotationAngle(tl.transpose() * left), RotationAngle(tr.transpose() * right));
  if (MovesNoPixel(frame, angle)) {
    FixationFrame same = OriginalFrame(frame);
    same.left_roll_rad = f.left_roll_rad;
    same.right_roll_rad = f.right_roll_rad;
    same.right_turn_rad = f.right_turn_rad;
    return same;
  }
  f.resampled = true;
  f.original = frame;
  f.views.state = frame.state;
  f.views.timestamp_s = frame.timestamp_s;
  // Grey only: the pair is matched in and drawn on in grey, and turning
  // the colour images too cost more than the grey ones.
  f.views.left = TurnView(Grey(frame.left), tl, frame.left.intrinsics, &f.left_H);
  f.views.right = TurnView(Grey(frame.right), tr, frame.left.intrinsics, &f.right_H);
  f.left_valid = ValidAfter(frame.left.gray.size(), f.left_H);
  return f;
}

FixationFrame ToRectifiedFrame(const rig::StereoFrame& frame) {
  const Eigen::Matrix3d& left = frame.left.world_T_camera.linear();
  const Eigen::Matrix3d& right = frame.right.world_T_camera.linear();
  Eigen::Matrix3d rect;
  rect.col(0) = (frame.right.world_T_camera.translation() - frame.left.world_T_camera.translation())
                    .normalized();
  const Eigen::Vector3d axis = left.col(2) + right.col(2);
  rect.col(2) = (axis - rect.col(0).dot(axis) * rect.col(0)).normalized();
  rect.col(1) = rect.col(2).cross(rect.col(0));
  // The left optical axis in the new orientation: it keeps its pixel.
  rig::CameraIntrinsics k = frame.left.intrinsics;
  const Eigen::Vector3d a = rect.transpose() * left.col(2);
  k.cx_px -= k.fx_px * a.x() / a.z();
  k.cy_px -= k.fy_px * a.y() / a.z();
  FixationFrame f;
  f.resampled = true;
  f.original = frame;
  f.views.state = frame.state;
  f.views.timestamp_s = frame.timestamp_s;
  // Grey only: the rectified pair is matched, never shown.
  f.views.left = TurnView(Grey(frame.left), rect, k, &f.left_H);
  f.views.right = TurnView(Grey(frame.right), rect, k, &f.right_H);
  f.left_valid = ValidAfter(frame.left.gray.size(), f.left_H);
  return f;
}

rig::StereoFrame ToParallelFrame(const rig::StereoFrame& frame) {
  const Eigen::Matrix3d& left = frame.left.world_T_camera.linear();
  const Eigen::Matrix3d& right = frame.right.world_T_camera.linear();
  // x along the rail (world X), not along the centres' offset: cameras
  // that sit off their axes are turned differently, so their centres also
  // differ forward and up by millimetres, which at IDR's smallest baselines
  // would turn the pair by tens of degrees. IDR's baseline is the centres'
  // offset along x; the rest is a depth-scale error of its order over the
  // depth, and vertical disparity of f times it over the depth.
  Eigen::Matrix3d rect;
  rect.col(0) = Eigen::Vector3d::UnitX();
  rect.col(2) = (left.col(2) - rect.col(0).dot(left.col(2)) * rect.col(0)).normalized();
  rect.col(1) = rect.col(2).cross(rect.col(0));
  const double angle =
      std::max(RotationAngle(rect.transpose() * left), RotationAngle(rect.transpose() * right));
  if (MovesNoPixel(frame, angle)) return frame;
  rig::StereoFrame out;
  out.state = frame.state;
  out.timestamp_s = frame.timestamp_s;
  cv::Matx33d H;
  out.left = TurnView(frame.left, rect, frame.left.intrinsics, &H, cv::BORDER_REPLICATE);
  out.right = TurnView(frame.right, rect, frame.left.intrinsics, &H, cv::BORDER_REPLICATE);
  return out;
}

std::vector<cv::Point2d> MapPixels(const cv::Matx33d& H, const std::vector<cv::Point2d>& pixels) {
  std::vector<cv::Point2d> out;
  cv::perspectiveTransform(pixels, out, cv::Matx33d(H));
  return out;
}

}  // namespace fovea
