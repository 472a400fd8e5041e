#include "experiments/scoring/run_eval.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <opencv2/imgproc.hpp>

#include "fovea/geometry.h"
#include "fovea/integration.h"
#include "fovea/stats.h"
#include "fovea/visibility.h"
#include "sim/sim_rig.h"

namespace experiments {
using fovea::Quantile;
namespace {

struct Accumulator {
  long bad = 0, bad_nearer = 0;
  std::vector<double> abs, rel, steps;
  double sum_sq = 0, sum_abs = 0;
  long within = 0;
  void Add(double z, double zt, double step) {
    if (!(std::abs(z - zt) <= kBadShare * zt)) {
      ++bad;
      bad_nearer += z < zt;
    }
    const double e = std::abs(z - zt);
    abs.push_back(e);
    rel.push_back(e / zt);
    steps.push_back(e / step);
    sum_sq += e * e;
    sum_abs += e;
    within += e <= 0.01 * zt;
  }
  /// The figures over `total` pixels; takes the medians in place, so once.
  ErrorFigures Figures(long total) {
    ErrorFigures f;
    f.pixels = static_cast<long>(abs.size());
    f.bad = bad;
    f.bad_nearer = bad_nearer;
    f.share = total ? double(f.pixels) / total : 0;
    if (abs.empty()) return f;
    f.median_abs_error_m = fovea::QuantileInPlace(&abs, 0.5);
    f.mean_abs_error_m = sum_abs / abs.size();
    f.rmse_m = std::sqrt(sum_sq / abs.size());
    f.median_rel_error = fovea::QuantileInPlace(&rel, 0.5);
    f.within_1pct = double(within) / abs.size();
    f.median_error_steps = fovea::QuantileInPlace(&steps, 0.5);
    return f;
  }
};

// Whether the right camera's optical centre, its carriage at one of
// `carriages` and its head turned to p_W, has p_W in sight.
bool RightCameraSees(const rig::RigGeometry& geometry, const std::vector<double>& carriages,
                     const sim::GroundTruth& truth, const Eigen::Vector3d& p_W) {
  // p_W lies on a surface: the ray reaches that surface within this share.
  constexpr double kOnSurfaceShare = 0.005;
  for (const double s : carriages) {
    const Eigen::Vector3d c =
        geometry.WorldFromCamera(rig::Side::kRight, geometry.FacingStage(rig::Side::kRight, s, p_W))
            .translation();
    const Eigen::Vector3d d = p_W - c;
    const double distance = d.norm();
    const auto hit = truth.CastRay(c, d / distance);
    if (!hit || hit->distance_m >= (1 - kOnSurfaceShare) * distance) return true;
  }
  return false;
}

}  // namespace

cv::Mat DepthEdges(const cv::Mat& depth_m) {
  cv::Mat edge = cv::Mat::zeros(depth_m.size(), CV_8U);
  auto z = [&](int y, int x) {
    const float d = depth_m.at<float>(y, x);
    return d > 0 ? double(d) : 1e9;
  };
  for (int y = 0; y < depth_m.rows; ++y)
    for (int x = 0; x < depth_m.cols; ++x) {
      const double here = z(y, x);
      if ((x + 1 < depth_m.cols && std::abs(here - z(y, x + 1)) > kEdgeJumpM) ||
          (y + 1 < depth_m.rows && std::abs(here - z(y + 1, x)) > kEdgeJumpM)) {
        edge.at<uchar>(y, x) = 255;
        if (x + 1 < depth_m.cols && std::abs(here - z(y, x + 1)) > kEdgeJumpM)
          edge.at<uchar>(y, x + 1) = 255;
        if (y + 1 < depth_m.rows && std::abs(here - z(y + 1, x)) > kEdgeJumpM)
          edge.at<uchar>(y + 1, x) = 255;
      }
    }
  return edge;
}

namespace {

// Pixels within kEdgeRadiusPx of an edge pixel.
cv::Mat NearEdge(const cv::Mat& edges) {
  cv::Mat near;
  cv::dilate(
      edges, near,
      cv::getStructuringElement(cv::MORPH_RECT, {2 * kEdgeRadiusPx + 1, 2 * kEdgeRadiusPx + 1}));
  return near;
}

}  // namespace

// The true camera's depths (`true_z`, along its axis, at the delivered
// pixels) as depths along the axis of the camera that delivered them (the
// rig turns its images to its head by the mount it believes in): what a map
// rendered into the delivered view is compared with. On an imperfect rig
// the axes differ by a degree or two: at 20 cm off the axis, a centimetre of
// depth.
cv::Mat DeliveredDepth(const cv::Mat& true_z, const sim::SimRig::TrueCamera& true_camera) {
  if (true_camera.delivered_R_camera.isIdentity(0)) return true_z;
  cv::Mat out = true_z.clone();
  for (int y = 0; y < out.rows; ++y)
    for (int x = 0; x < out.cols; ++x) {
      float& z = out.at<float>(y, x);
      if (z <= 0) continue;
      z = static_cast<float>(true_camera.delivered_R_camera.row(2).dot(
          z * true_camera.ideal.Ray(true_camera.IdealPixel(x, y))));
    }
  return out;
}

ReferenceView MakeReferenceView(rig::Rig& rig, sim::Simulation& sim) {
  const sim::GroundTruth& truth = sim.truth();
  ReferenceView ref;
  rig.MoveTo(rig.Home());
  ref.view = rig.Capture().left;
  // The scene's model at the same pose (a hardware run's rig is another).
  if (&rig != &sim.rig()) sim.rig().MoveTo(sim.rig().Home());
  // The truth of what the delivered image shows: the true camera (on an
  // imperfect rig, not where the rig believes it is), its labels carried to
  // the delivered pixels (nearest: depths and ids are not blended).
  const sim::SimRig::TrueCamera true_camera = sim.sim_rig().True(rig::Side::kLeft);
  sim::GroundTruth::Labels labels =
      truth.RenderLabels(true_camera.world_T_camera, true_camera.ideal);
  if (!true_camera.map_x.empty()) {
    cv::Mat depth, ids;
    cv::remap(labels.depth_m, depth, true_camera.map_x, true_camera.map_y, cv::INTER_NEAREST,
              cv::BORDER_CONSTANT, cv::Scalar(0));
    cv::remap(labels.geom_ids, ids, true_camera.map_x, true_camera.map_y, cv::INTER_NEAREST,
              cv::BORDER_CONSTANT, cv::Scalar(-1));
    labels.depth_m = depth;
    labels.geom_ids = ids;
  }
  ref.depth_m = labels.depth_m;
  ref.geom_ids = labels.geom_ids;
  ref.textured = truth.TexturedMask(ref.geom_ids);
  ref.textured_pixels = cv::countNonZero(ref.textured);
  ref.depth_edges = DepthEdges(ref.depth_m);
  ref.near_edge = NearEdge(ref.depth_edges);

  const rig::AxisLimit& travel = rig.Limits()[rig::Axis::kRightBaseline];
  std::vector<double> carriages;
  for (int i = 0; i < kStereoPositions; ++i)
    carriages.push_back(travel.min + (travel.max - travel.min) * i / (kStereoPositions - 1));
  const Eigen::Vector3d axis = true_camera.world_T_camera.linear().col(2);
  const rig::RigGeometry& geometry = rig.Geometry();
  // Ray casts cost tens of microseconds each against a mesh: first the
  // depth buffer of each carriage position's right camera (60 degrees wide,
  // the head turned to the reference view's centre at its mean depth)
  // accepts the points it shows within 1% of their depth; exact ray casts
  // decide the rest.
  constexpr double kDepthShare = 0.01;
  const double mean_depth = cv::mean(ref.depth_m, ref.textured)[0];
  const Eigen::Vector3d centre_W =
      ref.view.world_T_camera * Eigen::Vector3d(0, 0, mean_depth > 0 ? mean_depth : 1);
  const rig::CameraIntrinsics wide = rig::CameraIntrinsics::FromHorizontalFov(
      ref.view.intrinsics.width_px, ref.view.intrinsics.height_px, M_PI / 3);
  struct Seen {
    Eigen::Isometry3d camera_T_world;
    cv::Mat depth_m;
  };
  std::vector<Seen> renders;
  for (const double s : carriages) {
    const Eigen::Isometry3d world_T_camera = geometry.WorldFromCamera(
        rig::Side::kRight, geometry.FacingStage(rig::Side::kRight, s, centre_W));
    renders.push_back({world_T_camera.inverse(), truth.Render(world_T_camera, wide).depth_m});
  }
  auto rendered = [&](const Eigen::Vector3d& p_W) {
    for (const Seen& seen : renders) {
      const Eigen::Vector3d q = seen.camera_T_world * p_W;
      if (q.z() <= 0) continue;
      const int u = static_cast<int>(std::lround(wide.fx_px * q.x() / q.z() + wide.cx_px));
      const int v = static_cast<int>(std::lround(wide.fy_px * q.y() / q.z() + wide.cy_px));
      if (u < 0 || v < 0 || u >= seen.depth_m.cols || v >= seen.depth_m.rows) continue;
      if (seen.depth_m.at<float>(v, u) >= (1 - kDepthShare) * q.z()) return true;
    }
    return false;
  };
  ref.stereo_visible = cv::Mat::zeros(ref.textured.size(), CV_8U);
  for (int y = 0; y < ref.textured.rows; ++y)
    for (int x = 0; x < ref.textured.cols; ++x) {
      const float z = ref.depth_m.at<float>(y, x);
      if (!ref.textured.at<uchar>(y, x) || z <= 0) continue;
      const fovea::Ray ray = fovea::PixelRay(true_camera.world_T_camera, true_camera.ideal,
                                             true_camera.IdealPixel(x, y));
      const Eigen::Vector3d p = ray.origin_W + ray.direction_W * (z / ray.direction_W.dot(axis));
      if (rendered(p) || RightCameraSees(geometry, carriages, truth, p))
        ref.stereo_visible.at<uchar>(y, x) = 255;
    }
  ref.stereo_visible_pixels = cv::countNonZero(ref.stereo_visible);
  ref.depth_m = DeliveredDepth(ref.depth_m, true_camera);
  return ref;
}

namespace {

// The area of a simple polygon (shoelace formula), either orientation.
double PolygonArea(const std::vector<Eigen::Vector2d>& p) {
  double twice = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    const Eigen::Vector2d& a = p[i];
    const Eigen::Vector2d& b = p[(i + 1) % p.size()];
    twice += a.x() * b.y() - b.x() * a.y();
  }
  return 0.5 * std::abs(twice);
}

// A convex polygon clipped to the box [lo, hi] (Sutherland-Hodgman: one
// edge of the box at a time).
std::vector<Eigen::Vector2d> ClipToBox(std::vector<Eigen::Vector2d> p, const Eigen::Vector2d& lo,
                                       const Eigen::Vector2d& hi) {
  for (int axis = 0; axis < 2; ++axis)
    for (const double sign : {1.0, -1.0}) {
      // Keep the points with sign * (x[axis] - bound) >= 0.
      const double bound = sign > 0 ? lo[axis] : hi[axis];
      auto inside = [&](const Eigen::Vector2d& q) { return sign * (q[axis] - bound) >= 0; };
      std::vector<Eigen::Vector2d> out;
      for (size_t i = 0; i < p.size(); ++i) {
        const Eigen::Vector2d& a = p[i];
        const Eigen::Vector2d& b = p[(i + 1) % p.size()];
        if (inside(a)) out.push_back(a);
        if (inside(a) != inside(b))
          out.push_back(a + (b - a) * ((bound - a[axis]) / (b[axis] - a[axis])));
      }
      p = std::move(out);
    }
  return p;
}

}  // namespace

