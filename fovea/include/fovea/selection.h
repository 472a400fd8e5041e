// Choosing the next fixation (paper section IV; design note "DDR"): separate,
// swappable criteria over the pixels of the current left view, each
// normalized to sum 1; their product; a histogram of it, an exponential draw
// that favours high values, the pixel nearest the image centre in the drawn
// bin, raytraced into the map for the 3D point.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <mutex>
#include <opencv2/core.hpp>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "fovea/patch.h"
#include "rig/types.h"

namespace fovea {

/// What the criteria may look at.
struct SelectionContext {
  cv::Mat image;         ///< current left view, CV_8UC1
  rig::CameraView view;  ///< its camera
  /// The map rendered into the view (CV_32F, 0 = none). With hole filling,
  /// pixels the map is silent at carry the depth of the nearest mapped pixel
  /// (map_level stays -1 there).
  cv::Mat map_depth_m;
  cv::Mat map_level;  ///< CV_8S: PatchLevel of the patch seen, -1 = none
  cv::Mat map_id;     ///< CV_32S: index in the map of the patch seen, -1 = none
  /// The current left camera's pose: where the rig looks from now, which
  /// motion costs are measured from (the view's own pose unless the choice
  /// is made in another view).
  Eigen::Isometry3d eye_W = Eigen::Isometry3d::Identity();
  bool has_fixation = false;             ///< false before the first vergent fixation
  double fixation_depth_m = 0;           ///< depth of the current fixation point in the view
  double z_t_near_m = 0, z_t_far_m = 0;  ///< the current fovea's depth band (Z_T)
  /// An earlier fixation: where the servo settled, and the point aimed at
  /// (which stays unmapped when the servo settled elsewhere: a hole's
  /// guessed depth, a false match).
  struct Visit {
    Eigen::Vector3d settled_W, aimed_W;
  };
  std::vector<Visit> visits;
  /// Where 2D proximity is measured from, in this view's pixels: the
  /// image's principal point when unset (the current view, whose centre is
  /// where the eye looks), the current fixation point's image when the
  /// choice is made in another view.
  std::optional<Eigen::Vector2d> gaze_px;
  /// If set, only points that this view sees (the IDR view: the region the
  /// run maps) are candidates.
  std::optional<rig::CameraView> region;
  /// CV_8U, this view's size (SetRegion makes it): non-zero where the
  /// patch seen is one the reference camera does not see
  /// (Patch::hidden_in_reference: a surface seen past a nearer one's edge
  /// from where the rig stands now). No candidate: a fixation there maps
  /// nothing the run's view shows. Empty: no such test.
  cv::Mat region_hidden;

  /// Sets `region` to `region_view` and region_hidden from `map` (the one
  /// this context was made of: map_id indexes it).
  void SetRegion(const rig::CameraView& region_view, const PatchMap& map);

  /// MapPoint at every pixel with map_depth_m > 0 (CV_64FC3, world
  /// frame), made once by Make: local suppression and the refused points
  /// visit a box of pixels about each earlier point, every attempt.
  cv::Mat map_points_W;

  /// The map point seen at a pixel (requires map_depth_m > 0 there).
  Eigen::Vector3d MapPoint(int x, int y) const;

