#include "fovea/patch.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <utility>

#include "fovea/parallel.h"

namespace fovea {

const char* PatchLevelName(PatchLevel level) {
  switch (level) {
    case PatchLevel::kIdr:
      return "idr";
    case PatchLevel::kPeripheral:
      return "peripheral";
    case PatchLevel::kFoveal:
      return "foveal";
  }
  return "?";
}

Eigen::Vector3d Patch::Centre() const {
  return 0.25 * (corners_W[0] + corners_W[1] + corners_W[2] + corners_W[3]);
}

Eigen::Vector3d Patch::Normal() const {
  return (corners_W[2] - corners_W[0]).cross(corners_W[3] - corners_W[1]).normalized();
}

double Patch::ViewAngleRad(const Eigen::Vector3d& eye_W) const {
  const double c = std::abs(Normal().dot((Centre() - eye_W).normalized()));
  return std::acos(std::min(1.0, c));
}

double Patch::SizeM() const {
  return std::max((corners_W[2] - corners_W[0]).norm(), (corners_W[3] - corners_W[1]).norm());
}

double DepthSigma(double z_m, double sigma_d_px, double focal_px, const Eigen::Vector3d& baseline_W,
                  const Eigen::Vector3d& ray_W) {
  const double b_perp = baseline_W.cross(ray_W.normalized()).norm();
  if (!(b_perp > 1e-9) || !(focal_px > 0)) return std::numeric_limits<double>::infinity();
  return z_m * z_m * sigma_d_px / (focal_px * b_perp);
}

void SetDepthSigma(Patch* patch, const rig::CameraView& left, const Eigen::Vector3d& right_centre_W,
                   double sigma_d_px) {
  const Eigen::Vector3d c_W = patch->Centre(), left_W = left.world_T_camera.translation();
  const double z = (left.world_T_camera.inverse() * c_W).z();
  patch->sigma_z_m =
      DepthSigma(z, sigma_d_px, left.intrinsics.fx_px, right_centre_W - left_W, c_W - left_W);
}

bool PatchMap::SameSurface(double za, const Patch& a, double zb, const Patch& b) {
  // |za - zb| <= max(share min(za, zb), sigmas hypot(sigma_a, sigma_b)),
  // decided without the hypot (slow, and Render asks per pixel drawn over
  // another) where its bounds max(|sa|, |sb|) <= hypot <= |sa| + |sb|
  // settle it with a margin for rounding; the same answer everywhere.
  const double diff = std::abs(za - zb);
  if (diff <= kSameSurfaceShare * std::min(za, zb)) return true;
  const double sa = std::abs(a.sigma_z_m), sb = std::abs(b.sigma_z_m);
  if (diff > kSameSurfaceSigmas * (sa + sb) * (1 + 1e-12)) return false;
  if (diff < kSameSurfaceSigmas * std::max(sa, sb) * (1 - 1e-12)) return true;
  return diff <= kSameSurfaceSigmas * std::hypot(a.sigma_z_m, b.sigma_z_m);
}

void PlaneFitOptions::Check(const rig::ParamSpec& min_support_spec,
                            const rig::ParamSpec& fit_tolerance_spec,
                            const rig::ParamSpec& min_inlier_share_spec) const {
  rig::CheckParam(min_support_spec, min_support);
  rig::CheckParam(fit_tolerance_spec, fit_tolerance_px);
  rig::CheckParam(min_inlier_share_spec, min_inlier_share);
}

std::optional<PlaneFit> FitDisparityPlane(const std::vector<DisparitySample>& samples, double x0,
                                          double y0, double width, double height,
                                          const PlaneFitOptions& options,
                                          Eigen::Vector4d* inlier_box, Quad2d* inlier_quad) {
  // Centre coordinates on the block for conditioning.
  const double cx = x0 + 0.5 * width, cy = y0 + 0.5 * height;
  std::vector<const DisparitySample*> in_block;
  for (const auto& s : samples)
    if (s.x_px >= x0 && s.x_px < x0 + width && s.y_px >= y0 && s.y_px < y0 + height)
      in_block.push_back(&s);
  const int total = static_cast<int>(in_block.size());
  if (total < std::max(3, options.min_support)) return std::nullopt;

  std::vector<const DisparitySample*> inliers = in_block;
  PlaneFit fit;
  for (int round = 0; round < 3; ++round) {
    // The normal equations' sums, in registers: the products and their order
    // are those of accumulating row * row^T and row * d with Eigen.
    double xx = 0, xy = 0, x1 = 0, yy = 0, y1 = 0, n = 0, xd = 0, yd = 0, d1 = 0;
    for (const DisparitySample* s : inliers) {
      const double x = s->x_px - cx, y = s->y_px - cy, d = s->disparity_px;
      xx += x * x, xy += x * y, x1 += x, yy += y * y, y1 += y, n += 1;
      xd += x * d, yd += y * d, d1 += d;
    }
    Eigen::Matrix3d ata;
    ata << xx, xy, x1, xy, yy, y1, x1, y1, n;
    const Eigen::Vector3d atb(xd, yd, d1);
    // Degenerate support (all on one line): tiny smallest eigenvalue.
    const Eigen::Vector3d eig = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(ata).eigenvalues();
    if (eig.minCoeff() < 1e-6 * eig.maxCoeff()) return std::nullopt;
    const Eigen::Vector3d p = ata.ldlt().solve(atb);
    fit.a = p(0);
    fit.b = p(1);
    fit.c = p(2) - p(0) * cx - p(1) * cy;
    std::vector<const DisparitySample*> kept;
    for (const DisparitySample* s : in_block)
      if (std::abs(s->disparity_px - fit(s->x_px, s->y_px)) <= options.fit_tolerance_px)
        kept.push_back(s);
    const bool converged = kept.size() == inliers.size();
    inliers.swap(kept);
    if (static_cast<int>(inliers.size()) < std::max(3, options.min_support)) return std::nullopt;
    if (converged) break;
  }
  if (inliers.size() < options.min_inlier_share * total) return std::nullopt;
  bool quadrant[4] = {false, false, false, false};
  double ss = 0;
  Eigen::Vector4d box(1e300, 1e300, -1e300, -1e300);
  // The bounding inliers' extremes along the diagonals: the least x + y,
  // the most x - y, the most x + y, the least x - y (the first in the
  // samples' order on a tie), as (sign of x, sign of y) per corner.
  constexpr int kSx[4] = {-1, 1, 1, -1}, kSy[4] = {-1, -1, 1, 1};
  const DisparitySample* extreme[4] = {nullptr, nullptr, nullptr, nullptr};
  for (const DisparitySample* s : inliers) {
    const double r = s->disparity_px - fit(s->x_px, s->y_px);
    ss += r * r;
    fit.max_abs_px = std::max(fit.max_abs_px, std::abs(r));
    quadrant[(s->x_px >= cx ? 1 : 0) + (s->y_px >= cy ? 2 : 0)] = true;
    if (s->bounds) {
      box = Eigen::Vector4d(std::min(box(0), s->x_px), std::min(box(1), s->y_px),
                            std::max(box(2), s->x_px), std::max(box(3), s->y_px));
      for (int c = 0; c < 4; ++c)
        if (!extreme[c] || kSx[c] * s->x_px + kSy[c] * s->y_px >
                               kSx[c] * extreme[c]->x_px + kSy[c] * extreme[c]->y_px)
          extreme[c] = s;
    }
  }
  if (options.require_quadrants && !(quadrant[0] && quadrant[1] && quadrant[2] && quadrant[3]))
    return std::nullopt;
  if (inlier_box && box(0) > box(2)) return std::nullopt;  // no inlier bounds
  fit.support = static_cast<int>(inliers.size());
  fit.measurements = total;
  fit.rms_px = std::sqrt(ss / fit.support);
  if (inlier_box) *inlier_box = box;
  if (inlier_quad && extreme[0])
    for (int c = 0; c < 4; ++c)
      (*inlier_quad)[c] =
          Eigen::Vector2d(extreme[c]->x_px + 0.5 * kSx[c], extreme[c]->y_px + 0.5 * kSy[c]);
  return fit;
}

Quad2d BoxQuad(const Eigen::Vector4d& box) {
  return {Eigen::Vector2d(box(0), box(1)), Eigen::Vector2d(box(2), box(1)),
          Eigen::Vector2d(box(2), box(3)), Eigen::Vector2d(box(0), box(3))};
}

namespace {

// Whether a fit over `area` pixels is whole by BlockOptions' rule: its
// inliers fill `fill` of it (any fit, with fill 0) and at most 5% of its
// measurements are outliers (measurements of another surface).
bool Whole(const std::optional<PlaneFit>& fit, double area, double fill) {
  if (fill <= 0) return fit.has_value();
  return fit && fit->support >= fill * area &&
         fit->measurements - fit->support <= std::max(1.0, 0.05 * double(fit->measurements));
}

// The plane of `samples` over the rectangle [x0, x0 + w) x [y0, y0 + h) of
// block (bx, by, size) if the rectangle is whole, its footprint its inliers'
// box.
std::optional<BlockFit> WholeHalf(const std::vector<DisparitySample>& samples, int bx, int by,
                                  int size, int x0, int y0, int w, int h,
                                  const PlaneFitOptions& options, double fill) {
  Eigen::Vector4d box;
  const auto fit = FitDisparityPlane(samples, x0, y0, w, h, options, &box, nullptr);
  if (!Whole(fit, double(w) * h, fill)) return std::nullopt;
  BlockFit half{bx, by, size, *fit};
  half.footprint = Eigen::Vector4d(box(0) - 0.5, box(1) - 0.5, box(2) + 0.5, box(3) + 0.5);
  half.corners = BoxQuad(half.footprint);
  return half;
}

// The whole halves of a block that is not whole: side by side, or one above
// the other, whichever cut's whole halves hold more inliers (BlockOptions::
// half_agreement).
std::vector<BlockFit> WholeHalves(const std::vector<DisparitySample>& samples, int bx, int by,
                                  int size, const PlaneFitOptions& options, double fill) {
  const int half = size / 2;
  std::vector<BlockFit> best;
  int best_support = 0;
  for (const bool above : {false, true}) {
    std::vector<BlockFit> halves;
    int support = 0;
    for (int h = 0; h < 2; ++h)
      if (const auto f = WholeHalf(samples, bx, by, size, above ? bx : bx + h * half,
                                   above ? by + h * half : by, above ? size : half,
                                   above ? half : size, options, fill)) {
        halves.push_back(*f);
        support += f->fit.support;
      }
    if (support > best_support) {
      best = std::move(halves);
      best_support = support;
    }
  }
  return best;
}

// A block's planes into `out` by BlockOptions' rule; with
// BlockOptions::half_agreement, the whole halves of a smallest block that is
// not whole into `halves`, for FitBlocks to check against their neighbours.
void FitBlock(const cv::Mat& disparity, const cv::Mat& unbounded, int bx, int by, int size,
              const PlaneFitOptions& options, const BlockOptions& blocks,
              std::vector<BlockFit>* out, std::vector<BlockFit>* halves) {
  PlaneFitOptions o = options;
  o.min_support = std::min(options.min_support, (3 * size * size) / 4);
  std::vector<DisparitySample> samples;
  samples.reserve(static_cast<size_t>(size) * size);
  const bool all_bound = unbounded.empty();
  const int x_end = std::min(bx + size, disparity.cols);
  for (int y = by; y < std::min(by + size, disparity.rows); ++y) {
    const float* row = disparity.ptr<float>(y);
    const uchar* free_row = all_bound ? nullptr : unbounded.ptr<uchar>(y);
    for (int x = bx; x < x_end; ++x)
      if (std::isfinite(row[x]))
        samples.push_back({double(x), double(y), row[x], all_bound || free_row[x] == 0});
  }
  if (samples.empty()) return;
  Eigen::Vector4d box;
  Quad2d quad;
  const bool hull = blocks.clip_to_inliers && blocks.clip_diagonals;
  const auto fit =
      FitDisparityPlane(samples, bx, by, size, size, o, blocks.clip_to_inliers ? &box : nullptr,
                        hull ? &quad : nullptr);
  // One plane for the whole block when it is whole; else its quarters are
  // tried, and a smallest block that is not whole is left out.
  const double fill = blocks.min_fill_share;
  if (Whole(fit, double(size) * size, fill)) {
    BlockFit b{bx, by, size, *fit};
    b.footprint = blocks.clip_to_inliers
                      ? Eigen::Vector4d(box(0) - 0.5, box(1) - 0.5, box(2) + 0.5, box(3) + 0.5)
                      : Eigen::Vector4d(bx - 0.5, by - 0.5, bx + size - 0.5, by + size - 0.5);
    b.corners = hull ? quad : BoxQuad(b.footprint);
    out->push_back(b);
    return;
  }
  const int half = size / 2;
  if (fill <= 0) return;
  if (half < blocks.min_block_px) {
    if (blocks.half_agreement > 0 && half >= 1) {
      const std::vector<BlockFit> whole = WholeHalves(samples, bx, by, size, o, fill);
      halves->insert(halves->end(), whole.begin(), whole.end());
    }
    return;
  }
  for (int q = 0; q < 4; ++q)
    FitBlock(disparity, unbounded, bx + (q % 2) * half, by + (q / 2) * half, half, options, blocks,
             out, halves);
}

}  // namespace

std::vector<BlockFit> FitBlocks(const cv::Mat& disparity, int size, const PlaneFitOptions& options,
                                const BlockOptions& blocks,
                                const std::function<bool(int x, int y, int size)>& keep,
                                const cv::Mat& unbounded) {
  // A large level's block rows on two threads, the lower half's fits
  // appended after the upper's: the same fits in the same order.
  constexpr int kThreadedMinBlocks = 256;
  const int rows = disparity.rows / size;
  std::vector<BlockFit> out, lower, halves, lower_halves;
  ForHalves(
      rows, rows * (disparity.cols / size) >= kThreadedMinBlocks, [&](size_t first, size_t end) {
        std::vector<BlockFit>* fits = first == 0 ? &out : &lower;
        std::vector<BlockFit>* cut = first == 0 ? &halves : &lower_halves;
        for (int row = static_cast<int>(first); row < static_cast<int>(end); ++row)
          for (int bx = 0; bx + size <= disparity.cols; bx += size)
            if (!keep || keep(bx, row * size, size))
              FitBlock(disparity, unbounded, bx, row * size, size, options, blocks, fits, cut);
      });
  out.insert(out.end(), lower.begin(), lower.end());
  halves.insert(halves.end(), lower_halves.begin(), lower_halves.end());
  if (halves.empty()) return out;
  // A half is kept where a whole block beside its block (left, right, above
  // or below) has a plane within half_agreement fit tolerances of its own at
  // each of its footprint's corners: it extends a surface found whole.
  std::map<std::pair<int, int>, const BlockFit*> whole;
  for (const BlockFit& b : out)
    if (b.size == size) whole.emplace(std::make_pair(b.x, b.y), &b);
  const double agreement_px = blocks.half_agreement * options.fit_tolerance_px;
  std::vector<BlockFit> extending;
  for (const BlockFit& h : halves) {
    const int nx[4] = {h.x - size, h.x + size, h.x, h.x};
    const int ny[4] = {h.y, h.y, h.y - size, h.y + size};
    for (int k = 0; k < 4; ++k) {
      const auto it = whole.find({nx[k], ny[k]});
      if (it == whole.end()) continue;
      double worst = 0;
      for (const Eigen::Vector2d& c : h.corners)
        worst = std::max(worst, std::abs(it->second->fit(c.x(), c.y()) - h.fit(c.x(), c.y())));
      if (worst <= agreement_px) {
        extending.push_back(h);
        break;
      }
    }
  }
  out.insert(out.end(), extending.begin(), extending.end());
  return out;
}

namespace {
// Moller-Trumbore ray/triangle intersection; distance or -1.
double RayTriangle(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& a,
                   const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d e1 = b - a, e2 = c - a;
  const Eigen::Vector3d p = d.cross(e2);
  const double det = e1.dot(p);
  if (std::abs(det) < 1e-15) return -1;
  const double inv = 1.0 / det;
  const Eigen::Vector3d t = o - a;
  // Edges are closed with a margin for rounding: a ray through the diagonal
  // two triangles of a quad share (or an edge two patches share) must hit
  // one of them, not slip between both.
  constexpr double kEdge = 1e-9;
  const double u = t.dot(p) * inv;
  if (u < -kEdge || u > 1 + kEdge) return -1;
  const Eigen::Vector3d q = t.cross(e1);
  const double v = d.dot(q) * inv;
  if (v < -kEdge || u + v > 1 + kEdge) return -1;
  const double dist = e2.dot(q) * inv;
  return dist > 0 ? dist : -1;
}
}  // namespace

void PatchMap::Add(const Patch& patch) {
  patches_.push_back(patch);
  index_valid_ = false;
}

void PatchMap::Append(const PatchMap& other) {
  patches_.insert(patches_.end(), other.patches_.begin(), other.patches_.end());
  index_valid_ = false;
}

void PatchMap::Clear() {
  patches_.clear();
  index_valid_ = false;
}

size_t PatchMap::Remove(const std::vector<char>& drop) {
  size_t kept = 0;
  for (size_t i = 0; i < patches_.size(); ++i)
    if (i >= drop.size() || !drop[i]) patches_[kept++] = patches_[i];
  const size_t removed = patches_.size() - kept;
  patches_.resize(kept);
  if (removed) index_valid_ = false;
  return removed;
}

std::array<int, 3> PatchMap::CountByLevel() const {
  std::array<int, 3> n{0, 0, 0};
  for (const Patch& p : patches_) ++n[static_cast<int>(p.level)];
  return n;
}

namespace {
constexpr int kLeafSize = 4;

// Nearest hit of the ray on a patch's two triangles, or +infinity.
double RayPatch(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Patch& p) {
  double best = std::numeric_limits<double>::infinity();
  const auto& c = p.corners_W;
  for (const auto& tri : {std::array<int, 3>{0, 1, 2}, std::array<int, 3>{0, 2, 3}}) {
    const double t = RayTriangle(o, d, c[tri[0]], c[tri[1]], c[tri[2]]);
    if (t > 0 && t < best) best = t;
  }
  return best;
}

// Entry distance of the ray into the box (slab test), or +infinity if missed.
double RayBox(const Eigen::Vector3d& o, const Eigen::Vector3d& inv_d,
              const Eigen::AlignedBox3d& b) {
  double t0 = 0, t1 = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    double ta = (b.min()(a) - o(a)) * inv_d(a), tb = (b.max()(a) - o(a)) * inv_d(a);
    if (std::isnan(ta) || std::isnan(tb)) {  // ray parallel to the slab, origin on its plane
      if (o(a) < b.min()(a) || o(a) > b.max()(a)) return std::numeric_limits<double>::infinity();
      continue;
    }
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return std::numeric_limits<double>::infinity();
  }
  return t0;
}
}  // namespace