int StaleIdrPatches(const fovea::PatchMap& map, const rig::CameraView& view,
                    const std::vector<char>& off_surface) {
  const Eigen::Isometry3d camera_T_world = view.world_T_camera.inverse();
  const rig::CameraIntrinsics& k = view.intrinsics;
  int stale = 0;
  const std::vector<std::vector<fovea::IdrCover>> coverage = fovea::IdrCoverage(map, {view});
  for (const fovea::IdrCover& c : coverage.front()) {
    if (c.shown == 0) continue;
    // The part of the footprint past the image's border counts as not
    // covered: a sliver in view says nothing of the rest.
    std::vector<Eigen::Vector2d> quad;
    for (const Eigen::Vector3d& corner : map[c.index].corners_W) {
      const Eigen::Vector3d p_C = camera_T_world * corner;
      if (p_C.z() <= 0) break;
      quad.push_back(k.Project(p_C));
    }
    if (quad.size() != 4) continue;
    const double outside =
        PolygonArea(quad) -
        PolygonArea(ClipToBox(quad, {-0.5, -0.5}, {k.width_px - 0.5, k.height_px - 0.5}));
    const double footprint = c.shown + std::max(0.0, outside);
    const long covered = c.same_surface + (off_surface.at(c.index) ? c.in_front : 0);
    stale += covered >= kStaleCoveredShare * footprint;
  }
  return stale;
}

