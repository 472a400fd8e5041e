// Planar surface patches: the common currency of IDR, the foveated stage and
// the global map (design note, "Planar patches").
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <functional>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "rig/param.h"
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
  int fixation = -1;         ///< index of the fixation that made it; -1 for IDR
  int resolution_level = 0;  ///< 0 = full resolution, k = downsampled 2^k
  double fit_rms_px = 0;     ///< RMS residual of its disparity-plane fit
  int support = 0;           ///< number of measurements in the fit
  /// Standard deviation of its depth along the observing camera's axis at
  /// its centre, metres (DepthSigma): what integration and the map's
  /// rendering weigh observations by. 0: unknown (treated as certain).
  double sigma_z_m = 0;
  /// The reference camera does not see it (HiddenQuarters): a surface
  /// seen past a nearer one's edge from another viewpoint. It stays in the
  /// map (it is there, and other views see it) but not in the map's depth in
  /// the reference view (ReferenceMap).
  bool hidden_in_reference = false;
  /// The part of it the reference camera sees, in its coordinates (s, t) in
  /// [0, 1]^2 across and down its corners (top-left, top-right,
  /// bottom-right, bottom-left): [s0, s1] x [t0, t1]. Its sides the
  /// reference camera does not see (ReferenceSides: a strip of a farther
  /// surface past a nearer one's edge, or a plane carried over an edge) are
  /// cut from the map's depth in the reference view (ReferenceMap).
  struct Part {
    double s0 = 0, s1 = 1, t0 = 0, t1 = 1;
    bool Whole() const { return s0 <= 0 && s1 >= 1 && t0 <= 0 && t1 >= 1; }
    /// Every side cut away: the reference camera sees none of it.
    bool Empty() const { return !(s0 < s1 && t0 < t1); }
  } reference_part;

  /// Order of precedence between patches of the same surface: foveal over
  /// peripheral over IDR, and within a level the finer resolution first.
  int Fineness() const { return 8 * static_cast<int>(level) - resolution_level; }

  Eigen::Vector3d Centre() const;
  /// Unit normal (right-handed from the corner order).
  Eigen::Vector3d Normal() const;
  /// Diameter: the longer diagonal, metres.
  double SizeM() const;
  /// The angle between its plane's normal and the line of sight from
  /// `eye_W` to its centre, radians: 0 seen face on, pi/2 edge on.
  double ViewAngleRad(const Eigen::Vector3d& eye_W) const;
};

/// Matching precision of a well-textured window at full resolution, pixels
/// of disparity (sub-pixel refinement reaches 0.1 to 0.2 px; see FACTS).
constexpr double kMatchSigmaPx = 0.15;

/// Depth standard deviation of a point at planar depth `z_m` measured with a
/// disparity standard deviation `sigma_d_px` (full-resolution pixels) by a
/// pair whose optical centres differ by `baseline_W`, seen along `ray_W`:
/// sigma_Z = Z^2 sigma_d / (f B_perp), B_perp the baseline's component
/// perpendicular to the ray (a verged pair's effective baseline).
double DepthSigma(double z_m, double sigma_d_px, double focal_px, const Eigen::Vector3d& baseline_W,
                  const Eigen::Vector3d& ray_W);

/// Sets patch->sigma_z_m for a patch measured by a stereo pair whose left
/// camera is `left` and whose right optical centre is `right_centre_W`, with
/// a disparity standard deviation `sigma_d_px` in full-resolution pixels: the
/// depth sigma along the left camera's axis at the patch's centre.
void SetDepthSigma(Patch* patch, const rig::CameraView& left, const Eigen::Vector3d& right_centre_W,
                   double sigma_d_px);

/// A disparity plane d(x, y) = a x + b y + c fitted over one block.
struct PlaneFit {
  double a = 0, b = 0, c = 0;
  double rms_px = 0, max_abs_px = 0;
  int support = 0;       ///< inliers
  int measurements = 0;  ///< samples in the block, inliers and outliers
  double operator()(double x, double y) const { return a * x + b * y + c; }
};

struct PlaneFitOptions {
  int min_support = 8;  ///< inlier measurements needed in a block
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
  /// Throws rig::InputError naming the key, against the specs of the fit it
  /// serves (IDR's or the fovea's, fovea/params.h).
  void Check(const rig::ParamSpec& min_support_spec, const rig::ParamSpec& fit_tolerance_spec,
             const rig::ParamSpec& min_inlier_share_spec) const;
};

