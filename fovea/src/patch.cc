#include "fovea/patch.h"

#include <Eigen/Dense>
#include <cmath>
#include <limits>

namespace fovea {

const char* PatchLevelName(PatchLevel level) {
  switch (level) {
    case PatchLevel::kIdr: return "idr";
    case PatchLevel::kPeripheral: return "peripheral";
    case PatchLevel::kFoveal: return "foveal";
  }
  return "?";
}

Eigen::Vector3d Patch::Centre() const {
  return 0.25 * (corners_W[0] + corners_W[1] + corners_W[2] + corners_W[3]);
}

Eigen::Vector3d Patch::Normal() const {
  return (corners_W[2] - corners_W[0]).cross(corners_W[3] - corners_W[1]).normalized();
}

double Patch::SizeM() const {
  return std::max((corners_W[2] - corners_W[0]).norm(), (corners_W[3] - corners_W[1]).norm());
}

std::optional<PlaneFit> FitDisparityPlane(const std::vector<DisparitySample>& samples, double x0,
                                          double y0, double size, const PlaneFitOptions& options,
                                          Eigen::Vector4d* inlier_box) {
  // Centre coordinates on the block for conditioning.
  const double cx = x0 + 0.5 * size, cy = y0 + 0.5 * size;
  std::vector<const DisparitySample*> in_block;
  for (const auto& s : samples)
    if (s.x_px >= x0 && s.x_px < x0 + size && s.y_px >= y0 && s.y_px < y0 + size) in_block.push_back(&s);
  const int total = static_cast<int>(in_block.size());
  if (total < std::max(3, options.min_support)) return std::nullopt;

  std::vector<const DisparitySample*> inliers = in_block;
  PlaneFit fit;
  for (int round = 0; round < 3; ++round) {
    Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
    Eigen::Vector3d atb = Eigen::Vector3d::Zero();
    for (const DisparitySample* s : inliers) {
      const Eigen::Vector3d row(s->x_px - cx, s->y_px - cy, 1);
      ata += row * row.transpose();
      atb += row * s->disparity_px;
    }
    // Degenerate support (all on one line): tiny smallest eigenvalue.
    const Eigen::Vector3d eig = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(ata).eigenvalues();
    if (eig.minCoeff() < 1e-6 * eig.maxCoeff()) return std::nullopt;
    const Eigen::Vector3d p = ata.ldlt().solve(atb);
    fit.a = p(0);
    fit.b = p(1);
    fit.c = p(2) - p(0) * cx - p(1) * cy;
    std::vector<const DisparitySample*> kept;
    for (const DisparitySample* s : in_block)
      if (std::abs(s->disparity_px - fit(s->x_px, s->y_px)) <= options.fit_tolerance_px) kept.push_back(s);
    const bool converged = kept.size() == inliers.size();
    inliers.swap(kept);
    if (static_cast<int>(inliers.size()) < std::max(3, options.min_support)) return std::nullopt;
    if (converged) break;
  }
  if (inliers.size() < options.min_inlier_share * total) return std::nullopt;
  bool quadrant[4] = {false, false, false, false};
  double ss = 0;
  Eigen::Vector4d box(1e300, 1e300, -1e300, -1e300);
  for (const DisparitySample* s : inliers) {
    const double r = s->disparity_px - fit(s->x_px, s->y_px);
    ss += r * r;
    fit.max_abs_px = std::max(fit.max_abs_px, std::abs(r));
    quadrant[(s->x_px >= cx ? 1 : 0) + (s->y_px >= cy ? 2 : 0)] = true;
    box = Eigen::Vector4d(std::min(box(0), s->x_px), std::min(box(1), s->y_px),
                          std::max(box(2), s->x_px), std::max(box(3), s->y_px));
  }
  if (options.require_quadrants && !(quadrant[0] && quadrant[1] && quadrant[2] && quadrant[3]))
    return std::nullopt;
  fit.support = static_cast<int>(inliers.size());
  fit.rms_px = std::sqrt(ss / fit.support);
  if (inlier_box) *inlier_box = box;
  return fit;
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
  const double u = t.dot(p) * inv;
  if (u < 0 || u > 1) return -1;
  const Eigen::Vector3d q = t.cross(e1);
  const double v = d.dot(q) * inv;
  if (v < 0 || u + v > 1) return -1;
  const double dist = e2.dot(q) * inv;
  return dist > 0 ? dist : -1;
}
}  // namespace

std::optional<PatchHit> PatchMap::CastRay(const Eigen::Vector3d& origin_W,
                                          const Eigen::Vector3d& direction_W) const {
  PatchHit best;
  best.distance_m = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < patches_.size(); ++i) {
    const auto& c = patches_[i].corners_W;
    for (const auto& tri : {std::array<int, 3>{0, 1, 2}, std::array<int, 3>{0, 2, 3}}) {
      const double t = RayTriangle(origin_W, direction_W, c[tri[0]], c[tri[1]], c[tri[2]]);
      if (t > 0 && t < best.distance_m) {
        best.distance_m = t;
        best.patch = static_cast<int>(i);
      }
    }
  }
  if (best.patch < 0) return std::nullopt;
  return best;
}

void PatchMap::Render(const Eigen::Isometry3d& world_T_camera,
                      const rig::CameraIntrinsics& k, cv::Mat* depth_m, cv::Mat* patch_ids) const {
  cv::Mat depth(k.height_px, k.width_px, CV_32F, cv::Scalar(0));
  cv::Mat ids(k.height_px, k.width_px, CV_32S, cv::Scalar(-1));
  const Eigen::Isometry3d camera_T_world = world_T_camera.inverse();
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
        uv[j] = Eigen::Vector2d(k.fx_px * q.x() / q.z() + k.cx_px, k.fy_px * q.y() / q.z() + k.cy_px);
        inv_z[j] = 1.0 / q.z();
      }
      const double area = (uv[1] - uv[0]).x() * (uv[2] - uv[0]).y() - (uv[1] - uv[0]).y() * (uv[2] - uv[0]).x();
      if (std::abs(area) < 1e-12) continue;
      const int u0 = std::max(0, static_cast<int>(std::ceil(std::min({uv[0].x(), uv[1].x(), uv[2].x()}))));
      const int u1 = std::min(k.width_px - 1, static_cast<int>(std::floor(std::max({uv[0].x(), uv[1].x(), uv[2].x()}))));
      const int v0 = std::max(0, static_cast<int>(std::ceil(std::min({uv[0].y(), uv[1].y(), uv[2].y()}))));
      const int v1 = std::min(k.height_px - 1, static_cast<int>(std::floor(std::max({uv[0].y(), uv[1].y(), uv[2].y()}))));
      for (int v = v0; v <= v1; ++v) {
        for (int u = u0; u <= u1; ++u) {
          const Eigen::Vector2d p(u, v);
          auto edge = [](const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
            return (b - a).x() * (c - a).y() - (b - a).y() * (c - a).x();
          };
          const double w0 = edge(uv[1], uv[2], p) / area, w1 = edge(uv[2], uv[0], p) / area;
          const double w2 = 1 - w0 - w1;
          if (w0 < -1e-9 || w1 < -1e-9 || w2 < -1e-9) continue;
          const double z = 1.0 / (w0 * inv_z[0] + w1 * inv_z[1] + w2 * inv_z[2]);
          float& d = depth.at<float>(v, u);
          if (d == 0 || z < d) {
            d = static_cast<float>(z);
            ids.at<int>(v, u) = static_cast<int>(i);
          }
        }
      }
    }
  }
  if (depth_m) *depth_m = depth;
  if (patch_ids) *patch_ids = ids;
}

}  // namespace fovea
