// The foveal tessellation (paper section III; design note "Foveated vergent
// stereo", step 3): nested, centred rectangles of decreasing resolution,
// sized so that vertical disparity stays under half a pixel of each level and
// plain scanline matching holds everywhere.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <vector>

#include "fovea/patch.h"
#include "rig/types.h"

namespace fovea {

struct TessellationOptions {
  /// Full-resolution horizontal disparity limit of the fovea's search: Z_T
  /// is the depth offset at which a point on the left optical axis reaches
  /// half of it. Beyond the paper's setting (32): at 64 more of a depth
  /// edge's two sides fall inside one fixation's band, so the matcher sees
  /// the jump and keeps the nearer surface's fattening off the farther one
  /// (edge_bad_share 0.085 -> 0.071 over the accuracy set; README).
  double horizontal_disparity_limit_px = 64;
  int max_levels = 2;  ///< level k samples every 2^k pixels (the paper: 4; see README)
  /// Beyond the paper: the fovea (level 0) is at least this many pixels wide
  /// and high, centred, and every coarser level contains it. The worst-case
  /// plane at Z_max bounds vertical disparity over the whole view; near the
  /// fixation a surface that far off is rare, and at the floor's edge the
  /// bound grows only in proportion (the floor's half-size over the rule's).
  int min_fovea_px = 32;
  void Check() const;  ///< throws rig::InputError naming the key (fovea/params.h)
};

struct Tessellation {
  double fixation_depth_m = 0;  ///< Z of the fixation point in the left camera
  double z_t_near_m = 0;        ///< Z_T in front of the fixation (positive)
  double z_t_far_m = 0;         ///< Z_T behind it (positive)
  double z_max_near_m = 0;      ///< worst-case plane offsets used (map, limited by Z_T)
  double z_max_far_m = 0;
  /// Per level k: the centred rectangle (full-resolution pixels) inside
  /// which level k applies; level 0 innermost, the last one the whole image.
  std::vector<cv::Rect> rects;
  /// CV_8U: 255 where matching may run, 0 where the map puts the surface
  /// beyond Z_T of the fixation.
  cv::Mat mask;

  /// The finest level whose rectangle contains the pixel.
  int LevelAt(int u, int v) const;
  /// Whether a surface at planar depth `z_m` lies beyond Z_T of the
  /// fixation (`mask`'s rule where the map shows one).
  bool BeyondZt(double z_m) const {
    const double off = z_m - fixation_depth_m;
    return off > z_t_far_m || -off > z_t_near_m;
  }
};

/// Horizontal disparity (u_right - cx_right) of the point on the left
/// optical axis at depth z_m.
double AxisHorizontalDisparity(const rig::CameraView& left, const rig::CameraView& right,
                               double z_m);

/// Builds the tessellation for a verged pair fixating p_W, using the map's
/// depths in the left view for Z_max and the mask.
/// `options` must have passed Check(): the run checks them once, before
/// its work (RunFovea, RunIdr, RunConfig::Check), never per call.
Tessellation Tessellate(const rig::CameraView& left, const rig::CameraView& right,
                        const Eigen::Vector3d& fixation_W, const PatchMap& map,
                        const TessellationOptions& options);

/// The same from the map's depth in the left view, rendered already
/// (PatchMap::Render: 0 where the map is silent).
Tessellation TessellateFromDepth(const rig::CameraView& left, const rig::CameraView& right,
                                 const Eigen::Vector3d& fixation_W, const cv::Mat& map_depth,
                                 const TessellationOptions& options);

}  // namespace fovea
