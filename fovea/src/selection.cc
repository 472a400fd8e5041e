#include "fovea/selection.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "fovea/geometry.h"
#include "fovea/params.h"
#include "fovea/stats.h"

namespace fovea {

namespace {

// The map point at a pixel, from the view and the map's depth there.
Eigen::Vector3d PointAt(const SelectionContext& c, int x, int y) {
  return c.view.world_T_camera *
         (c.map_depth_m.at<float>(y, x) * c.view.intrinsics.Ray({double(x), double(y)}));
}

// Each pixel the map is silent at takes the depth of the nearest one it
// shows (SelectionContext::Make with fill_holes).
void FillHoles(SelectionContext* context) {
  SelectionContext& c = *context;
  const cv::Mat holes = c.map_depth_m <= 0;
  const int n_holes = cv::countNonZero(holes);
  if (n_holes == 0 || n_holes == static_cast<int>(holes.total())) return;
  // Each hole pixel gets the label of its nearest mapped (zero) pixel.
  cv::Mat distance, labels;
  cv::distanceTransform(holes, distance, labels, cv::DIST_L2, cv::DIST_MASK_5,
                        cv::DIST_LABEL_PIXEL);
  std::vector<float> depth_of_label(holes.total() + 1, 0.f);
  for (int y = 0; y < holes.rows; ++y)
    for (int x = 0; x < holes.cols; ++x)
      if (!holes.at<uchar>(y, x))
        depth_of_label[labels.at<int>(y, x)] = c.map_depth_m.at<float>(y, x);
  for (int y = 0; y < holes.rows; ++y)
    for (int x = 0; x < holes.cols; ++x)
      if (holes.at<uchar>(y, x))
        c.map_depth_m.at<float>(y, x) = depth_of_label[labels.at<int>(y, x)];
}

}  // namespace

SelectionContext SelectionContext::Make(const cv::Mat& image, const rig::CameraView& view,
                                        const PatchMap& map, bool fill_holes) {
  SelectionContext c;
  c.image = image;
  c.view = view;
  c.eye_W = view.world_T_camera;
  cv::Mat& ids = c.map_id;
  map.Render(view.world_T_camera, view.intrinsics, &c.map_depth_m, &ids);
  c.map_level = cv::Mat(ids.size(), CV_8S, cv::Scalar(-1));
  for (int y = 0; y < ids.rows; ++y) {
    const int* id = ids.ptr<int>(y);
    signed char* level = c.map_level.ptr<signed char>(y);
    for (int x = 0; x < ids.cols; ++x)
      if (id[x] >= 0) level[x] = static_cast<signed char>(map[id[x]].level);
  }
  if (fill_holes) FillHoles(&c);
  cv::Mat points(c.map_depth_m.size(), CV_64FC3, cv::Scalar::all(0));
  for (int y = 0; y < points.rows; ++y) {
    const float* depth = c.map_depth_m.ptr<float>(y);
    cv::Vec3d* point = points.ptr<cv::Vec3d>(y);
    for (int x = 0; x < points.cols; ++x)
      if (depth[x] > 0) {
        const Eigen::Vector3d p = PointAt(c, x, y);
        point[x] = cv::Vec3d(p.x(), p.y(), p.z());
      }
  }
  c.map_points_W = points;
  return c;
}

void NormalizeSum(cv::Mat* w) {
  const double s = cv::sum(*w)[0];
  if (s > 0) *w /= s;
}

cv::Mat GradientAttraction::Evaluate(const SelectionContext& c) const {
  // In single precision: a smooth attraction map needs no more than its 24
  // bits, and the blurs run on twice the lanes (issue 21).
  cv::Mat f, gx, gy;
  c.image.convertTo(f, CV_32F);
  cv::GaussianBlur(f, f, cv::Size(), sigma_);
  cv::Sobel(f, gx, CV_32F, 1, 0, 3, 1.0 / 8);
  cv::Sobel(f, gy, CV_32F, 0, 1, 3, 1.0 / 8);
  cv::Mat g(f.size(), CV_32F);
  for (int y = 0; y < g.rows; ++y) {
    const float *dx = gx.ptr<float>(y), *dy = gy.ptr<float>(y);
    float* e = g.ptr<float>(y);
    for (int x = 0; x < g.cols; ++x) e[x] = dx[x] * dx[x] + dy[x] * dy[x];
  }
  // Texture is a regional property: average the energy over a window.
  cv::GaussianBlur(g, g, cv::Size(), 2 * sigma_);
  // Saturate at the 80th percentile: every well-textured region attracts
  // alike, so that the strong contrast of an occluding edge does not hold
  // the eye on the edge fixation after fixation.
  std::vector<double> v(g.begin<float>(), g.end<float>());
  const double cap = NthSmallest(&v, v.size() * 8 / 10);
  if (cap > 0) cv::min(g, cap, g);
  cv::Mat w;
  g.convertTo(w, CV_64F);
  NormalizeSum(&w);
  return w;
}

void SelectionContext::SetRegion(const rig::CameraView& region_view, const PatchMap& map) {
  region = region_view;
  region_hidden = cv::Mat(map_id.size(), CV_8U, cv::Scalar(0));
  for (int y = 0; y < map_id.rows; ++y) {
    const int* id = map_id.ptr<int>(y);
    uchar* hidden = region_hidden.ptr<uchar>(y);
    for (int x = 0; x < map_id.cols; ++x) hidden[x] = id[x] >= 0 && map[id[x]].hidden_in_reference;
  }
}

Eigen::Vector3d SelectionContext::MapPoint(int x, int y) const {
  if (!map_points_W.empty()) {
    const cv::Vec3d& p = map_points_W.at<cv::Vec3d>(y, x);
    return {p[0], p[1], p[2]};
  }
  return PointAt(*this, x, y);
}

namespace {

// The pixels whose map point can lie within `r` of p_W: the bounding box of
// the images of the cube of half side r about p_W (a convex set's image lies
// in the hull of its corners' images), a pixel spare each side; the whole
// image when the cube reaches behind the camera or the lens distorts.
cv::Rect PixelsNear(const rig::CameraView& view, const Eigen::Vector3d& p_W, double r) {
  const rig::CameraIntrinsics& k = view.intrinsics;
  const cv::Rect image(0, 0, k.width_px, k.height_px);
  if (!k.distortion.empty()) return image;
  const Eigen::Isometry3d camera_T_world = view.world_T_camera.inverse();
  double u0 = std::numeric_limits<double>::infinity(), v0 = u0, u1 = -u0, v1 = -u0;
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d corner(i & 1 ? r : -r, i & 2 ? r : -r, i & 4 ? r : -r);
    const Eigen::Vector3d q = camera_T_world * (p_W + corner);
    if (q.z() <= 1e-6) return image;
    const double u = k.fx_px * q.x() / q.z() + k.cx_px, v = k.fy_px * q.y() / q.z() + k.cy_px;
    u0 = std::min(u0, u);
    u1 = std::max(u1, u);
    v0 = std::min(v0, v);
    v1 = std::max(v1, v);
  }
  auto clip = [](double x, int n) { return static_cast<int>(std::clamp(x, -1.0, n + 1.0)); };
  const cv::Point tl(clip(std::floor(u0) - 1, k.width_px), clip(std::floor(v0) - 1, k.height_px));
  const cv::Point br(clip(std::ceil(u1) + 2, k.width_px), clip(std::ceil(v1) + 2, k.height_px));
  return cv::Rect(tl, br) & image;
}

// Calls visit(x, y, r) for each pixel that PixelsNear(p_W, radius) gives,
// whose map point lies within `radius` of p_W (r its distance), unless
// done(x, y) says the pixel cannot change any more: the pixels one point can
// reach. O(box area) per point, so the cost grows with the points.
template <typename Visit, typename Done>
void ForPixelsNear(const SelectionContext& c, const Eigen::Vector3d& p_W, double radius,
                   Visit visit, Done done) {
  const cv::Rect box = PixelsNear(c.view, p_W, radius);
  for (int y = box.y; y < box.y + box.height; ++y)
    for (int x = box.x; x < box.x + box.width; ++x) {
      if (!(c.map_depth_m.at<float>(y, x) > 0) || done(x, y)) continue;
      const double r = (c.MapPoint(x, y) - p_W).norm();
      if (r < radius) visit(x, y, r);
    }
}
template <typename Visit>
void ForPixelsNear(const SelectionContext& c, const Eigen::Vector3d& p_W, double radius,
                   Visit visit) {
  ForPixelsNear(c, p_W, radius, visit, [](int, int) { return false; });
}

}  // namespace