namespace {

// Whether a patch's centre lies more than kBadShare of its depth in `view`
// from the true surface, measured along the view's line of sight through
// it, either way: the nearest surface along that line, as if nothing stood
// in front (a patch the view sees behind a nearer surface is judged on its
// own).
bool OffSurface(const fovea::Patch& p, const rig::CameraView& view, const sim::GroundTruth& truth) {
  const Eigen::Vector3d origin = view.world_T_camera.translation();
  const Eigen::Vector3d axis = view.world_T_camera.linear().col(2);
  const Eigen::Vector3d c = p.Centre(), line = (c - origin).normalized();
  double nearest = std::numeric_limits<double>::infinity();
  for (const double sign : {1.0, -1.0})
    if (const auto hit = truth.CastRay(c, sign * line))
      nearest = std::min(nearest, hit->distance_m);
  return !(nearest <= kBadShare * std::abs((c - origin).dot(axis)));
}

// Each patch's 3D error: the distance from its centre to the true surface
// along its normal (either way); and the IDR patches finer data has made stale.
void ScorePatches(const fovea::PatchMap& map, const rig::CameraView& view,
                  const sim::GroundTruth& truth, MapScore* s) {
  s->has_patch_error = true;
  std::vector<double> err;
  // IDR patches whose centre is more than kBadShare of its depth off the
  // true surface (OffSurface).
  std::vector<char> off_surface(map.size(), 0);
  for (size_t i = 0; i < map.size(); ++i) {
    const fovea::Patch& p = map[i];
    const Eigen::Vector3d c = p.Centre(), n = p.Normal();
    double best = std::numeric_limits<double>::infinity();
    for (const double sign : {1.0, -1.0}) {
      const auto hit = truth.CastRay(c, sign * n);
      if (hit) best = std::min(best, hit->distance_m);
    }
    if (std::isfinite(best)) err.push_back(best);
    off_surface[i] = p.level == fovea::PatchLevel::kIdr && OffSurface(p, view, truth);
  }
  s->patches_scored = static_cast<int>(err.size());
  s->patch_error_median_m = Quantile(err, 0.5);
  s->patch_error_p90_m = Quantile(err, 0.9);
  s->stale_idr_patches = StaleIdrPatches(map, view, off_surface);
}

}  // namespace