  /// Renders `map` into `view` and fills map_depth_m and map_level. With
  /// `fill_holes`, pixels the map is silent at take the depth of the nearest
  /// pixel it shows (Euclidean distance in the image), so that the unmapped
  /// parts of the view can be fixated: the servo then finds their depth.
  static SelectionContext Make(const cv::Mat& image, const rig::CameraView& view,
                               const PatchMap& map, bool fill_holes = false);
};

class FixationCriterion;

/// Which criteria the selector multiplies (all on: the paper's rule) and
/// their settings (fovea/params.h, "criteria.").
struct CriteriaOptions {
  bool gradient = true;
  bool suppression = true;
  bool proximity_2d = true;
  bool proximity_3d = true;
  double gradient_blur_px = 2.0;
  double suppressed_weight = 0.02;     ///< local suppression's weight on foveal data
  double suppression_radius_m = 0.08;  ///< and within this distance of an earlier fixation
  double peripheral_weight = 0.3;      ///< local suppression's weight on peripheral data (paper: 1)
  /// Local suppression's weight is 0 this close to an earlier fixation point.
  double revisit_radius_m = 0.03;
  /// Beyond the paper: local suppression's weight on a hole (a pixel the map
  /// is silent at) goes from hole_edge_weight at the hole's edge (beside
  /// mapped data) to hole_inside_weight this far inside it, pixels (the
  /// pixel's distance to the nearest mapped pixel), linearly, and stays
  /// there further in. 0: every hole weighs 1 (the paper's rule).
  /// Measured and not kept, both ways (README, "The map's trust").
  double hole_width_px = 0;
  double hole_edge_weight = 0.3;
  double hole_inside_weight = 1;
  double proximity_2d_scale_px = 320;
  double proximity_3d_low = 0.1;  ///< 3D proximity's weight outside the Z_T band
  void Check() const;             ///< throws rig::InputError naming the key (fovea/params.h)
  /// The criteria switched on, each with its settings from here.
  std::vector<std::shared_ptr<const FixationCriterion>> Make() const;
};

/// One criterion: a non-negative weight per pixel (CV_64F, the view's size)
/// that sums to 1 over the image (or is all zero if nothing qualifies).
class FixationCriterion {
 public:
  virtual ~FixationCriterion() = default;
  virtual std::string Name() const = 0;
  virtual cv::Mat Evaluate(const SelectionContext& context) const = 0;
};

/// Squared gradient magnitude (after a Gaussian blur of `blur_sigma_px`, and
/// averaged over a window of the same scale): attracts the eye to texture.
class GradientAttraction : public FixationCriterion {
 public:
  explicit GradientAttraction(const CriteriaOptions& o) : sigma_(o.gradient_blur_px) {}
  std::string Name() const override { return "gradient"; }
  cv::Mat Evaluate(const SelectionContext& context) const override;

 private:
  double sigma_;
};

/// Low weight where the map already holds foveal data or lies within
/// `suppression_radius_m` of an earlier fixation point (a fixation whose fovea yielded
/// no patches, at a depth edge say, must not attract the eye forever), high
/// elsewhere. Beyond the paper, `peripheral_weight` grades the suppression:
/// the weight where the map holds peripheral data (1 = the paper's rule, which
/// suppresses foveal data only), so that the eye prefers what is mapped
/// coarsely or not at all. Within `revisit_radius_m` of an earlier fixation
/// point the weight is 0: the scene is static, and a second look at the same
/// point from the same rig sees what the first saw (a fixation at a depth
/// edge, whose fovea yields nothing, kept drawing the eye back with any
/// weight above 0). With `hole_width_px` set, a hole's weight grades from
/// hole_edge_weight at its edge to hole_inside_weight that far inside it.
class LocalSuppression : public FixationCriterion {
 public:
  explicit LocalSuppression(const CriteriaOptions& o)
      : low_(o.suppressed_weight),
        radius_(o.suppression_radius_m),
        peripheral_(o.peripheral_weight),
        revisit_(o.revisit_radius_m),
        hole_width_(o.hole_width_px),
        hole_edge_(o.hole_edge_weight),
        hole_inside_(o.hole_inside_weight) {}
  std::string Name() const override { return "suppression"; }
  cv::Mat Evaluate(const SelectionContext& context) const override;

 private:
  double low_, radius_, peripheral_, revisit_, hole_width_, hole_edge_, hole_inside_;
};

/// exp(-r / s), r the distance from the image centre in pixels.
class Proximity2D : public FixationCriterion {
 public:
  explicit Proximity2D(const CriteriaOptions& o) : scale_(o.proximity_2d_scale_px) {}
  std::string Name() const override { return "proximity_2d"; }
  cv::Mat Evaluate(const SelectionContext& context) const override;

 private:
  double scale_;
  // The weights depend only on the image's size and principal point: made
  // once (an exp and a hypot per pixel), then copied.
  mutable std::mutex mutex_;
  mutable cv::Mat weights_;
  mutable double cx_ = 0, cy_ = 0;
};

/// Two levels: high where the map depth lies within the current fixation's
/// Z_T band, low elsewhere (uniform before the first vergent fixation).
class Proximity3D : public FixationCriterion {
 public:
  explicit Proximity3D(const CriteriaOptions& o) : low_(o.proximity_3d_low) {}
  std::string Name() const override { return "proximity_3d"; }
  cv::Mat Evaluate(const SelectionContext& context) const override;

