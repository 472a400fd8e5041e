#include "fovea/foveal.h"

#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <utility>

#include "fovea/geometry.h"
#include "fovea/parallel.h"
#include "fovea/params.h"
#include "fovea/timing.h"
#include "rig/left_pair.h"

namespace fovea {

void FovealOptions::Check() const {
  tessellation.Check();
  rig::CheckParam(params::kFovealFoveaPatchPx, fovea_patch_px);
  rig::CheckParam(params::kFovealPeripheryPatchPx, periphery_patch_px);
  rig::CheckParam(params::kFovealMapMarginPx, map_margin_px);
  rig::CheckParam(params::kFovealCoarseMarginPx, coarse_margin_px);
  rig::CheckParam(params::kFovealSilentConfidence, silent_confidence);
  rig::CheckParam(params::kFovealSilentCheckLevel, silent_check_level);
  rig::CheckParam(params::kFovealEdgeErosionPx, edge_erosion_px);
  rig::CheckParam(params::kFovealFoveaEdgeErosionPx, fovea_edge_erosion_px);
  rig::CheckParam(params::kFovealEdgeJumpPx, edge_jump_px);
  rig::CheckParam(params::kFovealEdgeHolePx, edge_hole_px);
  rig::CheckParam(params::kFovealMinFillShare, blocks.min_fill_share);
  rig::CheckParam(params::kFovealMinBlockPx, blocks.min_block_px);
  rig::CheckParam(params::kFovealPeripheryMinBlockPx, periphery_min_block_px);
  rig::CheckParam(params::kFovealPeripheryHalfAgreement, periphery_half_agreement);
  plane_fit.Check(params::kFovealFitMinSupport, params::kFovealFitTolerancePx,
                  params::kFovealFitMinInlierShare);
  // Set from idr.z_min_m (ResolvedFixationOptions), not a parameter of its own.
  if (!(silent_near_m >= 0)) throw rig::InputError("foveal options: silent_near_m must be >= 0");
  rig::CheckParam(params::kFovealSkipFovealEdgePx, skip_foveal_edge_px);
  rig::CheckParam(params::kFovealMaxViewAngleDeg, max_view_angle_deg);
  rig::CheckParam(params::kFovealRectifiedSilentConfidence, rectified_silent_confidence);
}

void FixationOptions::Check() const {
  vergence.Check();
  servo.Check();
  foveal.Check();
  rig::CheckParam(params::kFovealBaselineM, baseline_m);
  rig::CheckParam(params::kFovealMappedBaselineM, mapped_baseline_m);
  // Set from idr.z_min_m (ResolvedFixationOptions), not a parameter of its own.
  if (!(min_depth_m >= 0)) throw rig::InputError("fixation options: min_depth_m must be >= 0");
}

namespace {

// One resolution level of the tessellation: its images and geometry.
struct Level {
  int index = 0;
  double scale = 1;  ///< full-resolution pixels per level pixel
  cv::Mat left, right;
  cv::Rect rect;  ///< full-resolution pixels it covers
};

// Level `index` of the tessellation; `octave` (default: the level's own)
// sets the resolution, 2^octave full-resolution pixels per pixel.
Level MakeLevel(const rig::StereoFrame& frame, const Tessellation& t, int index, int octave = -1) {
  Level l;
  l.index = index;
  if (octave < 0) octave = index;
  l.scale = std::pow(2.0, octave);
  l.rect = t.rects[index];
  if (octave == 0) {
    l.left = frame.left.gray;
    l.right = frame.right.gray;
  } else {
    cv::resize(frame.left.gray, l.left, cv::Size(), 1 / l.scale, 1 / l.scale, cv::INTER_AREA);
    cv::resize(frame.right.gray, l.right, cv::Size(), 1 / l.scale, 1 / l.scale, cv::INTER_AREA);
  }
  return l;
}

// The pixels of a level with `scale` full-resolution pixels per pixel whose
// centres ((x + 0.5) scale - 0.5) may round into `rect`, one spare each side.
cv::Rect LevelPixels(const cv::Rect& rect, double scale) {
  const int x0 = static_cast<int>(std::floor((rect.x + 0.5) / scale - 0.5)) - 1;
  const int y0 = static_cast<int>(std::floor((rect.y + 0.5) / scale - 0.5)) - 1;
  const int x1 = static_cast<int>(std::ceil((rect.br().x + 0.5) / scale - 0.5)) + 1;
  const int y1 = static_cast<int>(std::ceil((rect.br().y + 0.5) / scale - 0.5)) + 1;
  return {x0, y0, x1 - x0, y1 - y0};
}

// Pixel (x, y) of a level with `scale` full-resolution pixels per pixel:
// its centre in full-resolution pixels (u, v) and the full-resolution pixel
// nearest it (ui, vi), inside the image.
struct FullResolutionPixel {
  double u, v;
  int ui, vi;
};

// The pixels of a level of `size` with `scale` full-resolution pixels per
// pixel: each one's FullResolutionPixel and left ray (CameraIntrinsics::Ray
// at its centre), worked out once per column and row, as a lens that does
// not distort allows (per pixel otherwise): the same values, a fraction of
// the cost in the per-pixel loops below.
class LevelGrid {
 public:
  LevelGrid(cv::Size size, double scale, const rig::CameraIntrinsics& k)
      : k_(k), separable_(k.distortion.empty()) {
    for (int x = 0; x < size.width; ++x) {
      const double u = (x + 0.5) * scale - 0.5;
      u_.push_back(u);
      ui_.push_back(std::clamp(static_cast<int>(std::lround(u)), 0, k.width_px - 1));
      if (separable_) ray_x_.push_back(k.Ray({u, 0.0}).x());
    }
    for (int y = 0; y < size.height; ++y) {
      const double v = (y + 0.5) * scale - 0.5;
      v_.push_back(v);
      vi_.push_back(std::clamp(static_cast<int>(std::lround(v)), 0, k.height_px - 1));
      if (separable_) ray_y_.push_back(k.Ray({0.0, v}).y());
    }
  }
  FullResolutionPixel At(int x, int y) const { return {u_[x], v_[y], ui_[x], vi_[y]}; }
  Eigen::Vector3d Ray(int x, int y) const {
    return separable_ ? Eigen::Vector3d(ray_x_[x], ray_y_[y], 1.0) : k_.Ray({u_[x], v_[y]});
  }