void RenderInReference(const fovea::PatchMap& map, int flank_px, const ReferenceView& ref,
                       cv::Mat* depth, cv::Mat* ids) {
  map.Render(ref.view.world_T_camera, ref.view.intrinsics, depth, ids);
  fovea::ClearFlankedFarther(flank_px, depth, ids);
}

MapScore ScoreMap(const fovea::PatchMap& map, int flank_px, const ReferenceView& ref,
                  const sim::GroundTruth& truth, double baseline_m, bool per_patch) {
  MapScore s;
  cv::Mat depth, ids;
  RenderInReference(map, flank_px, ref, &depth, &ids);
  const double f = ref.view.intrinsics.fx_px;
  Accumulator all, edges, edges_idr;
  std::array<Accumulator, 3> level;
  std::array<Accumulator, 6> resolution, edges_resolution;
  struct PerSurface {
    long pixels = 0, mapped = 0, foveal = 0, stereo_visible = 0;
    Accumulator errors;
  };
  std::map<int, PerSurface> surfaces;
  int last_geom = 0;
  PerSurface* last = nullptr;  // surfaces[last_geom]: neighbours mostly share a surface
  long mapped = 0, foveal = 0, mapped_stereo_visible = 0, edge_visible = 0;
  all.abs.reserve(ref.textured_pixels);
  all.rel.reserve(ref.textured_pixels);
  all.steps.reserve(ref.textured_pixels);
  for (int y = 0; y < depth.rows; ++y)
    for (int x = 0; x < depth.cols; ++x) {
      if (!ref.textured.at<uchar>(y, x)) continue;
      const double zt = ref.depth_m.at<float>(y, x);
      const int geom = ref.geom_ids.at<int>(y, x);
      if (!last || geom != last_geom) {
        last_geom = geom;
        last = &surfaces[geom];
      }
      PerSurface& ps = *last;
      ++ps.pixels;
      const bool paired = ref.stereo_visible.at<uchar>(y, x);
      ps.stereo_visible += paired;
      const bool near_edge = ref.near_edge.at<uchar>(y, x);
      edge_visible += near_edge;
      const int id = ids.at<int>(y, x);
      if (id < 0 || zt <= 0) continue;
      mapped_stereo_visible += paired;
      const double z = depth.at<float>(y, x);
      const int lv = static_cast<int>(map[id].level);
      ++mapped;
      ++ps.mapped;
      if (lv == static_cast<int>(fovea::PatchLevel::kFoveal)) ++foveal, ++ps.foveal;
      const double step = zt * zt / (f * baseline_m);
      all.Add(z, zt, step);
      if (near_edge) edges.Add(z, zt, step);
      level[lv].Add(z, zt, step);
      if (map[id].level == fovea::PatchLevel::kIdr) {
        if (near_edge) edges_idr.Add(z, zt, step);
      } else {
        const int r = std::clamp(map[id].resolution_level, 0, 5);
        resolution[r].Add(z, zt, step);
        if (near_edge) edges_resolution[r].Add(z, zt, step);
      }
      ps.errors.Add(z, zt, step);
    }
  const long total = ref.textured_pixels;
  s.coverage = total ? double(mapped) / total : 0;
  s.foveal_coverage = total ? double(foveal) / total : 0;
  s.stereo_visible_share = total ? double(ref.stereo_visible_pixels) / total : 0;
  s.stereo_visible_coverage =
      ref.stereo_visible_pixels ? double(mapped_stereo_visible) / ref.stereo_visible_pixels : 0;
  s.overall = all.Figures(total);
  s.good_coverage = total ? double(s.overall.pixels - s.overall.bad) / total : 0;
  s.near_edges = edges.Figures(total);
  s.edge_visible_pixels = edge_visible;
  if (edge_visible > 0) {
    s.edge_coverage = double(s.near_edges.pixels) / edge_visible;
    s.edge_good_coverage = double(s.near_edges.pixels - s.near_edges.bad) / edge_visible;
  }
  s.near_edges_idr = edges_idr.Figures(total);
  for (int i = 0; i < 6; ++i) s.near_edges_by_resolution[i] = edges_resolution[i].Figures(total);
  for (int i = 0; i < 3; ++i) s.by_level[i] = level[i].Figures(total);
  for (int i = 0; i < 6; ++i) s.by_resolution[i] = resolution[i].Figures(total);
  for (auto& [geom, ps] : surfaces) {
    SurfaceFigures sf;
    sf.name = truth.GeomName(geom);
    sf.pixels = ps.pixels;
    sf.mapped = ps.mapped;
    sf.coverage = double(ps.mapped) / ps.pixels;
    sf.foveal_coverage = double(ps.foveal) / ps.pixels;
    sf.stereo_visible_share = double(ps.stereo_visible) / ps.pixels;
    const ErrorFigures e = ps.errors.Figures(ps.pixels);
    sf.median_abs_error_m = e.median_abs_error_m;
    sf.median_rel_error = e.median_rel_error;
    sf.median_error_steps = e.median_error_steps;
    sf.rmse_m = e.rmse_m;
    s.surfaces.push_back(sf);
  }
  if (per_patch) ScorePatches(map, ref.view, truth, &s);
  return s;
}