 private:
  double low_;
};

/// Divides by the sum (leaves an all-zero image as it is).
void NormalizeSum(cv::Mat* weights);

struct SelectionOptions {
  /// Which rule chooses (MakeStrategy): "fovea" (the paper's composite and
  /// exponential draw), "deterministic", "random", "raster",
  /// "next_best_view".
  std::string strategy = "fovea";
  /// Always take the maximum of the composite: the same as strategy
  /// "deterministic" (kept for the configurations that set it).
  bool deterministic = false;
  /// How the first fixation is chosen: "ddr" (by the strategy, in IDR's
  /// final view, as the paper does) or "idr" (IDR's well-supported patch
  /// nearest the view's centre).
  std::string first_fixation = "ddr";
  /// Where the composite rules choose: "current" (the current left view,
  /// the paper's) or "reference" (IDR's final left view: the region the run
  /// maps, fixed from one fixation to the next, so that what is unmapped
  /// there stays in reach however far the last fixation turned the
  /// cameras; 2D proximity is then measured from the current fixation
  /// point's image in it).
  std::string view = "current";
  /// Beyond the paper, for the composite rules in the current view: when
  /// their choice there after the first fixation is mapped data ("mapped"),
  /// foveal data ("foveal": the current view holds nothing better), or
  /// mapped data after a fixation that raised the map's share of the
  /// reference view by less than kStalledGrowth ("stalled": the current view
  /// has stopped paying), they choose again in the reference view, and a
  /// hole chosen there is taken instead (what is unmapped in the region the
  /// run maps may lie outside the current view); "none": never. It applies
  /// to the composite rules in the current view only (FallsBack).
  /// "stalled": over the accuracy benchmark's 42 runs it raised good
  /// coverage and, with IntegrationOptions::reference_flank_px, kept every
  /// accuracy figure (README, "The map's trust").
  std::string reference_fallback = "stalled";
  /// reference_fallback "stalled": a fixation that raised the map's share of
  /// the reference view by less than this (a share of its pixels) stalled.
  static constexpr double kStalledGrowth = 0.002;
  double draw_scale = 0.5;  ///< s of the exponential draw
  int histogram_bins = 64;
  int border_px = 16;  ///< candidates keep this far from the image edge
  /// Beyond the paper: the criteria are weighed on the view reduced
  /// 2^resolution_level times in each direction (the chosen pixel is the
  /// centre of its block at full resolution; 0 = the paper's full
  /// resolution). The criteria are smooth over many pixels, and a choice at
  /// full resolution cost 40% of a fixation's compute (README). Pixel sizes
  /// here and in CriteriaOptions stay in full-resolution pixels
  /// (AtResolutionLevel).
  int resolution_level = 1;
  /// Candidates whose map point lies within this distance of a point that
  /// could not be fixated are left out.
  double refused_radius_m = 0.03;
  /// The fovea's size in the view, pixels: raster's cell and
  /// next_best_view's window.
  int fovea_size_px = 128;
  /// next_best_view: information given up per radian the left camera turns.
  double motion_weight = 0.5;
  /// next_best_view: a mapped pixel whose depth sigma is this share of its
  /// depth counts as half unknown.
  double half_known_rel_sigma = 0.002;
  void Check() const;  ///< throws rig::InputError naming the key (fovea/params.h)
  /// The strategy in force: "deterministic" when `deterministic` is set.
  std::string Strategy() const;
  /// Whether reference_fallback is in force: set, with a composite rule
  /// choosing in the current view. The other strategies, and the composite
  /// rules with view "reference", choose in the reference view already:
  /// there is no choice in the current view for a fallback to replace.
  bool FallsBack() const;
};

/// The options for choosing in a view reduced 2^level times: their pixel
/// sizes (the border, the fovea's size, the gradient's blur and 2D
/// proximity's scale, local suppression's hole width) divided by 2^level,
/// the integer ones rounded and kept at least their smallest allowed value.
void AtResolutionLevel(int level, SelectionOptions* selection, CriteriaOptions* criteria);

/// `view` reduced 2^level times in each direction: the same rays through
/// the centres of its blocks of 2^level x 2^level pixels (the image size
/// rounded down). The lens's distortion, in normalized coordinates, stays.
rig::CameraView ReducedView(const rig::CameraView& view, int level);

/// A pixel of the view ReducedView(view, level) as the full-resolution
/// pixel at the centre of its block.
Eigen::Vector2d FullResolutionPixel(const Eigen::Vector2d& pixel, int level);

/// What one choice looked like, for the records.
struct SelectionSummary {
  bool ok = false;
  std::string why;  ///< when not ok
  Eigen::Vector2d pixel = Eigen::Vector2d::Zero();
  Eigen::Vector3d point_W = Eigen::Vector3d::Zero();
  bool in_hole = false;  ///< the pixel showed no map data: point_W is a guess
  /// Chosen in the reference view by selection.reference_fallback (`pixel`
  /// is that view's).
  bool in_reference = false;
  int prescreened = 0;  ///< holes passed over before this choice (FoveaOptions::prescreen_holes)
  int candidates = 0;   ///< pixels with a map point
  double composite_max = 0, composite_chosen = 0;
  double drawn_value = 0;  ///< c drawn from the exponential density
  int bin = -1;
  /// Per criterion: its name, its value at the chosen pixel relative to its
  /// mean over the candidates (1 = average, > 1 = favoured).
  std::vector<std::pair<std::string, double>> criteria;
};

/// Why a strategy chose nothing when no pixel is a candidate.
inline constexpr char kNoCandidate[] =
    "no candidate pixel: the map shows nothing in view that may be fixated";

/// A draw in [0, 1) from 53 random bits: the same on every platform, unlike
/// the standard distributions.
double UniformDraw(std::mt19937_64* rng);

/// The pixels a strategy may choose (CV_8U, 255 = candidate): those the map
/// can raytrace (map_depth_m > 0, filled holes included), at least
/// `options.border_px` from the edge, inside `context.region` if it is set
/// and not on a patch context.region_hidden marks, and farther than
/// `options.refused_radius_m` from every refused point.
cv::Mat Candidates(const SelectionContext& context, const std::vector<Eigen::Vector3d>& refused_W,
                   const SelectionOptions& options);

/// Clears the candidates whose map point lies within `radius_m` of any of
/// `points_W`, visiting only the pixels each can reach.
void ClearNear(const SelectionContext& context, const std::vector<Eigen::Vector3d>& points_W,
               double radius_m, cv::Mat* candidates);

/// Caps at `cap` the weights (CV_32F) of the pixels whose map point lies
/// within `radius_m` of any of `points_W`, visiting only the pixels each can
/// reach.
void CapNear(const SelectionContext& context, const std::vector<Eigen::Vector3d>& points_W,
             double radius_m, float cap, cv::Mat* weights);

/// Completes a choice of pixel (x, y): the point its ray meets in the map (or,
/// in a hole the context filled, the hole's guessed depth) and ok; or why not.
void AimAt(const SelectionContext& context, const PatchMap& map, int x, int y,
           SelectionSummary* summary);

/// The composite selection rule over a set of criteria. All randomness comes
/// from the generator passed in.
class FixationSelector {
 public:
  FixationSelector(std::vector<std::shared_ptr<const FixationCriterion>> criteria,
                   const SelectionOptions& options);

