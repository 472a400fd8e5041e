// The fixation frame of a verged pair (beyond the paper; issue 20): both
// cameras turned virtually about their optical centres so that their image
// rows run parallel to the plane through the two optical centres and the
// left optical axis, and both optical axes lie in it.
//
// When the verged cameras also tilt, pan-then-tilt heads twist their image
// rows against each other (torsion, about vergence x sin(elevation)), the
// vertical disparity the paper's tessellation reads grows across the image,
// and the fovea collapses; and a servo that pans the tilted right camera
// swings its axis off the left one's (a cone, not a plane), which shifts
// every row by a constant. In this frame the pair is exactly a level vergent
// pair turned about its baseline: the vertical disparity field, and so the
// paper's tessellation, Z_T and scanline matching, are those of a level
// fixation at the same distance and vergence. The left camera only rolls
// about its principal point; the right one rolls and turns its axis by the
// (small) angle it missed the plane by. Both keep the fixation at the image
// centre and the sampling about it (unlike full rectification to a parallel
// pair, which would also undo the vergence that keeps disparities near zero
// about the fixation and the search bands narrow).
#pragma once

#include <opencv2/core.hpp>

#include "rig/types.h"

namespace fovea {

struct FixationFrame {
  /// The pair as matched: rolled images (grey only when resampled; the
  /// colour ones are in `original`), rolled poses, the stage state; when
  /// resampled, both views have the left camera's intrinsics (rows of one
  /// are rows of the other).
  rig::StereoFrame views;
  /// Original pixel -> fixation-frame pixel, per camera (the homographies
  /// of the two rotations).
  cv::Matx33d left_H = cv::Matx33d::eye(), right_H = cv::Matx33d::eye();
  double left_roll_rad = 0, right_roll_rad = 0;  ///< about each optical axis, original -> turned
  double right_turn_rad = 0;                     ///< the right optical axis's angle to the plane
  /// CV_8U, 255 where a left fixation-frame pixel has its source inside the
  /// original image (all 255 when not resampled).
  cv::Mat left_valid;
  /// false: the turns move no pixel by a hundredth of a pixel and views is
  /// the original frame, images not resampled.
  bool resampled = false;
  /// The pair as captured (its images shared, not copied); empty when the
  /// frame was put together by hand: then `views` stands for it.
  rig::StereoFrame original;
};

/// The fixation frame of a verged `frame`. Where the turns move no pixel by
/// a hundredth of a pixel and the two cameras' intrinsics agree as closely
/// the images are not resampled (a level fixation matches exactly as before).
FixationFrame ToFixationFrame(const rig::StereoFrame& frame);

/// The original frame as the frame matched in (the paper's unrectified
/// matching).
FixationFrame OriginalFrame(const rig::StereoFrame& frame);

/// A verged `frame` turned in software into an exactly parallel, rectified
/// pair (beyond the paper; FovealOptions::rectified_periphery): both views
/// given one orientation, its x axis along the optical centres' offset and
/// its z axis the mean of the two optical axes made perpendicular to it,
/// and one camera matrix, the left one's with its principal point moved so
/// that the left optical axis keeps its pixel (the left image barely moves;
/// the right one shifts by the vergence). Vertical disparity is then zero at
/// every pixel and depth, where the verged pair's grows towards the image's
/// corners (to several pixels at a near fixation). `left_H`, `right_H` map
/// the original pixels; the rolls and the turn are 0; always resampled,
/// grey images only. The optical centres must differ.
FixationFrame ToRectifiedFrame(const rig::StereoFrame& frame);

/// A pair taken with both cameras pointed straight ahead (IDR's), turned in
/// software into an exactly parallel, rectified one: both views given the
/// orientation whose x axis runs along the rail (world X) and whose z axis is the
/// left camera's optical axis made perpendicular to it (y completing it),
/// each image resampled through K_left R K^-1 (borders replicated; both
/// given the left camera's intrinsics). On an
/// imperfect rig this removes what the stages cannot: the mounts' roll and
/// the steps' quantization and the cameras' differing intrinsics. Returned
/// as it is when no pixel would move by a hundredth of a pixel (an ideal rig).
rig::StereoFrame ToParallelFrame(const rig::StereoFrame& frame);

/// Maps pixels through a 3x3 homography.
std::vector<cv::Point2d> MapPixels(const cv::Matx33d& H, const std::vector<cv::Point2d>& pixels);

}  // namespace fovea