int PatchMap::BuildNode(int first, int count, std::vector<Eigen::AlignedBox3d>* boxes,
                        std::vector<Eigen::Vector3d>* centres) const {
  Node node;
  Eigen::AlignedBox3d centre_box;
  for (int i = first; i < first + count; ++i) {
    node.box.extend((*boxes)[order_[i]]);
    centre_box.extend((*centres)[order_[i]]);
  }
  const int id = static_cast<int>(nodes_.size());
  nodes_.push_back(node);
  if (count <= kLeafSize) {
    nodes_[id].first = first;
    nodes_[id].count = count;
    return id;
  }
  // Median split along the widest axis of the centres.
  int axis;
  centre_box.sizes().maxCoeff(&axis);
  const int mid = first + count / 2;
  std::nth_element(order_.begin() + first, order_.begin() + mid, order_.begin() + first + count,
                   [&](int a, int b) { return (*centres)[a](axis) < (*centres)[b](axis); });
  const int left = BuildNode(first, mid - first, boxes, centres);
  const int right = BuildNode(mid, first + count - mid, boxes, centres);
  nodes_[id].left = left;
  nodes_[id].right = right;
  return id;
}

void PatchMap::BuildIndex() const {
  if (index_valid_) return;
  nodes_.clear();
  order_.resize(patches_.size());
  std::vector<Eigen::AlignedBox3d> boxes(patches_.size());
  std::vector<Eigen::Vector3d> centres(patches_.size());
  for (size_t i = 0; i < patches_.size(); ++i) {
    order_[i] = static_cast<int>(i);
    for (const auto& c : patches_[i].corners_W) boxes[i].extend(c);
    centres[i] = boxes[i].center();
  }
  if (!patches_.empty()) {
    nodes_.reserve(2 * patches_.size() / kLeafSize + 2);
    BuildNode(0, static_cast<int>(patches_.size()), &boxes, &centres);
  }
  index_valid_ = true;
}