cv::Mat ErrorPicture(const fovea::PatchMap& map, int flank_px, const ReferenceView& ref) {
  cv::Mat depth;
  RenderInReference(map, flank_px, ref, &depth);
  cv::Mat out(ref.view.gray.size(), CV_8UC3);
  constexpr double kFullRed = 0.05;  // relative error shown at full brightness
  for (int y = 0; y < out.rows; ++y)
    for (int x = 0; x < out.cols; ++x) {
      const int g = ref.view.gray.at<uchar>(y, x) / 2;
      cv::Vec3b& o = out.at<cv::Vec3b>(y, x);
      o = {uchar(g), uchar(g), uchar(g)};
      const double z = depth.at<float>(y, x), zt = ref.depth_m.at<float>(y, x);
      if (ref.textured.at<uchar>(y, x) && z > 0 && zt > 0) {
        const double rel = std::abs(z - zt) / zt;
        if (rel <= kBadShare) {
          o = {uchar(g / 2), uchar(160 + g / 2), uchar(g / 2)};
        } else {
          const double t = std::min(1.0, (rel - kBadShare) / (kFullRed - kBadShare));
          const uchar v = uchar(140 + 115 * t);
          o = z < zt ? cv::Vec3b(uchar(g / 3), uchar(g / 3), v) : cv::Vec3b(v, uchar(g / 3), v);
        }
      }
      if (!ref.depth_edges.empty() && ref.depth_edges.at<uchar>(y, x)) o = {255, 80, 0};
    }
  return out;
}

