#include "fovea/idr.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <unordered_map>

#include "fovea/fixation_frame.h"
#include "fovea/params.h"
#include "fovea/stats.h"
#include "fovea/timing.h"

namespace fovea {
namespace {

double AngleDiff(double a, double b) {
  double d = std::fmod(std::abs(a - b), 2 * M_PI);
  return d > M_PI ? 2 * M_PI - d : d;
}

bool Compatible(const ZeroCrossing& a, const ZeroCrossing& b, const ZcMatchOptions& o) {
  return a.polarity == b.polarity &&
         AngleDiff(a.orientation_rad, b.orientation_rad) <= o.orientation_tolerance_rad;
}

// Unique compatible crossing of `other` on row y with position in
// [x_lo, x_hi]; -1 none, -2 several. With take_nearest_when_ambiguous,
// several yield the smallest-disparity one, encoded as -3 - index.
int FindUnique(const ZeroCrossing& zc, const ZeroCrossingImage& other, double x_lo, double x_hi,
               const ZcMatchOptions& o, bool smallest_disparity_is_high_x) {
  const int b = other.row_begin[zc.y_px], e = other.row_begin[zc.y_px + 1];
  const auto first =
      std::lower_bound(other.crossings.begin() + b, other.crossings.begin() + e, x_lo,
                       [](const ZeroCrossing& c, double x) { return c.x_px < x; });
  int found = -1, count = 0, nearest = -1;
  for (auto it = first; it != other.crossings.begin() + e && it->x_px <= x_hi; ++it) {
    if (!Compatible(zc, *it, o)) continue;
    const int index = static_cast<int>(it - other.crossings.begin());
    if (++count == 1) found = index;
    // Scanning by increasing x: the last is the highest x.
    if (nearest < 0 || smallest_disparity_is_high_x) nearest = index;
  }
  if (count <= 1) return found;
  return o.take_nearest_when_ambiguous ? -3 - nearest : -2;
}

}  // namespace

double ZcMatchStats::UnambiguousShare() const {
  const int with_candidates = unique + ambiguous;
  return with_candidates > 0 ? static_cast<double>(unique) / with_candidates : 0.0;
}

bool DisparityWindows::Window(double x_px, int y_px, double* lo, double* hi) const {
  if (global) {
    *lo = global_lo_px;
    *hi = global_hi_px;
    return true;
  }
  bool any = false;
  for (int y = std::max(0, y_px - row_reach); y <= std::min<int>(rows.size() - 1, y_px + row_reach);
       ++y) {
    const auto& row = rows[y];
    auto it = std::lower_bound(row.begin(), row.end(), static_cast<float>(x_px - reach_px),
                               [](const Anchor& a, float x) { return a.x_px < x; });
    for (; it != row.end() && it->x_px <= x_px + reach_px; ++it) {
      if (!any) {
        *lo = it->lo_px;
        *hi = it->hi_px;
        any = true;
      } else {
        *lo = std::min<double>(*lo, it->lo_px);
        *hi = std::max<double>(*hi, it->hi_px);
      }
    }
  }
  return any;
}

std::vector<ZcMatch> MatchZeroCrossings(const ZeroCrossingImage& left,
                                        const ZeroCrossingImage& right,
                                        const DisparityWindows& left_windows,
                                        const DisparityWindows& right_windows,
                                        const ZcMatchOptions& options, ZcMatchStats* stats) {
  ZcMatchStats s;
  s.left_crossings = static_cast<int>(left.crossings.size());
  s.right_crossings = static_cast<int>(right.crossings.size());
  // Right to left first: for right crossing j, its unique left partner.
  std::vector<int> right_partner(right.crossings.size(), -1);
  for (size_t j = 0; j < right.crossings.size(); ++j) {
    const ZeroCrossing& zc = right.crossings[j];
    double lo, hi;
    if (!right_windows.Window(zc.x_px, zc.y_px, &lo, &hi)) continue;
    // d = x_left - x_right: the smallest disparity is the lowest left x.
    int found = FindUnique(zc, left, zc.x_px + lo, zc.x_px + hi, options, false);
    if (found <= -3) found = -3 - found;
    right_partner[j] = found;
  }
  std::vector<ZcMatch> matches;
  for (size_t i = 0; i < left.crossings.size(); ++i) {
    const ZeroCrossing& zc = left.crossings[i];
    double lo, hi;
    if (!left_windows.Window(zc.x_px, zc.y_px, &lo, &hi)) continue;
    ++s.searched;
    // Disparity d = x_left - x_right, so x_right in [x - hi, x - lo].
    int j = FindUnique(zc, right, zc.x_px - hi, zc.x_px - lo, options, true);
    if (j == -1) {
      ++s.no_candidate;
      continue;
    }
    if (j == -2) {
      ++s.ambiguous;
      continue;
    }
    if (j <= -3) {
      ++s.ambiguous;  // resolved by the nearest-candidate policy
      j = -3 - j;
    } else {
      ++s.unique;
    }
    if (right_partner[j] != static_cast<int>(i)) {
      ++s.inconsistent;
      continue;
    }
    matches.push_back({static_cast<int>(i), j, zc.x_px - right.crossings[j].x_px});
  }
  s.matches = static_cast<int>(matches.size());
  if (stats) *stats = s;
  return matches;
}

namespace {
// Samples bucketed in square cells, for neighbourhood queries.
class SampleGrid {
 public:
  SampleGrid(const std::vector<DisparitySample>& samples, double cell)
      : samples_(samples), cell_(std::max(1.0, cell)) {
    for (size_t i = 0; i < samples.size(); ++i)
      grid_[Key(samples[i].x_px, samples[i].y_px)].push_back(static_cast<int>(i));
  }
  // Indices of samples within `radius` of sample i (not i itself).
  template <typename F>
  void ForNeighbours(size_t i, double radius, F&& f) const {
    const DisparitySample& a = samples_[i];
    const int reach = static_cast<int>(std::ceil(radius / cell_));
    for (int dy = -reach; dy <= reach; ++dy)
      for (int dx = -reach; dx <= reach; ++dx) {
        const auto it = grid_.find(Key(a.x_px + dx * cell_, a.y_px + dy * cell_));
        if (it == grid_.end()) continue;
        for (int j : it->second) {
          if (j == static_cast<int>(i)) continue;
          const double ddx = a.x_px - samples_[j].x_px, ddy = a.y_px - samples_[j].y_px;
          if (ddx * ddx + ddy * ddy <= radius * radius) f(j);
        }
      }
  }