 private:
  const rig::CameraIntrinsics& k_;
  const bool separable_;  ///< no distortion: a pixel's ray is (ray_x_[x], ray_y_[y], 1)
  std::vector<double> u_, v_, ray_x_, ray_y_;
  std::vector<int> ui_, vi_;
};

// Disparities of one left pixel at planar depths z, in a level's pixels:
// its ray is found once (LevelGrid::Ray), each depth then costs a few
// multiplications (DisparityAtDepth's arithmetic, unrolled).
class PixelDisparity {
 public:
  PixelDisparity(const rig::StereoFrame& frame, double scale)
      : fx_r_(frame.right.intrinsics.fx_px), cx_r_(frame.right.intrinsics.cx_px), scale_(scale) {
    const Eigen::Isometry3d right_T_left =
        frame.right.world_T_camera.inverse() * frame.left.world_T_camera;
    r_ = right_T_left.linear();
    t_ = right_T_left.translation();
  }
  /// The pixel at column u (full-resolution pixels) whose left ray is `ray`.
  void At(double u, const Eigen::Vector3d& ray) {
    u_ = u;
    rr_ = r_ * ray;
  }
  /// NaN behind the right camera.
  double operator()(double z) const {
    const double zr = z * rr_.z() + t_.z();
    if (zr <= 1e-6) return std::numeric_limits<double>::quiet_NaN();
    return (u_ - (fx_r_ * (z * rr_.x() + t_.x()) / zr + cx_r_)) / scale_;
  }