  /// What a choice computes from its context alone: choosing again in the
  /// same context with more refused points (the loop's prescreen of holes)
  /// reuses it, and only the refused points' neighbourhoods are cleared
  /// anew.
  struct Weights {
    std::vector<cv::Mat> each;  ///< each criterion's weights (CV_64F)
    cv::Mat product;            ///< their product, in the criteria's order
    cv::Mat candidates;         ///< Candidates with no refused point
  };
  Weights Weigh(const SelectionContext& context) const;

  /// Product of the criteria (the context's weights), normalized, zero
  /// where the map has no point, near the border or near a refused point.
  cv::Mat Composite(const SelectionContext& context, const Weights& weights,
                    const std::vector<Eigen::Vector3d>& refused_W) const;

  /// Draws the next fixation point.
  SelectionSummary Choose(const SelectionContext& context, const PatchMap& map,
                          const std::vector<Eigen::Vector3d>& refused_W,
                          std::mt19937_64* rng) const;
  /// The same from the context's weights (Weigh(context)).
  SelectionSummary Choose(const SelectionContext& context, const Weights& weights,
                          const PatchMap& map, const std::vector<Eigen::Vector3d>& refused_W,
                          std::mt19937_64* rng) const;

  const std::vector<std::shared_ptr<const FixationCriterion>>& criteria() const {
    return criteria_;
  }

 private:
  std::vector<std::shared_ptr<const FixationCriterion>> criteria_;
  SelectionOptions options_;
};

/// The exponential draw of the design note: u in [0, 1] with density
/// proportional to exp(-u / s), by inverting its CDF at r in [0, 1); the
/// value drawn is c_max (1 - u).
double DrawExponential(double r, double scale);

}  // namespace fovea