 private:
  long long Key(double x, double y) const {
    // Cell indices offset to be non-negative, packed into 64 bits.
    const auto ix = static_cast<unsigned long long>(static_cast<long long>(std::floor(x / cell_)) +
                                                    (1LL << 30));
    const auto iy = static_cast<unsigned long long>(static_cast<long long>(std::floor(y / cell_)) +
                                                    (1LL << 30));
    return static_cast<long long>((iy << 32) | (ix & 0xffffffffULL));
  }
  const std::vector<DisparitySample>& samples_;
  double cell_;
  std::unordered_map<long long, std::vector<int>> grid_;
};
}  // namespace

std::vector<char> IsolatedOutliers(const std::vector<DisparitySample>& samples, double radius_px,
                                   double jump_px) {
  std::vector<char> flags(samples.size(), 0);
  const SampleGrid grid(samples, radius_px);
  std::vector<double> near;
  for (size_t i = 0; i < samples.size(); ++i) {
    near.clear();
    grid.ForNeighbours(i, radius_px, [&](int j) { near.push_back(samples[j].disparity_px); });
    if (near.size() < 3) continue;
    std::nth_element(near.begin(), near.begin() + near.size() / 2, near.end());
    if (std::abs(samples[i].disparity_px - near[near.size() / 2]) > jump_px) flags[i] = 1;
  }
  return flags;
}

std::vector<char> NearDiscontinuity(const std::vector<DisparitySample>& samples, double radius_px,
                                    double jump_px) {
  std::vector<char> flags(samples.size(), 0);
  if (samples.empty()) return flags;
  // Along each row, consecutive samples (whatever their distance) that jump
  // bracket a discontinuity.
  std::unordered_map<int, std::vector<int>> rows;
  for (size_t i = 0; i < samples.size(); ++i)
    rows[static_cast<int>(samples[i].y_px)].push_back(static_cast<int>(i));
  for (auto& [y, idx] : rows) {
    std::sort(idx.begin(), idx.end(),
              [&](int a, int b) { return samples[a].x_px < samples[b].x_px; });
    for (size_t k = 1; k < idx.size(); ++k)
      if (std::abs(samples[idx[k]].disparity_px - samples[idx[k - 1]].disparity_px) > jump_px)
        flags[idx[k]] = flags[idx[k - 1]] = 1;
  }
  const SampleGrid grid(samples, radius_px);
  for (size_t i = 0; i < samples.size(); ++i) {
    if (flags[i]) continue;
    grid.ForNeighbours(i, radius_px, [&](int j) {
      if (std::abs(samples[i].disparity_px - samples[j].disparity_px) > jump_px) flags[i] = 1;
    });
  }
  return flags;
}

double ExpansionFactor(double s_min_px, double d_max_px, double focal_px, double max_slant_rad) {
  const double g = d_max_px * s_min_px * std::tan(max_slant_rad) / focal_px;
  return s_min_px / (1 + g);
}

void ZcMatchOptions::Check() const {
  rig::CheckParam(params::kIdrOrientationToleranceRad, orientation_tolerance_rad);
}

void IdrOptions::Check() const {
  zero_crossings.Check();
  matching.Check();
  rig::CheckParam(params::kIdrUniqueShare, unique_share);
  rig::CheckParam(params::kIdrZMinM, z_min_m);
  rig::CheckParam(params::kIdrMaxViewAngleDeg, max_view_angle_deg);
  rig::CheckParam(params::kIdrMaxSlantDeg, max_slant_deg);
  rig::CheckParam(params::kIdrMaxExpansion, max_expansion);
  rig::CheckParam(params::kIdrMinExpansion, min_expansion);
  rig::CheckParam(params::kIdrVergentSearchPx, vergent_search_px);
  rig::CheckParam(params::kIdrVergentBaselineM, vergent_baseline_m);
  rig::CheckParam(params::kIdrMaxStages, max_stages);
  rig::CheckParam(params::kIdrPatchSizePx, patch_size_px);
  rig::CheckParam(params::kIdrDiscontinuityJumpPx, discontinuity_jump_px);
  rig::CheckParam(params::kIdrInitialBaselineM, fixed_initial_baseline_m);
  plane_fit.Check(params::kIdrFitMinSupport, params::kIdrFitTolerancePx,
                  params::kIdrFitMinInlierShare);
  if (min_expansion > max_expansion)
    throw rig::InputError("key 'idr.min_expansion': " + rig::FormatParamNumber(min_expansion) +
                          " exceeds idr.max_expansion (" + rig::FormatParamNumber(max_expansion) +
                          ")");
}

PatchMap PatchesFromDisparities(const std::vector<DisparitySample>& samples,
                                const rig::CameraView& left, double baseline_m, int patch_size_px,
                                const PlaneFitOptions& options, PatchLevel level,
                                double max_view_angle_deg) {
  PatchMap map;
  const rig::CameraIntrinsics& k = left.intrinsics;
  // Bucket samples by block so each fit sees only its own.
  const int bw = (k.width_px + patch_size_px - 1) / patch_size_px;
  const int bh = (k.height_px + patch_size_px - 1) / patch_size_px;
  std::vector<std::vector<DisparitySample>> blocks(bw * bh);
  for (const auto& s : samples) {
    const int bx = static_cast<int>(s.x_px) / patch_size_px,
              by = static_cast<int>(s.y_px) / patch_size_px;
    if (bx >= 0 && bx < bw && by >= 0 && by < bh) blocks[by * bw + bx].push_back(s);
  }
  for (int by = 0; by < bh; ++by) {
    for (int bx = 0; bx < bw; ++bx) {
      const double x0 = bx * patch_size_px, y0 = by * patch_size_px;
      Eigen::Vector4d box;
      const auto fit = FitDisparityPlane(blocks[by * bw + bx], x0, y0, patch_size_px, patch_size_px,
                                         options, &box);
      if (!fit) continue;
      // The block, cut back to half a pixel beyond its inliers: inside
      // texture the inliers span the block (crossings on every row); at a
      // depth step the last crossings stop short of the edge, and the patch
      // must not reach over it.
      const double ex0 = std::max(x0 - 0.5, box(0) - 0.5), ey0 = std::max(y0 - 0.5, box(1) - 0.5);
      const double ex1 = std::min(x0 + patch_size_px - 0.5, box(2) + 0.5);
      const double ey1 = std::min(y0 + patch_size_px - 0.5, box(3) + 0.5);
      if (ex1 - ex0 < 2 || ey1 - ey0 < 2) continue;
      Patch p;
      p.level = level;
      p.fit_rms_px = fit->rms_px;
      p.support = fit->support;
      bool ok = true;
      // Block corners: pixel borders at -0.5 offsets.
      const double xs[4] = {ex0, ex1, ex1, ex0};
      const double ys[4] = {ey0, ey0, ey1, ey1};
      for (int c = 0; c < 4; ++c) {
        const double d = (*fit)(xs[c], ys[c]);
        if (!(d > 0.05)) {
          ok = false;
          break;
        }
        const double z = k.fx_px * baseline_m / d;
        p.corners_W[c] = left.world_T_camera * (z * k.Ray({xs[c], ys[c]}));
      }
      if (!ok) continue;
      // Crossings are located to about half a pixel, the fit no better.
      const Eigen::Vector3d right_W =
          left.world_T_camera.translation() + baseline_m * left.world_T_camera.linear().col(0);
      SetDepthSigma(&p, left, right_W, std::max(0.5, fit->rms_px));
      if (max_view_angle_deg > 0 &&
          !(p.ViewAngleRad(left.world_T_camera.translation()) <= max_view_angle_deg * M_PI / 180))
        continue;
      map.Add(p);
    }
  }
  return map;
}

namespace {

// One stage's matches as samples, the crossings searched but unmatched, and
// the figures that set the next expansion.
struct StageSamples {
  std::vector<DisparitySample> samples;
  std::vector<Eigen::Vector2d> unmatched;
};

StageSamples CollectSamples(const ZeroCrossingImage& zc_left, const std::vector<ZcMatch>& matches,
                            const DisparityWindows& left_windows, double unique_share,
                            IdrStage* stage) {
  StageSamples out;
  out.samples.reserve(matches.size());
  std::vector<char> matched(zc_left.crossings.size(), 0);
  for (const ZcMatch& m : matches) matched[m.left] = 1;
  for (size_t i = 0; i < zc_left.crossings.size(); ++i) {
    const ZeroCrossing& z = zc_left.crossings[i];
    double lo, hi;
    if (!matched[i] && left_windows.Window(z.x_px, z.y_px, &lo, &hi))
      out.unmatched.emplace_back(z.x_px, z.y_px);
  }
  std::vector<double> disparities, separations;
  const std::vector<float> periods = SamePolarityPeriods(zc_left);
  for (const ZcMatch& m : matches) {
    const ZeroCrossing& z = zc_left.crossings[m.left];
    out.samples.push_back({z.x_px, static_cast<double>(z.y_px), m.disparity_px});
    disparities.push_back(m.disparity_px);
    if (std::isfinite(periods[m.left])) separations.push_back(periods[m.left]);
  }
  stage->max_disparity_px = Quantile(disparities, 0.99);
  // s_min: the separation that all but (1 - unique_share) of crossings exceed.
  stage->min_separation_px = Quantile(separations, 1 - unique_share);
  return out;
}

// The samples the patches are fitted to: without isolated wrong matches and
// without the matches at depth discontinuities.
std::vector<DisparitySample> SmoothSamples(const std::vector<DisparitySample>& samples,
                                           const IdrOptions& options) {
  const double radius = 2 * options.zero_crossings.sigma_px;
  const std::vector<char> outlier =
      IsolatedOutliers(samples, radius, options.discontinuity_jump_px);
  std::vector<DisparitySample> clean;
  for (size_t i = 0; i < samples.size(); ++i)
    if (!outlier[i]) clean.push_back(samples[i]);
  const std::vector<char> at_edge = NearDiscontinuity(clean, radius, options.discontinuity_jump_px);
  std::vector<DisparitySample> smooth;
  for (size_t i = 0; i < clean.size(); ++i)
    if (!at_edge[i]) smooth.push_back(clean[i]);
  return smooth;
}

// Candidate first fixation: the well-supported patch nearest the centre.
void ChooseFirstFixation(const rig::CameraView& left, const IdrOptions& options,
                         IdrResult* result) {
  const rig::CameraIntrinsics& k = left.intrinsics;
  const Eigen::Isometry3d camera_T_world = left.world_T_camera.inverse();
  double best = 1e300;
  result->has_fixation = false;
  for (size_t i = 0; i < result->map.size(); ++i) {
    const Patch& p = result->map.patches()[i];
    if (p.support < 2 * options.plane_fit.min_support) continue;
    const Eigen::Vector3d c_C = camera_T_world * p.Centre();
    const double r = std::hypot(k.fx_px * c_C.x() / c_C.z(), k.fy_px * c_C.y() / c_C.z());
    if (r < best) {
      best = r;
      result->has_fixation = true;
      result->first_fixation_W = p.Centre();
      result->first_fixation_patch = static_cast<int>(i);
    }
  }
}

// The expansion after a stage at baseline b (1 = stop, with the reason in
// `result`). Termination (section II-C): the IDR depth uncertainty at the
// fixation, Z^2 0.5 / (f B), within what the vergent stage disambiguates
// with a +-P px search at its baseline, Z^2 P / (f B_v).
double NextExpansion(const IdrStage& stage, bool last_stage, bool any_match, double f,
                     double max_baseline, const IdrOptions& options, IdrResult* result) {
  const double b = stage.baseline_m;
  const bool precise_enough = b >= 0.5 * options.vergent_baseline_m / options.vergent_search_px;
  if (precise_enough && result->has_fixation) {
    result->stop_reason = "depth precise enough to verge";
    return 1;
  }
  if (last_stage) {
    result->stop_reason = "stage budget spent";
    return 1;
  }
  if (!any_match) {
    result->stop_reason = "no matches";
    return 1;
  }
  double expansion = std::min(options.max_expansion,
                              ExpansionFactor(stage.min_separation_px, stage.max_disparity_px, f,
                                              options.max_slant_deg * M_PI / 180));
  expansion = std::min(expansion, max_baseline / b);
  if (expansion < options.min_expansion) {
    result->stop_reason =
        b >= max_baseline - 1e-9 ? "widest baseline reached" : "expansion factor too small";
    return 1;
  }
  return expansion;
}

// Windows for the next stage: each match predicts k (d +- 0.5), at its left
// position and at its predicted right position.
void NextWindows(const std::vector<DisparitySample>& samples, double expansion, int rows,
                 double min_separation_px, DisparityWindows* left_windows,
                 DisparityWindows* right_windows) {
  *left_windows = DisparityWindows();
  *right_windows = DisparityWindows();
  left_windows->global = right_windows->global = false;
  left_windows->rows.assign(rows, {});
  right_windows->rows.assign(rows, {});
  left_windows->reach_px = right_windows->reach_px = std::max(2.0, 0.5 * min_separation_px);
  for (const DisparitySample& m : samples) {
    const float lo = static_cast<float>(expansion * (m.disparity_px - 0.5));
    const float hi = static_cast<float>(expansion * (m.disparity_px + 0.5));
    const int y = static_cast<int>(m.y_px);
    left_windows->rows[y].push_back({static_cast<float>(m.x_px), lo, hi});
    right_windows->rows[y].push_back(
        {static_cast<float>(m.x_px - expansion * m.disparity_px), lo, hi});
  }
  for (auto* w : {left_windows, right_windows})
    for (auto& row : w->rows)
      std::sort(row.begin(), row.end(),
                [](const auto& a, const auto& b) { return a.x_px < b.x_px; });
}

}  // namespace

IdrResult RunIdr(rig::Rig& rig, const IdrOptions& options) {
  options.Check();
  IdrResult result;
  const rig::RigLimits& limits = rig.Limits();
  const rig::AxisLimit& lb = limits[rig::Axis::kLeftBaseline];
  const rig::AxisLimit& rb = limits[rig::Axis::kRightBaseline];
  // The left camera stays put (its image and crossings anchor every stage);
  // the right carriage sets the baseline.
  const double left_x = lb.max;
  const double min_baseline = rb.min - left_x, max_baseline = rb.max - left_x;
  // Both cameras straight ahead, whatever their mounts and encoder zeros
  // (pan = tilt = 0 on an ideal rig), and the pair rectified in software
  // for what the stages cannot set (a no-op on an ideal rig).
  const rig::RigGeometry& geometry = rig.Geometry();
  // The baseline is between the optical centres: on a rig whose cameras
  // sit off their axes, turned differently, the carriages differ by more or
  // less than it.
  auto centre_x = [&](rig::Side side, double carriage) {
    return geometry.WorldFromCamera(side, geometry.ParallelStage(side, carriage)).translation().x();
  };
  const double left_centre_x = centre_x(rig::Side::kLeft, left_x);
  const double right_offset_x = centre_x(rig::Side::kRight, 0);
  auto move_and_capture = [&](double baseline, IdrStage* stage) {
    rig::StageState s;
    s.left = geometry.ParallelStage(rig::Side::kLeft, left_x);
    s.right = geometry.ParallelStage(
        rig::Side::kRight, std::clamp(left_centre_x + baseline - right_offset_x, rb.min, rb.max));
    const rig::MoveResult move = rig.MoveTo(s);
    if (stage) stage->motion_time_s = move.motion_time_s;
    result.motion_time_s += move.motion_time_s;
    return ToParallelFrame(rig.Capture());
  };

  // Initial baseline from one image (section II-A).
  rig::StereoFrame frame = move_and_capture(min_baseline, nullptr);
  const double f = frame.left.intrinsics.fx_px;
  auto t0 = Clock::now();
  const bool fixed = options.fixed_initial_baseline_m > 0;
  const double d_max0 = UnambiguousDisparityLimit(
      SamePolarityPeriods(ExtractZeroCrossings(frame.left.gray, options.zero_crossings)),
      options.unique_share);
  const double baseline0 = fixed ? options.fixed_initial_baseline_m : d_max0 * options.z_min_m / f;
  double baseline = std::clamp(baseline0, min_baseline, max_baseline);
  const double search_limit = fixed ? f * baseline / options.z_min_m : d_max0;
  result.compute_time_s += Since(t0);

  DisparityWindows left_windows, right_windows;
  left_windows.global = right_windows.global = true;
  left_windows.global_lo_px = right_windows.global_lo_px = -0.25;
  left_windows.global_hi_px = right_windows.global_hi_px = search_limit + 0.25;
  for (int s = 0; s < options.max_stages; ++s) {
    IdrStage stage;
    frame = move_and_capture(baseline, &stage);
    t0 = Clock::now();
    // The actual baseline, from the camera poses (quantized and settled):
    // the optical centres' offset along the rectified rows.
    const double b =
        (frame.right.world_T_camera.translation() - frame.left.world_T_camera.translation())
            .dot(frame.left.world_T_camera.linear().col(0));
    stage.baseline_m = b;
    stage.search_limit_px = left_windows.global ? left_windows.global_hi_px : 0;
    const ZeroCrossingImage zc_left = ExtractZeroCrossings(frame.left.gray, options.zero_crossings);
    const ZeroCrossingImage zc_right =
        ExtractZeroCrossings(frame.right.gray, options.zero_crossings);
    const auto matches = MatchZeroCrossings(zc_left, zc_right, left_windows, right_windows,
                                            options.matching, &stage.stats);
    StageSamples stage_samples =
        CollectSamples(zc_left, matches, left_windows, options.unique_share, &stage);
    result.final_frame = frame;
    result.final_samples = stage_samples.samples;
    result.final_unmatched = std::move(stage_samples.unmatched);
    result.map = PatchesFromDisparities(SmoothSamples(stage_samples.samples, options), frame.left,
                                        b, options.patch_size_px, options.plane_fit,
                                        PatchLevel::kIdr, options.max_view_angle_deg);
    ChooseFirstFixation(frame.left, options, &result);
    const double expansion = NextExpansion(stage, s + 1 == options.max_stages, !matches.empty(), f,
                                           max_baseline, options, &result);
    stage.expansion_factor = expansion;
    if (expansion > 1)
      NextWindows(stage_samples.samples, expansion, frame.left.intrinsics.height_px,
                  stage.min_separation_px, &left_windows, &right_windows);
    stage.compute_time_s = Since(t0);
    result.compute_time_s += stage.compute_time_s;
    result.stages.push_back(stage);
    if (expansion <= 1) break;
    baseline = b * expansion;
  }
  return result;
}

}  // namespace fovea