double UniformDraw(std::mt19937_64* rng) { return static_cast<double>((*rng)() >> 11) * 0x1.0p-53; }

cv::Mat LocalSuppression::Evaluate(const SelectionContext& c) const {
  // Every settled point, and each point aimed at where the servo settled
  // farther than the revisit radius from it.
  std::vector<Eigen::Vector3d> points;
  for (const SelectionContext::Visit& v : c.visits) {
    points.push_back(v.settled_W);
    if ((v.aimed_W - v.settled_W).norm() > revisit_) points.push_back(v.aimed_W);
  }
  cv::Mat w(c.map_level.size(), CV_64F, cv::Scalar(1.0));
  for (int y = 0; y < w.rows; ++y) {
    const signed char* level = c.map_level.ptr<signed char>(y);
    double* wp = w.ptr<double>(y);
    for (int x = 0; x < w.cols; ++x) {
      if (level[x] == static_cast<signed char>(PatchLevel::kFoveal)) wp[x] = low_;
      if (level[x] == static_cast<signed char>(PatchLevel::kPeripheral)) wp[x] = peripheral_;
    }
  }
  if (hole_width_ > 0) {
    // A hole pixel's distance to the nearest mapped pixel (the image's edge
    // is not mapped data: a hole reaching it is as wide as it is inside).
    const cv::Mat holes = c.map_level < 0;
    const int n_holes = cv::countNonZero(holes);
    if (n_holes > 0 && n_holes < static_cast<int>(holes.total())) {
      cv::Mat distance;
      cv::distanceTransform(holes, distance, cv::DIST_L2, cv::DIST_MASK_5);
      for (int y = 0; y < w.rows; ++y) {
        const signed char* level = c.map_level.ptr<signed char>(y);
        const float* d = distance.ptr<float>(y);
        double* wp = w.ptr<double>(y);
        for (int x = 0; x < w.cols; ++x)
          if (level[x] < 0)
            wp[x] = hole_edge_ + (hole_inside_ - hole_edge_) * std::min(1.0, d[x] / hole_width_);
      }
    }
  }
  // Each point suppresses only the pixels whose map points lie within the
  // radius: visiting just the pixels it can reach keeps the cost per
  // fixation from growing with the fixations made (0 within the revisit
  // radius of any point, else at most low_ within the radius of any; the
  // order of the points does not matter).
  const double reach = std::max(radius_, revisit_);
  for (const Eigen::Vector3d& f : points)
    ForPixelsNear(
        c, f, reach,
        [&](int x, int y, double r) {
          double& wp = w.at<double>(y, x);
          if (r < revisit_)
            wp = 0;
          else if (r < radius_)
            wp = std::min(wp, low_);
        },
        // 0 stays 0 (the weights are not negative).
        [&](int x, int y) { return w.at<double>(y, x) == 0; });
  NormalizeSum(&w);
  return w;
}

