// Planar surface patches: the common currency of IDR, the foveated stage and
// the global map (design note, "Planar patches").
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "rig/types.h"

namespace fovea {

/// Where a patch came from, coarsest first. Integration (paper section IV)
/// lets finer levels replace coarser ones, never the reverse.
enum class PatchLevel { kIdr = 0, kPeripheral = 1, kFoveal = 2 };
const char* PatchLevelName(PatchLevel level);

/// A planar quadrilateral in the world.
struct Patch {
  std::array<Eigen::Vector3d, 4> corners_W;  ///< in order around the quad
  PatchLevel level = PatchLevel::kIdr;
  int fixation = -1;          ///< index of the fixation that made it; -1 for IDR
  int resolution_level = 0;   ///< 0 = full resolution, k = downsampled 2^k
  double fit_rms_px = 0;      ///< RMS residual of its disparity-plane fit
  int support = 0;            ///< number of measurements in the fit

  Eigen::Vector3d Centre() const;
  /// Unit normal (right-handed from the corner order).
  Eigen::Vector3d Normal() const;
  /// Diameter: the longer diagonal, metres.
  double SizeM() const;
};

/// A disparity plane d(x, y) = a x + b y + c fitted over one block.
struct PlaneFit {
  double a = 0, b = 0, c = 0;
  double rms_px = 0, max_abs_px = 0;
  int support = 0;
  double operator()(double x, double y) const { return a * x + b * y + c; }
};

struct PlaneFitOptions {
  int min_support = 8;           ///< inlier measurements needed in a block
  /// Measurements farther than this from the plane are outliers; the fit is
  /// redone without them (twice), and every kept measurement lies within it.
  double fit_tolerance_px = 1.0;
  /// Reject the block unless this share of its measurements are inliers: a
  /// block across a depth step has two populations and fails.
  double min_inlier_share = 0.85;
  /// Require measurements in all four quadrants of the block, so that a
  /// patch never extrapolates over a part of the block it has no data for
  /// (for instance the other side of a depth step).
  bool require_quadrants = true;
};

/// One measurement: a disparity at a (sub-pixel) image position.
struct DisparitySample {
  double x_px, y_px, disparity_px;
};

/// Trimmed least-squares plane over the samples that fall in the block
/// [x0, x0 + size) x [y0, y0 + size). nullopt if the block has too little
/// support, degenerate geometry, or too many samples beyond the tolerance.
/// `inlier_box`, if given, receives the inliers' extent (x0, y0, x1, y1).
std::optional<PlaneFit> FitDisparityPlane(const std::vector<DisparitySample>& samples, double x0,
                                          double y0, double size, const PlaneFitOptions& options,
                                          Eigen::Vector4d* inlier_box = nullptr);

/// Result of a ray query.
struct PatchHit {
  double distance_m = 0;  ///< along the unit ray direction
  int patch = -1;
};

/// The global map of patches. Queries: by ray (raytrace a pixel of any camera
/// into the map) and by footprint in a view (rasterize the map into a camera).
class PatchMap {
 public:
  const std::vector<Patch>& patches() const { return patches_; }
  size_t size() const { return patches_.size(); }
  void Add(const Patch& patch) { patches_.push_back(patch); }
  void Clear() { patches_.clear(); }

  /// First patch hit by the ray from origin_W along direction_W (unit).
  std::optional<PatchHit> CastRay(const Eigen::Vector3d& origin_W, const Eigen::Vector3d& direction_W) const;

  /// The map seen by a camera: planar depth (CV_32F, 0 where no patch) and
  /// the index of the nearest patch per pixel (CV_32S, -1 where none), by
  /// z-buffered rasterization of every patch in front of the camera.
  void Render(const Eigen::Isometry3d& world_T_camera, const rig::CameraIntrinsics& intrinsics,
              cv::Mat* depth_m, cv::Mat* patch_ids) const;

 private:
  std::vector<Patch> patches_;
};

}  // namespace fovea
