#include "fovea/sgbm.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>

#include "fovea/params.h"
#include "rig/input_file.h"

namespace fovea {

void SgbmOptions::Check() const {
  rig::CheckParam(params::kSgbmBlockSize, block_size);
  if (block_size % 2 == 0)
    throw rig::InputError("key 'sgbm.block_size': " + std::to_string(block_size) + " is not odd");
  rig::CheckParam(params::kSgbmUniquenessRatio, uniqueness_ratio);
  rig::CheckParam(params::kSgbmSpeckleWindow, speckle_window);
  rig::CheckParam(params::kSgbmSpeckleRange, speckle_range);
}
namespace {

cv::Ptr<cv::StereoSGBM> Make(const SgbmOptions& o, int min_d, int num_d) {
  const int p1 = 8 * o.block_size * o.block_size, p2 = 32 * o.block_size * o.block_size;
  return cv::StereoSGBM::create(min_d, num_d, o.block_size, p1, p2, 1, 0, o.uniqueness_ratio,
                                o.speckle_window, o.speckle_range, cv::StereoSGBM::MODE_SGBM);
}

}  // namespace

DisparityMap SgbmMatcher::Match(const cv::Mat& left, const cv::Mat& right, const cv::Mat& lo_px,
                                const cv::Mat& hi_px) const {
  DisparityMap out;
  out.disparity_px =
      cv::Mat(left.size(), CV_32F, cv::Scalar(std::numeric_limits<float>::quiet_NaN()));
  out.confidence = cv::Mat(left.size(), CV_32F, cv::Scalar(0));
  double lo = 1e9, hi = -1e9;
  for (int y = 0; y < left.rows; ++y)
    for (int x = 0; x < left.cols; ++x)
      if (lo_px.at<float>(y, x) <= hi_px.at<float>(y, x)) {
        lo = std::min<double>(lo, lo_px.at<float>(y, x));
        hi = std::max<double>(hi, hi_px.at<float>(y, x));
        ++out.searched;
      }
  if (out.searched == 0) return out;
  const int min_d = static_cast<int>(std::floor(lo)) - 1;
  const int num_d = ((static_cast<int>(std::ceil(hi)) + 2 - min_d + 15) / 16) * 16;
  cv::Mat d16;
  Make(options_, min_d, num_d)->compute(left, right, d16);
  for (int y = 0; y < left.rows; ++y)
    for (int x = 0; x < left.cols; ++x) {
      const float l = lo_px.at<float>(y, x), h = hi_px.at<float>(y, x);
      if (!(l <= h)) continue;
      const short raw = d16.at<short>(y, x);
      if (raw <= (min_d - 1) * 16) continue;  // SGBM's "invalid"
      const float d = raw / 16.0f;
      if (d < l - 1 || d > h + 1) continue;
      out.disparity_px.at<float>(y, x) = d;
      out.confidence.at<float>(y, x) = 1;
      ++out.matched;
    }
  return out;
}

cv::Mat RectifiedSgbmDepth(const rig::CameraView& left, const rig::CameraView& right,
                           double min_depth_m, double max_depth_m, const SgbmOptions& options) {
  const cv::Size size(left.intrinsics.width_px, left.intrinsics.height_px);
  // OpenCV's R, T take left-camera points to the right camera.
  const Eigen::Isometry3d right_T_left = right.world_T_camera.inverse() * left.world_T_camera;
  cv::Mat r, t, r1, r2, p1, p2, q;
  cv::eigen2cv(Eigen::Matrix3d(right_T_left.linear()), r);
  cv::eigen2cv(Eigen::Vector3d(right_T_left.translation()), t);
  const cv::Mat k1(left.intrinsics.K()), k2(right.intrinsics.K());
  cv::stereoRectify(k1, cv::noArray(), k2, cv::noArray(), size, r, t, r1, r2, p1, p2, q,
                    cv::CALIB_ZERO_DISPARITY, 0);
  cv::Mat m1x, m1y, m2x, m2y, lr, rr;
  cv::initUndistortRectifyMap(k1, cv::noArray(), r1, p1, size, CV_32FC1, m1x, m1y);
  cv::initUndistortRectifyMap(k2, cv::noArray(), r2, p2, size, CV_32FC1, m2x, m2y);
  cv::remap(left.gray, lr, m1x, m1y, cv::INTER_LINEAR);
  cv::remap(right.gray, rr, m2x, m2y, cv::INTER_LINEAR);
  // Rectified disparity d = -P2(0, 3) / Z (P2's Tx is -f B).
  const double fb = -p2.at<double>(0, 3);
  const double min_disparity_px = fb / max_depth_m, max_disparity_px = fb / min_depth_m;
  const int min_d = static_cast<int>(std::floor(min_disparity_px)) - 1;
  const int num_d = ((static_cast<int>(std::ceil(max_disparity_px)) + 2 - min_d + 15) / 16) * 16;
  // StereoSGBM leaves the left min_d + num_d columns without a result; pad
  // both images on the left so that every real column gets one.
  const int pad = std::max(0, min_d + num_d);
  cv::Mat lp, rp, d16, d, xyz;
  cv::copyMakeBorder(lr, lp, 0, 0, pad, 0, cv::BORDER_REPLICATE);
  cv::copyMakeBorder(rr, rp, 0, 0, pad, 0, cv::BORDER_REPLICATE);
  Make(options, min_d, num_d)->compute(lp, rp, d16);
  d16(cv::Rect(pad, 0, size.width, size.height)).convertTo(d, CV_32F, 1.0 / 16);
  cv::reprojectImageTo3D(d, xyz, q, true);
  // Back to the unrectified left view: rectified pixel of each left pixel,
  // then the point, rotated from the rectified frame into the left camera.
  cv::Mat depth(size, CV_32F, cv::Scalar(0));
  std::vector<cv::Point2f> src, dst;
  for (int v = 0; v < size.height; ++v)
    for (int u = 0; u < size.width; ++u) src.emplace_back(float(u), float(v));
  cv::undistortPoints(src, dst, k1, cv::noArray(), r1, p1);
  cv::Matx33d r1m(r1);
  for (size_t i = 0; i < src.size(); ++i) {
    const int x = static_cast<int>(std::lround(dst[i].x)),
              y = static_cast<int>(std::lround(dst[i].y));
    if (x < 0 || y < 0 || x >= size.width || y >= size.height) continue;
    if (d.at<float>(y, x) <= min_d) continue;
    const cv::Vec3f p = xyz.at<cv::Vec3f>(y, x);
    if (!std::isfinite(p[2]) || p[2] <= 0 || p[2] > 100) continue;
    const cv::Vec3d p_left = r1m.t() * cv::Vec3d(p[0], p[1], p[2]);
    depth.at<float>(static_cast<int>(src[i].y), static_cast<int>(src[i].x)) =
        static_cast<float>(p_left[2]);
  }
  return depth;
}

}  // namespace fovea