cv::Mat Proximity2D::Evaluate(const SelectionContext& c) const {
  const double cx = c.gaze_px ? c.gaze_px->x() : c.view.intrinsics.cx_px;
  const double cy = c.gaze_px ? c.gaze_px->y() : c.view.intrinsics.cy_px;
  const std::lock_guard<std::mutex> lock(mutex_);
  if (weights_.size() != c.image.size() || cx_ != cx || cy_ != cy) {
    cv::Mat w(c.image.size(), CV_64F);
    for (int y = 0; y < w.rows; ++y)
      for (int x = 0; x < w.cols; ++x)
        w.at<double>(y, x) = std::exp(-std::hypot(x - cx, y - cy) / scale_);
    NormalizeSum(&w);
    weights_ = w;
    cx_ = cx;
    cy_ = cy;
  }
  return weights_.clone();
}

cv::Mat Proximity3D::Evaluate(const SelectionContext& c) const {
  cv::Mat w(c.map_depth_m.size(), CV_64F, cv::Scalar(1.0));
  if (c.has_fixation) {
    const double lo = c.fixation_depth_m - c.z_t_near_m, hi = c.fixation_depth_m + c.z_t_far_m;
    for (int y = 0; y < w.rows; ++y)
      for (int x = 0; x < w.cols; ++x) {
        const float z = c.map_depth_m.at<float>(y, x);
        if (!(z > 0 && z >= lo && z <= hi)) w.at<double>(y, x) = low_;
      }
  }
  NormalizeSum(&w);
  return w;
}