namespace {
// A figure over `pixels` values: null when there were none.
nlohmann::json Figure(long pixels, double value) {
  return pixels > 0 ? nlohmann::json(value) : nlohmann::json();
}

// Share of a figure's pixels that are bad: null over no pixel.
nlohmann::json BadShare(const ErrorFigures& f) {
  return Figure(f.pixels, f.pixels ? double(f.bad) / f.pixels : 0);
}

// Share of a figure's bad pixels that the map puts nearer than the truth
// (a nearer surface's depth carried over its edge, window matching's
// fattening) rather than farther (a farther surface's patch seen where the
// nearer surface is unmapped, or a plane tilted away): null without a bad
// pixel.
nlohmann::json BadNearerShare(const ErrorFigures& f) {
  return Figure(f.bad, f.bad ? double(f.bad_nearer) / f.bad : 0);
}

// The pixels of a figure, their bad share and its nearer part.
nlohmann::json BadJson(const ErrorFigures& f) {
  return {
      {"pixels", f.pixels}, {"bad_share", BadShare(f)}, {"bad_nearer_share", BadNearerShare(f)}};
}

nlohmann::json ErrorJson(const ErrorFigures& f) {
  nlohmann::json j = BadJson(f);
  j.update({{"share", f.share},
            {"median_abs_error_m", Figure(f.pixels, f.median_abs_error_m)},
            {"mean_abs_error_m", Figure(f.pixels, f.mean_abs_error_m)},
            {"rmse_m", Figure(f.pixels, f.rmse_m)},
            {"median_rel_error", Figure(f.pixels, f.median_rel_error)},
            {"within_1pct", Figure(f.pixels, f.within_1pct)},
            {"median_error_steps", Figure(f.pixels, f.median_error_steps)}});
  return j;
}
}  // namespace