std::optional<PatchHit> PatchMap::CastRay(const Eigen::Vector3d& origin_W,
                                          const Eigen::Vector3d& direction_W) const {
  BuildIndex();
  if (nodes_.empty()) return std::nullopt;
  const Eigen::Vector3d inv_d = direction_W.cwiseInverse();
  PatchHit best;
  best.distance_m = std::numeric_limits<double>::infinity();
  // Depth-first, nearer child first, pruning boxes entered beyond the best hit.
  std::vector<std::pair<double, int>> stack;
  stack.reserve(64);
  const double t_root = RayBox(origin_W, inv_d, nodes_[0].box);
  if (std::isfinite(t_root)) stack.emplace_back(t_root, 0);
  while (!stack.empty()) {
    const auto [t_enter, id] = stack.back();
    stack.pop_back();
    if (t_enter >= best.distance_m) continue;
    const Node& n = nodes_[id];
    if (n.left < 0) {
      for (int i = n.first; i < n.first + n.count; ++i) {
        const double t = RayPatch(origin_W, direction_W, patches_[order_[i]]);
        if (t < best.distance_m || (t == best.distance_m && order_[i] < best.patch)) {
          best.distance_m = t;
          best.patch = order_[i];
        }
      }
      continue;
    }
    const double tl = RayBox(origin_W, inv_d, nodes_[n.left].box);
    const double tr = RayBox(origin_W, inv_d, nodes_[n.right].box);
    // Push the farther first so that the nearer is visited first.
    if (tl <= tr) {
      if (std::isfinite(tr)) stack.emplace_back(tr, n.right);
      if (std::isfinite(tl)) stack.emplace_back(tl, n.left);
    } else {
      if (std::isfinite(tl)) stack.emplace_back(tl, n.left);
      if (std::isfinite(tr)) stack.emplace_back(tr, n.right);
    }
  }
  if (best.patch < 0) return std::nullopt;
  return best;
}