/// One measurement: a disparity at a (sub-pixel) image position.
struct DisparitySample {
  double x_px, y_px, disparity_px;
  /// Whether, as an inlier, it extends the fit's inlier box (false: a match
  /// that counts in the fit but does not set the patch's footprint).
  bool bounds = true;
};

/// A footprint's corners in the image, pixel edges, in the order top-left,
/// top-right, bottom-right, bottom-left.
using Quad2d = std::array<Eigen::Vector2d, 4>;

/// Trimmed least-squares plane over the samples that fall in the block
/// [x0, x0 + width) x [y0, y0 + height) (a square block, or a half of one).
/// nullopt if the block has too little support, degenerate geometry, too
/// many samples beyond the tolerance, or (PlaneFitOptions::
/// require_quadrants) a quadrant of it without an inlier.
/// `inlier_box`, if given, receives the extent (x0, y0, x1, y1) of the
/// inliers that bound (DisparitySample::bounds); nullopt if none does.
/// `inlier_quad`, if given, receives their diagonal hull: the pixel corners
/// farthest up-left, up-right, down-right and down-left of them
/// (BlockOptions::clip_diagonals).
std::optional<PlaneFit> FitDisparityPlane(const std::vector<DisparitySample>& samples, double x0,
                                          double y0, double width, double height,
                                          const PlaneFitOptions& options,
                                          Eigen::Vector4d* inlier_box = nullptr,
                                          Quad2d* inlier_quad = nullptr);

/// The corners of a box (x0, y0, x1, y1) as a Quad2d.
Quad2d BoxQuad(const Eigen::Vector4d& box);

/// One block of a disparity image fitted as one plane.
struct BlockFit {
  int x = 0, y = 0, size = 0;  ///< the block: [x, x + size) x [y, y + size), image pixels
  PlaneFit fit;
  /// The patch's extent in the image, pixel edges (x0, y0, x1, y1): the
  /// block, or with BlockOptions::clip_to_inliers the inliers' bounding box.
  Eigen::Vector4d footprint = Eigen::Vector4d::Zero();
  /// The patch's corners in the image: the footprint's, or with
  /// BlockOptions::clip_diagonals the inliers' diagonal hull.
  Quad2d corners{};
};

/// How FitBlocks turns blocks into planes (beyond the paper: its defaults;
/// min_fill_share = 0 and clip_to_inliers = false give the paper's rule).
struct BlockOptions {
  /// A block becomes one plane only if its inliers fill this share of it
  /// and next to none of its measurements are outliers (at most 5%, at least
  /// one); otherwise (a depth edge inside it, a strip without matches along
  /// one) it is split into quarters, recursively down to `min_block_px`,
  /// and a smallest block that is not whole is left out, so that no plane
  /// spans two surfaces. 0: every block whose fit succeeds.
  double min_fill_share = 0.5;
  int min_block_px = 4;
  /// A plane covers only its inliers' bounding box, not its whole block: a
  /// block whose data stops short of a side (the far side of a depth edge,
  /// unmatched or eroded) does not extrapolate its plane over the rest.
  bool clip_to_inliers = true;
  /// With clip_to_inliers, a plane covers only the quadrilateral of its
  /// inliers' extreme pixels along both diagonals (the pixel corner farthest
  /// up-left, up-right, down-right and down-left), not their bounding box: a
  /// block that a depth edge crosses at a slant (a sphere's or a box's
  /// outline) stops at the edge instead of reaching over the other side's
  /// corner. The same footprint as the box where the inliers fill a
  /// rectangle.
  bool clip_diagonals = false;
  /// Beyond the paper (issue 19): with this > 0, a block that is not whole
  /// and is split no further (its quarters would be under min_block_px) is
  /// cut in two halves, side by side and one above the other. A half whole
  /// by the rule above (its own fill and outliers, and its own four
  /// quadrants where PlaneFitOptions::require_quadrants; its footprint its
  /// inliers' box) becomes a plane where a whole block beside
  /// its block (left, right, above or below) has a plane within this many
  /// fit tolerances of its own at each corner of its footprint: the half
  /// extends, up to a depth edge, a surface found whole next to it. Without
  /// that neighbour a half is left out: a half-block of coherent matches
  /// alone is as often a false match (README, issue 19). Of the two cuts,
  /// the one whose whole halves hold more inliers. 0: no halves.
  double half_agreement = 0;
};