nlohmann::json ScoreJson(const MapScore& s) {
  const long n = s.overall.pixels;
  nlohmann::json j;
  j["coverage"] = s.coverage;
  j["foveal_coverage"] = s.foveal_coverage;
  j["stereo_visible_share"] = s.stereo_visible_share;
  j["stereo_visible_coverage"] = s.stereo_visible_coverage;
  j["median_abs_error_m"] = Figure(n, s.overall.median_abs_error_m);
  j["median_rel_error"] = Figure(n, s.overall.median_rel_error);
  j["rmse_m"] = Figure(n, s.overall.rmse_m);
  j["mean_abs_error_m"] = Figure(n, s.overall.mean_abs_error_m);
  j["within_1pct"] = Figure(n, s.overall.within_1pct);
  j["median_error_steps"] = Figure(n, s.overall.median_error_steps);
  for (int i = 0; i < 6; ++i)
    if (s.by_resolution[i].pixels > 0)
      j["by_resolution"][std::to_string(i)] = ErrorJson(s.by_resolution[i]);
  j["good_coverage"] = s.good_coverage;
  j["bad_share"] = BadShare(s.overall);
  j["edge_bad_share"] = BadShare(s.near_edges);
  j["edge_pixels"] = s.near_edges.pixels;
  // Null where the view holds no pixel beside a depth edge.
  j["edge_visible_pixels"] = s.edge_visible_pixels;
  j["edge_coverage"] = Figure(s.edge_visible_pixels, s.edge_coverage);
  j["edge_good_coverage"] = Figure(s.edge_visible_pixels, s.edge_good_coverage);
  // Where the pixels near edges come from: IDR, or a resolution level.
  j["edge_bad_nearer_share"] = BadNearerShare(s.near_edges);
  j["edge_by_source"]["idr"] = BadJson(s.near_edges_idr);
  for (int i = 0; i < 6; ++i)
    if (s.near_edges_by_resolution[i].pixels > 0)
      j["edge_by_source"][std::to_string(i)] = BadJson(s.near_edges_by_resolution[i]);
  for (int i = 0; i < 3; ++i)
    j["by_level"][fovea::PatchLevelName(static_cast<fovea::PatchLevel>(i))] =
        ErrorJson(s.by_level[i]);
  for (const SurfaceFigures& sf : s.surfaces)
    j["by_surface"][sf.name] = {{"pixels", sf.pixels},
                                {"coverage", sf.coverage},
                                {"foveal_coverage", sf.foveal_coverage},
                                {"stereo_visible_share", sf.stereo_visible_share},
                                {"median_abs_error_m", Figure(sf.mapped, sf.median_abs_error_m)},
                                {"median_rel_error", Figure(sf.mapped, sf.median_rel_error)},
                                {"median_error_steps", Figure(sf.mapped, sf.median_error_steps)},
                                {"rmse_m", Figure(sf.mapped, sf.rmse_m)}};
  if (s.has_patch_error) {
    j["patch_3d_error"] = {{"patches", s.patches_scored},
                           {"median_m", Figure(s.patches_scored, s.patch_error_median_m)},
                           {"p90_m", Figure(s.patches_scored, s.patch_error_p90_m)}};
    j["stale_idr_patches"] = s.stale_idr_patches;
  }
  return j;
}

CommonPixels CompareOnCommonPixels(const fovea::PatchMap& map, int flank_px,
                                   const fovea::PatchMap& other, const ReferenceView& ref) {
  cv::Mat a, b;
  RenderInReference(map, flank_px, ref, &a);
  other.Render(ref.view.world_T_camera, ref.view.intrinsics, &b, nullptr);
  std::vector<double> ea, eb;
  for (int y = 0; y < a.rows; ++y)
    for (int x = 0; x < a.cols; ++x) {
      const double zt = ref.depth_m.at<float>(y, x);
      if (!ref.textured.at<uchar>(y, x) || zt <= 0 || a.at<float>(y, x) <= 0 ||
          b.at<float>(y, x) <= 0)
        continue;
      ea.push_back(std::abs(a.at<float>(y, x) - zt));
      eb.push_back(std::abs(b.at<float>(y, x) - zt));
    }
  return {static_cast<long>(ea.size()), Quantile(ea, 0.5), Quantile(eb, 0.5)};
}

std::string ScoreLine(const MapScore& s, bool brief) {
  char line[256];
  const ErrorFigures& e = s.overall;
  if (e.pixels == 0) {
    std::snprintf(line, sizeof line, "coverage %.3f, foveal %.3f, median error - (no mapped pixel)",
                  s.coverage, s.foveal_coverage);
  } else if (brief) {
    std::snprintf(line, sizeof line, "coverage %.3f, foveal %.3f, median error %.2f mm", s.coverage,
                  s.foveal_coverage, 1e3 * e.median_abs_error_m);
  } else {
    std::snprintf(
        line, sizeof line,
        "coverage %.3f, foveal %.3f, median error %.2f mm (%.3f%% of depth), RMSE %.2f mm",
        s.coverage, s.foveal_coverage, 1e3 * e.median_abs_error_m, 100 * e.median_rel_error,
        1e3 * e.rmse_m);
  }
  return line;
}

}  // namespace experiments