bool SelectionOptions::FallsBack() const {
  const std::string rule = Strategy();
  return reference_fallback != "none" && (rule == "fovea" || rule == "deterministic") &&
         view == "current";
}

void SelectionOptions::Check() const {
  rig::CheckParam(params::kSelectionStrategy, strategy);
  rig::CheckParam(params::kSelectionFirstFixation, first_fixation);
  rig::CheckParam(params::kSelectionView, view);
  rig::CheckParam(params::kSelectionReferenceFallback, reference_fallback);
  if (deterministic && strategy != "fovea" && strategy != "deterministic")
    throw rig::InputError("key 'selection.deterministic': true applies to strategy fovea, not '" +
                          strategy + "'");
  rig::CheckParam(params::kSelectionFoveaSizePx, fovea_size_px);
  rig::CheckParam(params::kSelectionMotionWeight, motion_weight);
  rig::CheckParam(params::kSelectionHalfKnownRelSigma, half_known_rel_sigma);
  rig::CheckParam(params::kSelectionDrawScale, draw_scale);
  rig::CheckParam(params::kSelectionHistogramBins, histogram_bins);
  rig::CheckParam(params::kSelectionBorderPx, border_px);
  rig::CheckParam(params::kSelectionResolutionLevel, resolution_level);
  rig::CheckParam(params::kSelectionRefusedRadiusM, refused_radius_m);
}

void CriteriaOptions::Check() const {
  rig::CheckParam(params::kCriteriaGradientBlurPx, gradient_blur_px);
  rig::CheckParam(params::kCriteriaSuppressedWeight, suppressed_weight);
  rig::CheckParam(params::kCriteriaSuppressionRadiusM, suppression_radius_m);
  rig::CheckParam(params::kCriteriaPeripheralWeight, peripheral_weight);
  rig::CheckParam(params::kCriteriaRevisitRadiusM, revisit_radius_m);
  rig::CheckParam(params::kCriteriaHoleWidthPx, hole_width_px);
  rig::CheckParam(params::kCriteriaHoleEdgeWeight, hole_edge_weight);
  rig::CheckParam(params::kCriteriaHoleInsideWeight, hole_inside_weight);
  rig::CheckParam(params::kCriteriaProximity2dScalePx, proximity_2d_scale_px);
  rig::CheckParam(params::kCriteriaProximity3dLow, proximity_3d_low);
}

std::vector<std::shared_ptr<const FixationCriterion>> CriteriaOptions::Make() const {
  std::vector<std::shared_ptr<const FixationCriterion>> c;
  if (gradient) c.push_back(std::make_shared<GradientAttraction>(*this));
  if (suppression) c.push_back(std::make_shared<LocalSuppression>(*this));
  if (proximity_2d) c.push_back(std::make_shared<Proximity2D>(*this));
  if (proximity_3d) c.push_back(std::make_shared<Proximity3D>(*this));
  return c;
}

FixationSelector::FixationSelector(std::vector<std::shared_ptr<const FixationCriterion>> criteria,
                                   const SelectionOptions& options)
    : criteria_(std::move(criteria)), options_(options) {
  options_.Check();
}

cv::Mat Candidates(const SelectionContext& c, const std::vector<Eigen::Vector3d>& refused_W,
                   const SelectionOptions& options) {
  cv::Mat candidates(c.map_depth_m.size(), CV_8U, cv::Scalar(0));
  const int b = options.border_px;
  // The region camera's inverse pose once, not per pixel.
  const Eigen::Isometry3d region_T_world =
      c.region ? c.region->world_T_camera.inverse() : Eigen::Isometry3d::Identity();
  for (int y = b; y < candidates.rows - b; ++y) {
    const float* depth = c.map_depth_m.ptr<float>(y);
    uchar* candidate = candidates.ptr<uchar>(y);
    for (int x = b; x < candidates.cols - b; ++x) {
      if (!(depth[x] > 0)) continue;
      if (c.region) {
        if (!c.region_hidden.empty() && c.region_hidden.at<uchar>(y, x)) continue;
        const auto& k = c.region->intrinsics;
        const auto uv = ProjectIntoCamera(region_T_world, k, c.MapPoint(x, y));
        if (!uv || uv->x() < b || uv->y() < b || uv->x() > k.width_px - 1 - b ||
            uv->y() > k.height_px - 1 - b)
          continue;
      }
      candidate[x] = 255;
    }
  }
  ClearNear(c, refused_W, options.refused_radius_m, &candidates);
  return candidates;
}