 private:
  double fx_r_, cx_r_, scale_;
  Eigen::Matrix3d r_;
  Eigen::Vector3d t_, rr_;
  double u_ = 0;
};

}  // namespace

cv::Mat FovealNearEdges(const PatchMap& map, const cv::Mat& depth, const cv::Mat& ids, int radius) {
  if (radius <= 0) return {};
  cv::Mat edge = cv::Mat::zeros(depth.size(), CV_8U);
  for (int y = 0; y < depth.rows; ++y)
    for (int x = 0; x < depth.cols; ++x) {
      const float z = depth.at<float>(y, x);
      auto apart = [&](int u, int v) {
        const float n = depth.at<float>(v, u);
        return !(z > 0) || !(n > 0) ||
               std::abs(z - n) > PatchMap::kSameSurfaceShare * std::min(z, n);
      };
      if ((x + 1 < depth.cols && apart(x + 1, y)) || (y + 1 < depth.rows && apart(x, y + 1))) {
        edge.at<uchar>(y, x) = 1;
        if (x + 1 < depth.cols) edge.at<uchar>(y, x + 1) = 1;
        if (y + 1 < depth.rows) edge.at<uchar>(y + 1, x) = 1;
      }
    }
  cv::dilate(edge, edge,
             cv::getStructuringElement(cv::MORPH_RECT, {2 * radius + 1, 2 * radius + 1}));
  for (int y = 0; y < ids.rows; ++y)
    for (int x = 0; x < ids.cols; ++x) {
      const int id = ids.at<int>(y, x);
      if (id < 0 || map[id].level != PatchLevel::kFoveal) edge.at<uchar>(y, x) = 0;
    }
  return edge;
}

namespace {

// The full-resolution pixels a finer level covers, in the frame a level is
// matched in: the finer level's rectangle, or where the level is matched in
// another frame (FovealOptions::rectified_periphery) that rectangle mapped
// into it, a mask.
struct Inner {
  cv::Rect rect;
  cv::Mat mask;  ///< CV_8U, non-zero inside; when not empty, `rect` is unused
  bool Contains(cv::Point p) const {
    if (mask.empty()) return rect.contains(p);
    return p.x >= 0 && p.y >= 0 && p.x < mask.cols && p.y < mask.rows && mask.at<uchar>(p) != 0;
  }
};

Inner FinerLevel(const Tessellation& t, int index) {
  return {index > 0 ? t.rects[index - 1] : cv::Rect(), cv::Mat()};
}

// The wide search behind FovealOptions::silent_near_m, once per fixation
// at one coarse resolution (2^silent_check_level full-resolution pixels
// per pixel): every pixel the map is silent at, over every depth from
// silent_near_m to infinity and the Z_T band.
struct SilentCheck {
  double scale = 1;  ///< full-resolution pixels per pixel
  cv::Mat wide;      ///< disparity, its pixels (NaN: none); empty: no check
  cv::Mat confidence;
  /// CV_8U, non-zero where the match and its 8 neighbours' lie within one
  /// of its pixels of one another: no depth edge about it (worked out only
  /// for FovealOptions::silent_outside_seed; zero otherwise).
  cv::Mat smooth;
  /// The wide search's match about pixel (x, y) of a level of `level_scale`
  /// full-resolution pixels per pixel: its disparity in that level's pixels
  /// (NaN: none, or no search), its confidence, and whether it is smooth.
  struct Match {
    double disparity, confidence;
    bool smooth;
  };
  Match At(int x, int y, double level_scale) const {
    if (wide.empty()) return {std::nan(""), 0, false};
    const double ratio = scale / level_scale;  // level pixels per check pixel
    const int xc = std::min(wide.cols - 1, static_cast<int>((x + 0.5) / ratio));
    const int yc = std::min(wide.rows - 1, static_cast<int>((y + 0.5) / ratio));
    return {wide.at<float>(yc, xc) * ratio, confidence.at<float>(yc, xc),
            smooth.at<uchar>(yc, xc) != 0};
  }
};

// Per-pixel disparity ranges of one level (lo > hi: not searched): around the
// coarser level's estimate, else around the map's prediction, else (the map
// silent) the Z_T band about the fixation depth, marked in `silent`.
struct SearchRanges {
  cv::Mat lo, hi;
  cv::Mat silent;  ///< CV_8U: the Z_T band, the map silent and no coarser estimate
};

SearchRanges LevelRanges(const rig::StereoFrame& frame, const Tessellation& t,
                         const cv::Mat& map_depth, const cv::Mat& skip, const cv::Mat* coarse,
                         const Level& level, const Inner& inner, const SilentCheck& wide,
                         const FovealOptions& options) {
  const rig::CameraIntrinsics& k = frame.left.intrinsics;
  const double s = level.scale, z0 = t.fixation_depth_m;
  const cv::Size size = level.left.size();
  const LevelGrid grid(size, s, k);
  SearchRanges r{cv::Mat(size, CV_32F, cv::Scalar(1)), cv::Mat(size, CV_32F, cv::Scalar(0)),
                 cv::Mat(size, CV_8U, cv::Scalar(0))};
  // The level's pixels whose centres may fall in its rectangle.
  const cv::Rect inside = LevelPixels(level.rect, s) & cv::Rect(cv::Point(), size);
  // Rows are independent: a large level's are split between two threads.
  auto rows = [&](size_t begin, size_t end) {
    PixelDisparity disparity(frame, s);
    for (int y = inside.y + static_cast<int>(begin); y < inside.y + static_cast<int>(end); ++y)
      for (int x = inside.x; x < inside.br().x; ++x) {
        const auto [u, v, ui, vi] = grid.At(x, y);
        if (!level.rect.contains({ui, vi}) || t.mask.at<uchar>(vi, ui) == 0) continue;
        // (The finer level's coarse estimates are needed inside it.)
        if (!skip.empty() && skip.at<uchar>(vi, ui) && !inner.Contains({ui, vi})) continue;
        double dlo, dhi;
        const float cd = coarse ? coarse->at<float>(std::min(coarse->rows - 1, y / 2),
                                                    std::min(coarse->cols - 1, x / 2))
                                : std::numeric_limits<float>::quiet_NaN();
        const float z = map_depth.at<float>(vi, ui);
        if (std::isfinite(cd)) {
          // The coarser level's estimate, in this level's pixels.
          dlo = 2 * cd - options.coarse_margin_px;
          dhi = 2 * cd + options.coarse_margin_px;
        } else if (z > 0) {
          disparity.At(u, grid.Ray(x, y));
          const double d = disparity(z);
          dlo = d - options.map_margin_px;
          dhi = d + options.map_margin_px;
        } else {
          // The map is silent: anything within Z_T of the fixation depth.
          disparity.At(u, grid.Ray(x, y));
          const double a = disparity(z0 - t.z_t_near_m), b = disparity(z0 + t.z_t_far_m);
          dlo = std::min(a, b) - 1;
          dhi = std::max(a, b) + 1;
          r.silent.at<uchar>(y, x) = 1;
          // Beyond the paper (FovealOptions::silent_outside_seed): where the
          // wide search matched a surface outside the band, away from any
          // depth edge, the band gives way to its match, as a coarser
          // level's estimate.
          if (options.silent_outside_seed) {
            const auto [w, confidence, smooth] = wide.At(x, y, level.scale);
            const double ratio = wide.scale / level.scale;
            if (std::isfinite(w) && smooth && confidence >= options.silent_confidence &&
                (w < dlo - ratio || w > dhi + ratio)) {
              dlo = w - ratio - options.coarse_margin_px;
              dhi = w + ratio + options.coarse_margin_px;
              r.silent.at<uchar>(y, x) = 0;
            }
          }
        }
        if (!std::isfinite(dlo) || !std::isfinite(dhi)) continue;
        r.lo.at<float>(y, x) = static_cast<float>(dlo);
        r.hi.at<float>(y, x) = static_cast<float>(dhi);
      }
  };
  constexpr int kThreadedMinPixels = 32768;
  ForHalves(inside.height, inside.area() >= kThreadedMinPixels, rows);
  return r;
}

SilentCheck CheckSilent(const rig::StereoFrame& frame, const Tessellation& t,
                        const cv::Mat& map_depth, const cv::Rect& region,
                        const StereoMatcher& matcher, const FovealOptions& options) {
  SilentCheck c;
  c.scale = std::pow(2.0, options.silent_check_level);
  const Level level = MakeLevel(frame, t, 0, options.silent_check_level);
  const rig::CameraIntrinsics& k = frame.left.intrinsics;
  const double s = c.scale, z0 = t.fixation_depth_m;
  PixelDisparity disparity(frame, s);
  const cv::Size size = level.left.size();
  const LevelGrid grid(size, s, k);
  cv::Mat lo(size, CV_32F, cv::Scalar(1)), hi(size, CV_32F, cv::Scalar(0));
  for (int y = 0; y < size.height; ++y)
    for (int x = 0; x < size.width; ++x) {
      const auto [u, v, ui, vi] = grid.At(x, y);
      if (!region.contains({ui, vi}) || t.mask.at<uchar>(vi, ui) == 0 ||
          map_depth.at<float>(vi, ui) > 0)
        continue;
      disparity.At(u, grid.Ray(x, y));
      const double values[4] = {disparity(z0 - t.z_t_near_m), disparity(z0 + t.z_t_far_m),
                                disparity(options.silent_near_m), disparity(kFarDepthM)};
      if (!std::all_of(std::begin(values), std::end(values),
                       [](double d) { return std::isfinite(d); }))
        continue;
      lo.at<float>(y, x) =
          static_cast<float>(*std::min_element(std::begin(values), std::end(values)) - 1);
      hi.at<float>(y, x) =
          static_cast<float>(*std::max_element(std::begin(values), std::end(values)) + 1);
    }
  const DisparityMap dm = matcher.Match(level.left, level.right, lo, hi);
  c.wide = dm.disparity_px;
  c.confidence = dm.confidence;
  c.smooth = cv::Mat::zeros(c.wide.size(), CV_8U);
  if (!options.silent_outside_seed) return c;  // only it reads `smooth`
  for (int y = 1; y + 1 < c.wide.rows; ++y)
    for (int x = 1; x + 1 < c.wide.cols; ++x) {
      const float here = c.wide.at<float>(y, x);
      bool smooth = std::isfinite(here);
      for (int v = y - 1; smooth && v <= y + 1; ++v)
        for (int u = x - 1; smooth && u <= x + 1; ++u)
          smooth = std::abs(c.wide.at<float>(v, u) - here) <= 1;
      c.smooth.at<uchar>(y, x) = smooth;
    }
  return c;
}

// A band match at a silent pixel where the wide search (CheckSilent)
// confidently matched outside the band (give or take one of its pixels) is
// a false match of a surface the band does not hold: dropped from `dm`.
// Returns how many.
int DropOutsideBand(const SilentCheck& check, const Level& level, const SearchRanges& ranges,
                    const FovealOptions& options, DisparityMap* dm) {
  const double ratio = check.scale / level.scale;  // this level's pixels per check pixel
  int dropped = 0;
  for (int y = 0; y < dm->disparity_px.rows; ++y)
    for (int x = 0; x < dm->disparity_px.cols; ++x) {
      float& d = dm->disparity_px.at<float>(y, x);
      if (!std::isfinite(d) || !ranges.silent.at<uchar>(y, x)) continue;
      const auto [wl, confidence, smooth] = check.At(x, y, level.scale);
      if (!std::isfinite(wl) || confidence < options.silent_confidence) continue;
      if (wl < ranges.lo.at<float>(y, x) - ratio || wl > ranges.hi.at<float>(y, x) + ratio) {
        d = std::numeric_limits<float>::quiet_NaN();
        ++dropped;
      }
    }
  return dropped;
}

}  // namespace

int ErodeAtDisparityJumps(int radius, double jump_px, cv::Mat* disparity) {
  if (radius <= 0) return 0;
  // Only the matched pixels' bounding box and `radius` around it can change
  // (elsewhere the limit is +inf, as beyond the image's border): the fovea's
  // level is mostly unmatched.
  int x0 = disparity->cols, x1 = -1, y0 = disparity->rows, y1 = -1;
  for (int y = 0; y < disparity->rows; ++y) {
    const float* row = disparity->ptr<float>(y);
    int first = 0, last = disparity->cols - 1;
    while (first <= last && !std::isfinite(row[first])) ++first;
    while (last > first && !std::isfinite(row[last])) --last;
    if (first > last) continue;
    x0 = std::min(x0, first);
    x1 = std::max(x1, last);
    y0 = std::min(y0, y);
    y1 = y;
  }
  if (x1 < 0) return 0;
  cv::Rect box(x0, y0, x1 - x0 + 1, y1 - y0 + 1);
  box = cv::Rect(box.x - radius, box.y - radius, box.width + 2 * radius, box.height + 2 * radius) &
        cv::Rect(0, 0, disparity->cols, disparity->rows);
  cv::Mat d = (*disparity)(box);
  // The limits: each pixel's disparity where it belongs to a surface, at
  // least kSupport of its 8 neighbours within jump_px of it; +inf (no limit)
  // where it is NaN or an isolated mismatch, which would otherwise cost the
  // good matches around it.
  constexpr int kSupport = 3;
  cv::Mat farthest(d.size(), CV_32F, cv::Scalar(std::numeric_limits<float>::infinity()));
  // The comparison |a - b| <= jump_px of two floats, in floats: against
  // the largest float not above jump_px (the same answer), so that the
  // loop below vectorizes. NaN is near nothing.
  float jump = static_cast<float>(jump_px);
  if (jump > jump_px) jump = std::nextafter(jump, -std::numeric_limits<float>::infinity());
  auto near = [jump](float a, float b) { return int{std::abs(a - b) <= jump}; };
  // The rows above and below (NaN beyond the box: there the image ends or
  // nothing is matched).
  const std::vector<float> none(d.cols, std::numeric_limits<float>::quiet_NaN());
  for (int y = 0; y < d.rows; ++y) {
    const float* up = y > 0 ? d.ptr<float>(y - 1) : none.data();
    const float* mid = d.ptr<float>(y);
    const float* down = y + 1 < d.rows ? d.ptr<float>(y + 1) : none.data();
    float* out = farthest.ptr<float>(y);
    // The columns with both neighbours, branch-free; then the box's first
    // and last column.
    for (int x = 1; x + 1 < d.cols; ++x) {
      const float here = mid[x];
      const int support = near(up[x - 1], here) + near(up[x], here) + near(up[x + 1], here) +
                          near(mid[x - 1], here) + near(mid[x + 1], here) +
                          near(down[x - 1], here) + near(down[x], here) + near(down[x + 1], here);
      out[x] = support >= kSupport && std::isfinite(here) ? here : out[x];
    }
    for (const int x : {0, d.cols - 1}) {
      const float here = mid[x];
      if (!std::isfinite(here)) continue;
      const int u0 = std::max(0, x - 1), u1 = std::min(d.cols - 1, x + 1);
      int support = 0;
      for (int u = u0; u <= u1; ++u) support += near(up[u], here) + near(down[u], here);
      for (const int u : {x - 1, x + 1})
        if (u >= u0 && u <= u1) support += near(mid[u], here);
      if (support >= kSupport) out[x] = here;
    }
  }
  cv::erode(farthest, farthest,
            cv::getStructuringElement(cv::MORPH_RECT, {2 * radius + 1, 2 * radius + 1}));
  int n = 0;
  for (int y = 0; y < d.rows; ++y)
    for (int x = 0; x < d.cols; ++x) {
      float& here = d.at<float>(y, x);
      if (std::isfinite(here) && here - farthest.at<float>(y, x) > jump_px) {
        here = std::numeric_limits<float>::quiet_NaN();
        ++n;
      }
    }
  return n;
}

cv::Mat BesideUnmatchedRuns(const cv::Mat& disparity, int radius, int run_px) {
  cv::Mat beside = cv::Mat::zeros(disparity.size(), CV_8U);
  if (radius <= 0 || run_px <= 0) return beside;
  for (const bool rows : {true, false}) {
    const int lines = rows ? disparity.rows : disparity.cols;
    const int length = rows ? disparity.cols : disparity.rows;
    auto matched = [&](int line, int i) {
      return std::isfinite(rows ? disparity.at<float>(line, i) : disparity.at<float>(i, line));
    };
    auto mark = [&](int line, int i) {
      (rows ? beside.at<uchar>(line, i) : beside.at<uchar>(i, line)) = 1;
    };
    for (int line = 0; line < lines; ++line)
      for (int i = 0; i < length;) {
        if (matched(line, i)) {
          ++i;
          continue;
        }
        const int a = i;  // the run is [a, i)
        while (i < length && !matched(line, i)) ++i;
        if (i - a < run_px) continue;
        for (int k = std::max(0, a - radius); k < a; ++k) mark(line, k);
        for (int k = i; k < std::min(length, i + radius); ++k) mark(line, k);
      }
  }
  return beside;
}

namespace {

// The patch of one fitted block of a level: it spans the block's footprint
// (the whole block, which tiles the image without cracks, or its inliers'
// extent: their bounding box or their diagonal hull), its corners
// triangulated from both rays; nullopt if a corner's rays do not meet.
std::optional<Patch> BlockPatch(const rig::StereoFrame& frame, const Level& level,
                                const BlockFit& b, int fixation, double max_view_angle_deg) {
  const rig::CameraView& left = frame.left;
  const rig::CameraView& right = frame.right;
  const double s = level.scale;
  Patch p;
  p.level = level.index == 0 ? PatchLevel::kFoveal : PatchLevel::kPeripheral;
  p.resolution_level = level.index;
  p.fixation = fixation;
  p.fit_rms_px = b.fit.rms_px;
  p.support = b.fit.support;
  for (int c = 0; c < 4; ++c) {
    const double x = b.corners[c].x(), y = b.corners[c].y();
    const double d = b.fit(x, y) * s;
    const double u = (x + 0.5) * s - 0.5, v = (y + 0.5) * s - 0.5;
    const auto tri =
        TriangulateMidpoint(PixelRay(left.world_T_camera, left.intrinsics, {u, v}),
                            PixelRay(right.world_T_camera, right.intrinsics, {u - d, v}));
    if (!tri) return std::nullopt;
    p.corners_W[c] = tri->p_W;
  }
  // Matching precision and fit residual, in level pixels, at the level's scale.
  SetDepthSigma(&p, left, right.world_T_camera.translation(),
                s * std::max(kMatchSigmaPx, b.fit.rms_px));
  if (max_view_angle_deg > 0 &&
      !(p.ViewAngleRad(left.world_T_camera.translation()) <= max_view_angle_deg * M_PI / 180))
    return std::nullopt;
  return p;
}

// Patches over the part of a level the finer one does not cover. Peripheral
// blocks keep about the same size in the image at every level (the paper's
// were about twice the foveal ones), but never fewer than 4 x 4 of the
// level's pixels; their fit tolerance shrinks with the level so that it stays
// near a full-resolution pixel and a plane cannot bridge a depth step.
// Returns how many were added.
int LevelPatches(const rig::StereoFrame& frame, const Level& level, const Inner& inner,
                 const cv::Mat& disparity, const FovealOptions& options, int fixation,
                 PatchMap* patches) {
  const int size = level.index == 0 ? options.fovea_patch_px
                                    : std::max(4, options.periphery_patch_px >> level.index);
  PlaneFitOptions fit_options = options.plane_fit;
  if (level.index > 0)
    fit_options.fit_tolerance_px = std::max(0.25, options.plane_fit.fit_tolerance_px / level.scale);
  auto in_level = [&](int bx, int by, int block) {
    const cv::Point centre(static_cast<int>((bx + 0.5 * block) * level.scale - 0.5),
                           static_cast<int>((by + 0.5 * block) * level.scale - 0.5));
    return level.rect.contains(centre) && !(level.index > 0 && inner.Contains(centre));
  };
  BlockOptions blocks = options.blocks;
  if (level.index > 0) {
    blocks.min_block_px = std::max(blocks.min_block_px, options.periphery_min_block_px);
    blocks.half_agreement = options.periphery_half_agreement;
    // A peripheral block's hull, cut at a corner its sparser matches miss,
    // gave up more right pixels than wrong ones (README, issue 19).
    blocks.clip_diagonals = false;
  }
  int added = 0;
  const cv::Mat beside_holes =
      BesideUnmatchedRuns(disparity, options.edge_erosion_px, options.edge_hole_px);
  for (const BlockFit& b : FitBlocks(disparity, size, fit_options, blocks, in_level, beside_holes))
    if (const auto p = BlockPatch(frame, level, b, fixation, options.max_view_angle_deg)) {
      patches->Add(*p);
      ++added;
    }
  return added;
}

// The pixels of level `index` (the outermost, index > 0) beyond the finer
// level's rectangle, matched in the pair turned into a rectified one
// (FovealOptions::rectified_periphery): the map rendered into its left view
// sets the search ranges and the Z_T mask as in the fixation frame, and the
// finer level's rectangle, mapped into it, is left to the finer levels.
// Adds the level's patches to `result` and its counts to `fig`.
void MatchRectifiedPeriphery(const FixationFrame& matched, const Eigen::Vector3d& fixation_W,
                             const Tessellation& t, int index, const PatchMap& map,
                             const StereoMatcher& matcher, const FovealOptions& options,
                             int fixation, FovealResult* result, LevelFigures* fig) {
  const FixationFrame rectified = ToRectifiedFrame(matched.original);
  const rig::StereoFrame& frame = rectified.views;
  const rig::CameraIntrinsics& k = frame.left.intrinsics;
  const cv::Rect image(0, 0, k.width_px, k.height_px);
  cv::Mat depth, ids;
  map.Render(frame.left.world_T_camera, k, &depth, &ids);
  Tessellation tr;
  tr.fixation_depth_m = (frame.left.world_T_camera.inverse() * fixation_W).z();
  tr.z_t_near_m = t.z_t_near_m;
  tr.z_t_far_m = t.z_t_far_m;
  tr.rects.assign(index + 1, image);
  // Z_T's mask, as TessellateFromDepth's, and pixels turned in from outside.
  tr.mask = rectified.left_valid.clone();
  for (int v = 0; v < depth.rows; ++v)
    for (int u = 0; u < depth.cols; ++u) {
      const float z = depth.at<float>(v, u);
      if (z > 0 && tr.BeyondZt(z)) tr.mask.at<uchar>(v, u) = 0;
    }
  // The finer level's rectangle: fixation-frame pixel -> original -> rectified.
  Inner inner;
  cv::Mat finer(t.mask.size(), CV_8U, cv::Scalar(0));
  finer(t.rects[index - 1]).setTo(255);
  cv::warpPerspective(finer, inner.mask, rectified.left_H * matched.left_H.inv(), image.size(),
                      cv::INTER_NEAREST, cv::BORDER_CONSTANT);
  const cv::Mat skip = FovealNearEdges(map, depth, ids, options.skip_foveal_edge_px);
  SilentCheck silent;
  if (options.silent_near_m > 0) {
    const auto t0 = Clock::now();
    silent = CheckSilent(frame, tr, depth, image, matcher, options);
    result->silent_check_time_s += Since(t0);
  }
  const Level level =
      MakeLevel(frame, tr, index, options.rectified_periphery_full_resolution ? 0 : index);
  const SearchRanges ranges =
      LevelRanges(frame, tr, depth, skip, nullptr, level, inner, silent, options);
  DisparityMap dm = matcher.Match(level.left, level.right, ranges.lo, ranges.hi);
  FovealOptions drop = options;
  drop.silent_confidence = options.rectified_silent_confidence;
  const int outside_band =
      silent.wide.empty() ? 0 : DropOutsideBand(silent, level, ranges, drop, &dm);
  fig->searched += dm.searched;
  fig->matched += dm.matched - outside_band;
  fig->outside_band += outside_band;
  fig->eroded +=
      ErodeAtDisparityJumps(options.edge_erosion_px, options.edge_jump_px, &dm.disparity_px);
  fig->patches +=
      LevelPatches(frame, level, inner, dm.disparity_px, options, fixation, &result->patches);
  result->rectified_periphery_px = dm.disparity_px;
}

}  // namespace

FoveaFigures FovealResult::Fovea() const {
  FoveaFigures f;
  f.resampled = frame.resampled;
  f.left_roll_rad = frame.left_roll_rad;
  f.right_roll_rad = frame.right_roll_rad;
  f.right_turn_rad = frame.right_turn_rad;
  if (tessellation.rects.empty()) return f;
  const cv::Rect& r = tessellation.rects[0];
  f.width_px = r.width;
  f.height_px = r.height;
  const cv::Size image = tessellation.mask.size();
  if (image.area() > 0) f.image_share = double(r.area()) / image.area();
  return f;
}

FovealResult FovealStereo(const FixationFrame& matched, const Eigen::Vector3d& fixation_W,
                          const PatchMap& map, const StereoMatcher& matcher,
                          const FovealOptions& options, int fixation) {
  const auto t_start = Clock::now();
  FovealResult result;
  result.frame = matched;
  const rig::StereoFrame& frame = result.frame.views;
  cv::Mat map_depth, map_ids;
  map.Render(frame.left.world_T_camera, frame.left.intrinsics, &map_depth, &map_ids);
  const cv::Mat skip = FovealNearEdges(map, map_depth, map_ids, options.skip_foveal_edge_px);
  result.tessellation =
      TessellateFromDepth(frame.left, frame.right, fixation_W, map_depth, options.tessellation);
  Tessellation& t = result.tessellation;
  // Pixels turned in from outside the original image are not matched.
  if (result.frame.resampled) t.mask &= result.frame.left_valid;
  const int levels = static_cast<int>(t.rects.size());
  // With rectified_periphery the outermost level is matched here only about
  // the finer level (its coarse estimates), and beyond it in the rectified
  // pair (MatchRectifiedPeriphery).
  const rig::StereoFrame& original = result.frame.original;
  const bool rectified_periphery =
      options.rectified_periphery && levels > 1 && !original.left.gray.empty() &&
      (original.right.world_T_camera.translation() - original.left.world_T_camera.translation())
              .norm() > 1e-6;
  auto matched_here = [&](int index) {
    if (!rectified_periphery || index + 1 < levels) return t.rects[index];
    const int margin = 2 << index;  // two of the level's pixels
    const cv::Rect& finer = t.rects[index - 1];
    return cv::Rect(finer.x - margin, finer.y - margin, finer.width + 2 * margin,
                    finer.height + 2 * margin) &
           t.rects[index];
  };
  SilentCheck silent;
  if (options.silent_near_m > 0 && levels > 0) {
    const auto t0 = Clock::now();
    silent = CheckSilent(frame, t, map_depth, matched_here(levels - 1), matcher, options);
    result.silent_check_time_s = Since(t0);
  }
  result.disparity_px.resize(levels);
  result.levels.resize(levels);
  // Coarse to fine: each level's search starts from the coarser one's estimate.
  for (int index = levels - 1; index >= 0; --index) {
    const auto t0 = Clock::now();
    const double silent_before = result.silent_check_time_s;
    Level level = MakeLevel(frame, t, index);
    level.rect = matched_here(index);
    const cv::Mat* coarse = index + 1 < levels ? &result.disparity_px[index + 1] : nullptr;
    const Inner inner = FinerLevel(t, index);
    SearchRanges ranges = LevelRanges(frame, t, map_depth, index > 0 ? skip : cv::Mat(), coarse,
                                      level, inner, silent, options);
    DisparityMap dm = matcher.Match(level.left, level.right, ranges.lo, ranges.hi);
    const int outside_band =
        silent.wide.empty() ? 0 : DropOutsideBand(silent, level, ranges, options, &dm);

    LevelFigures& fig = result.levels[index];
    fig.level = index;
    fig.rect = t.rects[index];
    fig.searched = dm.searched;
    fig.matched = dm.matched - outside_band;
    fig.outside_band = outside_band;
    fig.eroded = ErodeAtDisparityJumps(index == 0 && options.fovea_edge_erosion_px >= 0
                                           ? options.fovea_edge_erosion_px
                                           : options.edge_erosion_px,
                                       options.edge_jump_px, &dm.disparity_px);
    if (rectified_periphery && index + 1 == levels)
      MatchRectifiedPeriphery(result.frame, fixation_W, t, index, map, matcher, options, fixation,
                              &result, &fig);
    else
      fig.patches =
          LevelPatches(frame, level, inner, dm.disparity_px, options, fixation, &result.patches);
    // The rectified periphery's wide search is counted in
    // silent_check_time_s, not twice.
    fig.match_time_s = Since(t0) - (result.silent_check_time_s - silent_before);
    result.disparity_px[index] = dm.disparity_px;
  }
  result.compute_time_s = Since(t_start);
  return result;
}

namespace {

// Why a fixation point the servo settled on cannot be trusted, given the
// map: along the left optical axis the map shows a certain surface (its
// depth sigma within kCertainShare of its depth) behind the point, beyond
// their combined uncertainty (the servo's point: its depth from the pair's
// baseline and the servo's residual, at least half a pixel). The point then
// lies in free space: a false match, a repeated texture's copy. A point
// behind the map's surface is accepted: where the map is wrong (a nearer
// surface's patch reaching over its edge), that is what the camera sees.
// nullopt when the map agrees, is silent or is not certain.
std::optional<std::string> DisagreesWithMap(const rig::StereoFrame& frame,
                                            const Eigen::Vector3d& fixation_W, double depth_m,
                                            double residual_px, const PatchMap& map) {
  const Eigen::Vector3d origin = frame.left.world_T_camera.translation();
  const Eigen::Vector3d axis = frame.left.world_T_camera.linear().col(2);
  const auto hit = map.CastRay(origin, axis);
  if (!hit) return std::nullopt;
  const Patch& surface = map[hit->patch];
  Patch point;  // the servo's measurement, as a patch of one point
  point.corners_W = {fixation_W, fixation_W, fixation_W, fixation_W};
  point.sigma_z_m =
      DepthSigma(depth_m, std::max(0.5, std::abs(residual_px)), frame.left.intrinsics.fx_px,
                 frame.right.world_T_camera.translation() - origin, axis);
  constexpr double kCertainShare = 0.01;
  if (depth_m >= hit->distance_m ||
      PatchMap::SameSurface(depth_m, point, hit->distance_m, surface) ||
      !(surface.sigma_z_m <= kCertainShare * hit->distance_m))
    return std::nullopt;
  char why[200];
  std::snprintf(why, sizeof why,
                "servoing settled at %.3f m, in front of the surface the map holds on the optical "
                "axis at %.3f m "
                "(+-%.1f mm): a false match in free space",
                depth_m, hit->distance_m, 1e3 * surface.sigma_z_m);
  return std::string(why);
}

}  // namespace

FixationResult Fixate(rig::Rig& rig, const PatchMap& map, const Eigen::Vector3d& p_W,
                      const StereoMatcher& matcher, const FixationOptions& options, int fixation,
                      const std::optional<DepthRange>& guessed_depths) {
  FixationResult r;
  const auto t0 = Clock::now();
  r.baseline_m = !guessed_depths && options.mapped_baseline_m > 0 ? options.mapped_baseline_m
                                                                  : options.baseline_m;
  if (options.choose_placement) {
    const PlacementChoice choice =
        ChoosePlacement(PlacementRig::Of(rig, options.left_pair, options.left_pair_first), map, p_W,
                        r.baseline_m, options.vergence, guessed_depths);
    r.placement = choice.placement;
    r.vergence = choice.vergence;
  } else {
    r.vergence = Verge(rig.Geometry(), rig.Limits(), rig.Intrinsics(rig::Side::kLeft),
                       rig.Intrinsics(rig::Side::kRight), rig::StageState::Parallel(r.baseline_m),
                       p_W, options.vergence);
  }
  if (!r.vergence.ok) {
    r.why = r.vergence.why;
    return r;
  }
  const double verge_s = Since(t0);
  r.verge_time_s = verge_s;
  const auto t_servo = Clock::now();
  std::optional<rig::LeftCameraPair> left_pair;
  if (r.placement == Placement::kLeftPair) left_pair.emplace(rig);
  rig::Rig& pair = left_pair ? static_cast<rig::Rig&>(*left_pair) : rig;
  ServoOptions servo = options.servo;
  servo.rectify = options.foveal.rectify;
  r.servo = Servo(pair, r.vergence.state, servo, guessed_depths);
  r.servo_wall_s = Since(t_servo);
  r.motion_time_s = r.servo.motion_time_s;
  // A point refused after servoing: nothing was matched, only the vergence computed.
  auto refuse = [&r, verge_s](std::string why) {
    r.why = std::move(why);
    r.compute_time_s = verge_s;
    return r;
  };
  if (!r.servo.mutual)
    return refuse(
        "servoing's match is not mutual: the right camera's centre matches elsewhere in the left "
        "image");
  if (guessed_depths && !r.servo.converged)
    return refuse("servoing found no unique match for a point of guessed depth");
  const rig::StereoFrame& frame = r.servo.frame;
  // Where the two optical axes (the principal points' rays) meet.
  const auto& kl = frame.left.intrinsics;
  const auto& kr = frame.right.intrinsics;
  const auto meet =
      TriangulateMidpoint(PixelRay(frame.left.world_T_camera, kl, {kl.cx_px, kl.cy_px}),
                          PixelRay(frame.right.world_T_camera, kr, {kr.cx_px, kr.cy_px}));
  r.fixation_W = meet ? meet->p_W : p_W;
  const double depth = (frame.left.world_T_camera.inverse() * r.fixation_W).z();
  if (depth < options.min_depth_m)
    return refuse("servoing settled at " + std::to_string(depth) +
                  " m, nearer than idr.z_min_m: a false match");
  if (options.map_check)
    if (const auto why = DisagreesWithMap(frame, r.fixation_W, depth, r.servo.residual_px, map))
      return refuse(*why);
  // In the frame the servo measured in (foveal.rectify), not turned again.
  r.foveal = FovealStereo(r.servo.measured, r.fixation_W, map, matcher, options.foveal, fixation);
  r.compute_time_s = verge_s + r.foveal.compute_time_s;
  r.ok = true;
  return r;
}

}  // namespace fovea