std::optional<PatchHit> PatchMap::CastRayBruteForce(const Eigen::Vector3d& origin_W,
                                                    const Eigen::Vector3d& direction_W) const {
  PatchHit best;
  best.distance_m = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < patches_.size(); ++i) {
    const double t = RayPatch(origin_W, direction_W, patches_[i]);
    if (t < best.distance_m) {
      best.distance_m = t;
      best.patch = static_cast<int>(i);
    }
  }
  if (best.patch < 0) return std::nullopt;
  return best;
}

void PatchMap::Render(const Eigen::Isometry3d& world_T_camera, const rig::CameraIntrinsics& k,
                      cv::Mat* depth_m, cv::Mat* patch_ids, const cv::Rect& region) const {
  // The pixels drawn: the region within the image (the whole image when
  // the region is empty).
  const cv::Rect image(0, 0, k.width_px, k.height_px);
  const cv::Rect drawn = region.empty() ? image : region & image;
  cv::Mat depth(k.height_px, k.width_px, CV_32F, cv::Scalar(0));
  cv::Mat ids(k.height_px, k.width_px, CV_32S, cv::Scalar(-1));
  const Eigen::Isometry3d camera_T_world = world_T_camera.inverse();
  // The rows are drawn in bands of kBandRows. draw(begin, end) draws the
  // bands whose parity (band index mod 2) is in [begin, end), going through
  // every patch in order: on two threads each draws every other band, and
  // each pixel sees the patches in the same order as on one, so the render
  // does not depend on the split.
  constexpr int kBandRows = 8;
  auto draw = [&](size_t begin, size_t end) {
    for (size_t i = 0; i < patches_.size(); ++i) {
      std::array<Eigen::Vector3d, 4> p_C;
      bool in_front = true;
      for (int j = 0; j < 4; ++j) {
        p_C[j] = camera_T_world * patches_[i].corners_W[j];
        if (p_C[j].z() < 1e-3) in_front = false;
      }
      if (!in_front) continue;
      // Rasterize the two triangles; 1/z is affine in screen space.
      for (const auto& tri : {std::array<int, 3>{0, 1, 2}, std::array<int, 3>{0, 2, 3}}) {
        Eigen::Vector2d uv[3];
        double inv_z[3];
        for (int j = 0; j < 3; ++j) {
          const Eigen::Vector3d& q = p_C[tri[j]];
          uv[j] =
              Eigen::Vector2d(k.fx_px * q.x() / q.z() + k.cx_px, k.fy_px * q.y() / q.z() + k.cy_px);
          inv_z[j] = 1.0 / q.z();
        }
        const double area =
            (uv[1] - uv[0]).x() * (uv[2] - uv[0]).y() - (uv[1] - uv[0]).y() * (uv[2] - uv[0]).x();
        if (std::abs(area) < 1e-12) continue;
        const int u0 = std::max(
            drawn.x, static_cast<int>(std::ceil(std::min({uv[0].x(), uv[1].x(), uv[2].x()}))));
        const int u1 =
            std::min(drawn.x + drawn.width - 1,
                     static_cast<int>(std::floor(std::max({uv[0].x(), uv[1].x(), uv[2].x()}))));
        const int v0 = std::max(
            drawn.y, static_cast<int>(std::ceil(std::min({uv[0].y(), uv[1].y(), uv[2].y()}))));
        const int v1 =
            std::min(drawn.y + drawn.height - 1,
                     static_cast<int>(std::floor(std::max({uv[0].y(), uv[1].y(), uv[2].y()}))));
        // The barycentric weights w0, w1, w2 (of uv[0], uv[1], uv[2]) are
        // affine in the pixel, w = du u + dv v + c, and 1/z is affine in them:
        // per pixel three products and one division. Each pixel's two edge
        // functions and three divisions took 1.2 times as long for the whole
        // render (6000 small patches over a 640 x 480 view).
        struct Affine {
          double du, dv, c;
        };
        // The edge function of (a, b) at p over the area: the weight of the
        // vertex opposite that edge.
        auto weight = [area](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
          const Eigen::Vector2d e = b - a;
          return Affine{-e.y() / area, e.x() / area, (e.y() * a.x() - e.x() * a.y()) / area};
        };
        const std::array<Affine, 3> f = {weight(uv[1], uv[2]), weight(uv[2], uv[0]),
                                         weight(uv[0], uv[1])};
        // Inside, each weight is at least -1e-9 (the test's tolerance); far
        // wider here, so that no rounding excludes a column the test would take.
        const double tolerance = 1e-6 * (1 + 1 / (area * area));
        const double iz0 = inv_z[0] - inv_z[2], iz1 = inv_z[1] - inv_z[2];
        float* const depth_rows = depth.ptr<float>(0);
        int* const id_rows = ids.ptr<int>(0);
        for (int v = v0; v <= v1; ++v) {
          if (const auto parity = static_cast<size_t>((v / kBandRows) % 2);
              parity < begin || parity >= end) {
            v = (v / kBandRows + 1) * kBandRows - 1;  // on to the next band's first row
            continue;
          }
          // The row's columns inside the triangle, with a pixel to spare
          // either side: only they are tested below, which decides. Along the
          // row each weight is du * u + offset.
          double lo = u0 - 1, hi = u1 + 1;
          for (const Affine& w : f) {
            const double offset = w.dv * v + w.c + tolerance;
            if (w.du > 0) lo = std::max(lo, -offset / w.du);
            if (w.du < 0) hi = std::min(hi, -offset / w.du);
          }
          // Both bounds within [u0 - 1, u1 + 1] before the conversion (a
          // sliver's edge can put one far beyond the image).
          const int first =
              std::max(u0, static_cast<int>(std::floor(std::clamp(lo, u0 - 1.0, u1 + 1.0))) - 1);
          const int last =
              std::min(u1, static_cast<int>(std::ceil(std::clamp(hi, u0 - 1.0, u1 + 1.0))) + 1);
          const double r0 = f[0].dv * v + f[0].c, r1 = f[1].dv * v + f[1].c;
          float* const depth_row = depth_rows + static_cast<size_t>(v) * k.width_px;
          int* const id_row = id_rows + static_cast<size_t>(v) * k.width_px;
          for (int u = first; u <= last; ++u) {
            const double w0 = f[0].du * u + r0, w1 = f[1].du * u + r1;
            const double w2 = 1 - w0 - w1;
            if (w0 < -1e-9 || w1 < -1e-9 || w2 < -1e-9) continue;
            const double z = 1.0 / (inv_z[2] + w0 * iz0 + w1 * iz1);
            float& d = depth_row[u];
            int& id = id_row[u];
            bool take = d == 0 || z < d;
            if (d != 0 && SameSurface(z, patches_[i], d, patches_[id])) {
              // The same surface seen twice: the finer level wins.
              const int mine = patches_[i].Fineness(), theirs = patches_[id].Fineness();
              take = mine > theirs || (mine == theirs && z < d);
            }
            if (take) {
              d = static_cast<float>(z);
              id = static_cast<int>(i);
            }
          }
        }
      }
    }
  };
  // Two threads where there are patches and pixels enough to share: every
  // thread projects every patch, and a small view's render is mostly that.
  constexpr size_t kThreadedMinPatches = 256;
  constexpr int kThreadedMinPixels = 1 << 17;
  ForHalves(2, patches_.size() >= kThreadedMinPatches && drawn.area() >= kThreadedMinPixels, draw);
  if (depth_m) *depth_m = depth;
  if (patch_ids) *patch_ids = ids;
}

}  // namespace fovea