void ClearNear(const SelectionContext& c, const std::vector<Eigen::Vector3d>& points_W,
               double radius_m, cv::Mat* candidates) {
  for (const Eigen::Vector3d& p : points_W)
    ForPixelsNear(c, p, radius_m, [&](int x, int y, double) { candidates->at<uchar>(y, x) = 0; });
}

void CapNear(const SelectionContext& c, const std::vector<Eigen::Vector3d>& points_W,
             double radius_m, float cap, cv::Mat* weights) {
  for (const Eigen::Vector3d& p : points_W)
    ForPixelsNear(c, p, radius_m, [&](int x, int y, double) {
      float& w = weights->at<float>(y, x);
      w = std::min(w, cap);
    });
}

FixationSelector::Weights FixationSelector::Weigh(const SelectionContext& c) const {
  Weights w;
  w.product = cv::Mat(c.image.size(), CV_64F, cv::Scalar(1.0));
  for (const auto& criterion : criteria_) {
    w.each.push_back(criterion->Evaluate(c));
    w.product = w.product.mul(w.each.back());
  }
  w.candidates = Candidates(c, {}, options_);
  return w;
}

cv::Mat FixationSelector::Composite(const SelectionContext& c, const Weights& w,
                                    const std::vector<Eigen::Vector3d>& refused_W) const {
  // Only the candidates: pixels the map can raytrace, away from the border
  // and from refused points.
  cv::Mat candidates = w.candidates.clone();
  ClearNear(c, refused_W, options_.refused_radius_m, &candidates);
  cv::Mat composite = w.product.clone();
  composite.setTo(0.0, candidates == 0);
  NormalizeSum(&composite);
  return composite;
}

void AtResolutionLevel(int level, SelectionOptions* selection, CriteriaOptions* criteria) {
  const double s = std::ldexp(1.0, -level);
  auto scaled = [&](int px, double smallest) {
    return static_cast<int>(std::max(smallest, std::round(px * s)));
  };
  selection->border_px = scaled(selection->border_px, params::kSelectionBorderPx.lo);
  selection->fovea_size_px = scaled(selection->fovea_size_px, params::kSelectionFoveaSizePx.lo);
  criteria->gradient_blur_px *= s;
  criteria->proximity_2d_scale_px *= s;
  criteria->hole_width_px *= s;
}

rig::CameraView ReducedView(const rig::CameraView& view, int level) {
  rig::CameraView reduced = view;
  const double s = std::ldexp(1.0, -level);
  rig::CameraIntrinsics& k = reduced.intrinsics;
  k.width_px = view.intrinsics.width_px >> level;
  k.height_px = view.intrinsics.height_px >> level;
  k.fx_px *= s;
  k.fy_px *= s;
  k.cx_px = (view.intrinsics.cx_px + 0.5) * s - 0.5;
  k.cy_px = (view.intrinsics.cy_px + 0.5) * s - 0.5;
  if (!view.gray.empty())
    cv::resize(view.gray, reduced.gray, cv::Size(k.width_px, k.height_px), 0, 0, cv::INTER_AREA);
  reduced.bgr.release();
  return reduced;
}

Eigen::Vector2d FullResolutionPixel(const Eigen::Vector2d& pixel, int level) {
  const double n = std::ldexp(1.0, level);
  return (pixel.array() + 0.5) * n - 0.5;
}

double DrawExponential(double r, double s) {
  // CDF F(u) = (1 - exp(-u / s)) / (1 - exp(-1 / s)) on [0, 1].
  return -s * std::log1p(-r * (1 - std::exp(-1 / s)));
}

SelectionSummary FixationSelector::Choose(const SelectionContext& c, const PatchMap& map,
                                          const std::vector<Eigen::Vector3d>& refused_W,
                                          std::mt19937_64* rng) const {
  return Choose(c, Weigh(c), map, refused_W, rng);
}