/// Planes over the blocks of `size` pixels that tile `disparity` (CV_32F,
/// NaN = no measurement) that `keep` accepts, by the rules of `blocks`. The
/// fit's min_support shrinks with the block (to 3/4 of its pixels). Where
/// `unbounded` (CV_8U, same size, optional) is non-zero, a match counts in
/// the fit but does not set a clipped footprint.
std::vector<BlockFit> FitBlocks(const cv::Mat& disparity, int size, const PlaneFitOptions& options,
                                const BlockOptions& blocks,
                                const std::function<bool(int x, int y, int size)>& keep,
                                const cv::Mat& unbounded = cv::Mat());

/// Result of a ray query.
struct PatchHit {
  double distance_m = 0;  ///< along the unit ray direction
  int patch = -1;
};

/// The global map of patches. Queries: by ray (raytrace a pixel of any camera
/// into the map) and by footprint in a view (rasterize the map into a camera).
///
/// Spatial index: a bounding-volume hierarchy over the patches' boxes, built
/// lazily by the first query after a change, in O(N log N) for N patches.
/// A ray query then visits O(log N) nodes on typical (spread-out) maps
/// instead of testing every patch; the map changes in batches (one per
/// fixation), so the index is rebuilt once per batch. Rendering is
/// O(N + pixels covered). Const queries rebuild the index if needed, so a map
/// that has changed must not be queried from several threads at once; call
/// BuildIndex() first to share it.
class PatchMap {
 public:
  const std::vector<Patch>& patches() const { return patches_; }
  size_t size() const { return patches_.size(); }
  bool empty() const { return patches_.empty(); }
  const Patch& operator[](size_t i) const { return patches_[i]; }
  void Add(const Patch& patch);
  void Append(const PatchMap& other);
  void Clear();
  /// Sets patch i's Patch::hidden_in_reference, which no query reads: the
  /// spatial index stays valid.
  void SetHiddenInReference(size_t i, bool hidden) { patches_[i].hidden_in_reference = hidden; }
  /// Sets patch i's Patch::reference_part, which no query reads either.
  void SetReferencePart(size_t i, const Patch::Part& part) { patches_[i].reference_part = part; }
  /// Removes the patches whose flag is set (`drop` has one flag per patch);
  /// the others keep their order. Returns how many were removed.
  size_t Remove(const std::vector<char>& drop);
  /// Number of patches per PatchLevel (indexed by the enum's value).
  std::array<int, 3> CountByLevel() const;

  /// First patch hit by the ray from origin_W along direction_W (unit).
  std::optional<PatchHit> CastRay(const Eigen::Vector3d& origin_W,
                                  const Eigen::Vector3d& direction_W) const;
  /// The same query by testing every patch: the reference for the index.
  std::optional<PatchHit> CastRayBruteForce(const Eigen::Vector3d& origin_W,
                                            const Eigen::Vector3d& direction_W) const;

  /// Depths within this share of each other at a pixel are the same surface,
  /// and so are depths within kSameSurfaceSigmas combined standard deviations
  /// (SameSurface).
  static constexpr double kSameSurfaceShare = 0.02;
  static constexpr double kSameSurfaceSigmas = 3.0;
  /// Whether depths `za` and `zb` seen at one pixel by patches `a` and `b`
  /// belong to one surface.
  static bool SameSurface(double za, const Patch& a, double zb, const Patch& b);

  /// The map seen by a camera: planar depth (CV_32F, 0 where no patch) and
  /// the index of the patch seen per pixel (CV_32S, -1 where none), by
  /// z-buffered rasterization of every patch in front of the camera. Where
  /// patches are of the same surface (SameSurface), the one of the finest
  /// level is seen (finer data supersedes coarser), else the nearest. With a
  /// non-empty `region`, only its pixels are drawn (the same values there as
  /// the whole image's render; 0 and -1 elsewhere).
  void Render(const Eigen::Isometry3d& world_T_camera, const rig::CameraIntrinsics& intrinsics,
              cv::Mat* depth_m, cv::Mat* patch_ids, const cv::Rect& region = {}) const;

  /// Builds the index now if the map changed since it was last built.
  void BuildIndex() const;
  /// Nodes of the index (0 before it is built); for tests and figures.
  size_t IndexNodes() const { return nodes_.size(); }

 private:
  struct Node {
    Eigen::AlignedBox3d box;
    int left = -1, right = -1;  ///< children (inner node) or -1 (leaf)
    int first = 0, count = 0;   ///< leaf: range in order_
  };
  int BuildNode(int first, int count, std::vector<Eigen::AlignedBox3d>* boxes,
                std::vector<Eigen::Vector3d>* centres) const;

  std::vector<Patch> patches_;
  mutable std::vector<Node> nodes_;
  mutable std::vector<int> order_;
  mutable bool index_valid_ = false;
};

}  // namespace fovea