SelectionSummary FixationSelector::Choose(const SelectionContext& c, const Weights& weights,
                                          const PatchMap& map,
                                          const std::vector<Eigen::Vector3d>& refused_W,
                                          std::mt19937_64* rng) const {
  SelectionSummary s;
  const std::vector<cv::Mat>& each = weights.each;
  const cv::Mat composite = Composite(c, weights, refused_W);
  double c_max = 0;
  cv::minMaxLoc(composite, nullptr, &c_max);
  s.composite_max = c_max;
  s.candidates = cv::countNonZero(composite > 0);
  if (c_max <= 0) {
    s.why = kNoCandidate;
    return s;
  }
  const double cx = c.view.intrinsics.cx_px, cy = c.view.intrinsics.cy_px;
  auto centre_dist = [&](int x, int y) { return std::hypot(x - cx, y - cy); };
  const int bins = options_.histogram_bins;
  auto bin_of = [&](double v) { return std::min(bins - 1, static_cast<int>(v / c_max * bins)); };
  int chosen_bin;
  const bool deterministic = options_.Strategy() == "deterministic";
  if (deterministic) {
    chosen_bin = bins - 1;
    s.drawn_value = c_max;
  } else {
    const double r = UniformDraw(rng);
    s.drawn_value = c_max * (1 - DrawExponential(r, options_.draw_scale));
    std::vector<int> count(bins, 0);
    for (int y = 0; y < composite.rows; ++y)
      for (int x = 0; x < composite.cols; ++x) {
        const double v = composite.at<double>(y, x);
        if (v > 0) ++count[bin_of(v)];
      }
    const int target = bin_of(s.drawn_value);
    chosen_bin = -1;
    for (int d = 0; d < bins && chosen_bin < 0; ++d) {
      if (target + d < bins && count[target + d] > 0)
        chosen_bin = target + d;
      else if (target - d >= 0 && count[target - d] > 0)
        chosen_bin = target - d;
    }
  }
  s.bin = chosen_bin;
  // In deterministic mode, the maximum itself; otherwise the bin's pixel
  // nearest the image centre.
  int bx = -1, by = -1;
  double best_value = -1, best_dist = std::numeric_limits<double>::infinity();
  for (int y = 0; y < composite.rows; ++y)
    for (int x = 0; x < composite.cols; ++x) {
      const double v = composite.at<double>(y, x);
      // Only pixels that can win need their distance from the centre.
      if (v <= 0 || (deterministic ? v < best_value : bin_of(v) != chosen_bin)) continue;
      const double d = centre_dist(x, y);
      const bool better = deterministic ? (v > best_value || d < best_dist) : d < best_dist;
      if (better) best_value = v, best_dist = d, bx = x, by = y;
    }
  s.composite_chosen = composite.at<double>(by, bx);
  AimAt(c, map, bx, by, &s);
  if (!s.ok) return s;
  const cv::Mat candidates = composite > 0;
  for (size_t i = 0; i < criteria_.size(); ++i) {
    const double mean = cv::mean(each[i], candidates)[0];
    s.criteria.emplace_back(criteria_[i]->Name(),
                            mean > 0 ? each[i].at<double>(by, bx) / mean : 0.0);
  }
  return s;
}

void AimAt(const SelectionContext& c, const PatchMap& map, int x, int y, SelectionSummary* s) {
  s->pixel = Eigen::Vector2d(x, y);
  const Ray ray = PixelRay(c.view.world_T_camera, c.view.intrinsics, s->pixel);
  const auto hit = map.CastRay(ray.origin_W, ray.direction_W);
  if (hit) {
    s->point_W = ray.origin_W + hit->distance_m * ray.direction_W;
  } else if (c.map_level.at<signed char>(y, x) < 0) {
    // A hole the context filled (see SelectionContext::Make): its guessed depth.
    s->point_W = c.MapPoint(x, y);
    s->in_hole = true;
  } else {
    s->why = "the chosen pixel's ray misses the map";
    return;
  }
  s->ok = true;
}

std::string SelectionOptions::Strategy() const {
  return deterministic ? "deterministic" : strategy;
}

}  // namespace fovea
