#include "fovea/visibility.h"

#include <algorithm>
#include <array>
#include <bitset>
#include <cmath>
#include <cstdint>
#include <optional>

#include "fovea/geometry.h"
#include "fovea/parallel.h"

namespace fovea {
namespace {

// Bilinear grey level at (x, y), or nullopt outside the image's pixel
// centres.
std::optional<double> SampleGray(const cv::Mat& gray, const Eigen::Vector2d& p) {
  const double x = p.x(), y = p.y();
  if (!(x >= 0 && y >= 0 && x <= gray.cols - 1.001 && y <= gray.rows - 1.001)) return std::nullopt;
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
  const double fx = x - x0, fy = y - y0;
  const uchar* r0 = gray.ptr<uchar>(y0) + x0;
  const uchar* r1 = gray.ptr<uchar>(y0 + 1) + x0;
  return (1 - fy) * ((1 - fx) * r0[0] + fx * r0[1]) + fy * ((1 - fx) * r1[0] + fx * r1[1]);
}

// Sums for one normalized cross-correlation.
struct NccSums {
  int n = 0;
  double a = 0, b = 0, aa = 0, bb = 0, ab = 0;
  void Add(double x, double y) {
    ++n;
    a += x, b += y, aa += x * x, bb += y * y, ab += x * y;
  }
  double VarA() const { return n ? aa / n - (a / n) * (a / n) : 0; }
  double VarB() const { return n ? bb / n - (b / n) * (b / n) : 0; }
  NccSums& operator+=(const NccSums& o) {
    n += o.n;
    a += o.a, b += o.b, aa += o.aa, bb += o.bb, ab += o.ab;
    return *this;
  }
  double Ncc() const {
    const double va = aa - a * a / n, vb = bb - b * b / n, cov = ab - a * b / n;
    return va > 0 && vb > 0 ? cov / std::sqrt(va * vb) : 0;
  }
  /// Whether these samples, of `tried` sample points, are judged (at least
  /// 3/4 of them fell inside both images, at least `min_n` in all, and they
  /// vary by at least `min_var` in either image) and correlate below
  /// `min_ncc`: the part they cover is hidden from the reference camera. A
  /// faint surface the reference camera does not see, where it sees a
  /// textured one in front, is judged too; where it sees the faint surface
  /// itself, the samples vary little in both.
  bool Uncorrelated(int tried, double min_var, double min_ncc, int min_n = 0) const {
    return 4 * n >= 3 * tried && n >= min_n && std::max(VarA(), VarB()) >= min_var &&
           Ncc() < min_ncc;
  }
};

// The point of a patch at (s, t) in [0, 1]^2, bilinear between its corners
// (top-left, top-right, bottom-right, bottom-left): on its plane.
Eigen::Vector3d QuadPoint(const Patch& p, double s, double t) {
  const std::array<Eigen::Vector3d, 4>& c = p.corners_W;
  return (1 - t) * ((1 - s) * c[0] + s * c[1]) + t * ((1 - s) * c[3] + s * c[2]);
}

}  // namespace

bool HiddenSide(std::uint8_t quarters) {
  return (quarters & 5) == 5 || (quarters & 10) == 10 || std::bitset<4>(quarters).count() >= 3;
}

std::vector<std::uint8_t> HiddenQuarters(const PatchMap& patches, const rig::CameraView& measured,
                                         const rig::CameraView& reference,
                                         const ReferenceCheckOptions& options) {
  ReferenceCheckOptions quarters_only = options;
  quarters_only.side_px = 0;
  std::vector<std::uint8_t> hidden;
  for (const ReferenceSight& s : JudgeReference(patches, measured, reference, quarters_only))
    hidden.push_back(s.hidden_quarters);
  return hidden;
}

std::vector<ReferenceSight> JudgeReference(const PatchMap& patches, const rig::CameraView& measured,
                                           const rig::CameraView& reference,
                                           const ReferenceCheckOptions& options) {
  std::vector<ReferenceSight> sight(patches.size());
  if (options.min_ncc <= 0) return sight;
  const Eigen::Isometry3d m_T_w = measured.world_T_camera.inverse();
  const Eigen::Isometry3d r_T_w = reference.world_T_camera.inverse();
  const double min_var = options.min_texture_dn * options.min_texture_dn;
  // Each patch is judged alone: the patches are split between two threads,
  // each writing its own entries (the result does not depend on the split).
  auto judge = [&](size_t begin, size_t end) {
    for (size_t i = begin; i < end; ++i) {
      const Patch& patch = patches[i];
      // Samples about a pixel apart in the measuring image.
      double side_px = 0;
      for (int k = 0; k < 4; ++k) {
        const auto a = ProjectIntoCamera(m_T_w, measured.intrinsics, patch.corners_W[k]);
        const auto b = ProjectIntoCamera(m_T_w, measured.intrinsics, patch.corners_W[(k + 1) % 4]);
        if (a && b) side_px = std::max(side_px, (*a - *b).norm());
      }
      const int n = 2 * std::clamp(static_cast<int>(std::lround(side_px / 2)), 2, 16);
      // Side strips w samples wide (about side_px pixels of the measuring
      // image), judged from the samples kept per grid point.
      const int w =
          options.side_px > 0 && side_px > 0
              ? std::clamp(static_cast<int>(std::lround(options.side_px * n / side_px)), 1, n / 4)
              : 0;
      struct Sample {
        double m = 0, r = 0;
        bool ok = false;
      };
      std::vector<Sample> samples(w > 0 ? static_cast<size_t>(n) * n : 0);
      std::array<NccSums, 4> quarter;
      std::array<int, 4> tried{0, 0, 0, 0};
      for (int v = 0; v < n; ++v)
        for (int u = 0; u < n; ++u) {
          const Eigen::Vector3d x = QuadPoint(patch, (u + 0.5) / n, (v + 0.5) / n);
          const int q = (v >= n / 2) * 2 + (u >= n / 2);
          ++tried[q];
          const auto pm = ProjectIntoCamera(m_T_w, measured.intrinsics, x);
          const auto pr = ProjectIntoCamera(r_T_w, reference.intrinsics, x);
          if (!pm || !pr) continue;
          const auto gm = SampleGray(measured.gray, *pm), gr = SampleGray(reference.gray, *pr);
          if (!gm || !gr) continue;
          quarter[q].Add(*gm, *gr);
          if (w > 0) samples[static_cast<size_t>(v) * n + u] = {*gm, *gr, true};
        }
      std::uint8_t& hidden = sight[i].hidden_quarters;
      for (int q = 0; q < 4; ++q)
        if (quarter[q].Uncorrelated(tried[q], min_var, options.min_ncc))
          hidden |= std::uint8_t(1u << q);
      if (w > 0) {
        // The part kept, in samples: columns [u0, u1), rows [v0, v1). Side
        // by side (left, right, then top, bottom: the cameras move along
        // the rail, so occluding edges mostly run up and down), the outer
        // strip is cut if the reference camera does not see it, then the
        // next one in if it does not see that either. A strip runs only
        // along the part left, so that an occluded corner, cut with its
        // side, does not decide the perpendicular sides.
        std::array<int, 4> bound{0, n, 0, n};  // u0, u1, v0, v1
        for (int side = 0; side < 4; ++side)
          for (int k = 0; k < 2; ++k) {
            const bool across = side < 2;  // a column of samples, else a row
            const int lo = across ? bound[2] : bound[0], hi = across ? bound[3] : bound[1];
            const int edge = bound[side];
            const int first = side % 2 == 0 ? edge : edge - w;  // the strip's lines
            NccSums strip;
            int strip_tried = 0;
            for (int line = first; line < first + w; ++line)
              for (int along = lo; along < hi; ++along) {
                const Sample& x = across ? samples[static_cast<size_t>(along) * n + line]
                                         : samples[static_cast<size_t>(line) * n + along];
                ++strip_tried;
                if (x.ok) strip.Add(x.m, x.r);
              }
            if (!strip.Uncorrelated(strip_tried, min_var, options.min_ncc,
                                    ReferenceCheckOptions::kMinSideSamples))
              break;
            bound[side] += side % 2 == 0 ? w : -w;
          }
        Patch::Part& part = sight[i].part;
        part.s0 = double(bound[0]) / n;
        part.s1 = double(bound[1]) / n;
        part.t0 = double(bound[2]) / n;
        part.t1 = double(bound[3]) / n;
      }
      if (options.pooled_min_ncc <= 0) continue;
      // The left and the right column of quarters, then the whole patch.
      const double pooled_min_var = options.pooled_min_texture_dn * options.pooled_min_texture_dn;
      for (const std::uint8_t group : {std::uint8_t{5}, std::uint8_t{10}, std::uint8_t{15}}) {
        NccSums sums;
        int tried_group = 0;
        for (int q = 0; q < 4; ++q)
          if (group & (1u << q)) {
            sums += quarter[q];
            tried_group += tried[q];
          }
        if ((hidden & group) != group &&
            sums.Uncorrelated(tried_group, pooled_min_var, options.pooled_min_ncc,
                              ReferenceCheckOptions::kMinPooledSamples))
          hidden |= group;
      }
    }
  };
  constexpr size_t kThreadedMinPatches = 64;
  ForHalves(patches.size(), patches.size() >= kThreadedMinPatches, judge);
  return sight;
}

int MarkHiddenFromReference(PatchMap* patches, const rig::CameraView& measured,
                            const rig::CameraView& reference,
                            const ReferenceCheckOptions& options) {
  const std::vector<ReferenceSight> sight = JudgeReference(*patches, measured, reference, options);
  int count = 0;
  for (size_t i = 0; i < patches->size(); ++i) {
    // A patch whose every strip is cut is hidden as a whole.
    const bool hidden = HiddenSide(sight[i].hidden_quarters) || sight[i].part.Empty();
    patches->SetHiddenInReference(i, hidden);
    patches->SetReferencePart(i, sight[i].part);
    count += hidden;
  }
  return count;
}

PatchMap ReferenceMap(const PatchMap& map) {
  PatchMap seen;
  for (const Patch& p : map.patches()) {
    if (p.hidden_in_reference) continue;
    const Patch::Part& part = p.reference_part;
    if (part.Whole()) {
      seen.Add(p);
    } else if (!part.Empty()) {
      // The same plane, cut to the part (bilinear between coplanar corners).
      Patch cut = p;
      cut.corners_W = {QuadPoint(p, part.s0, part.t0), QuadPoint(p, part.s1, part.t0),
                       QuadPoint(p, part.s1, part.t1), QuadPoint(p, part.s0, part.t1)};
      seen.Add(cut);
    }
  }
  return seen;
}

void ClearFlankedFarther(int flank_px, cv::Mat* depth, cv::Mat* ids) {
  if (flank_px <= 0) return;
  const cv::Mat given = depth->clone();
  const float nearer = static_cast<float>(1 - kFlankNearerShare);
  for (int y = 0; y < given.rows; ++y) {
    const float* row = given.ptr<float>(y);
    for (int x = 0; x < given.cols; ++x) {
      const float z = row[x];
      if (!(z > 0)) continue;
      const int u0 = std::max(0, x - flank_px), u1 = std::min(given.cols - 1, x + flank_px);
      bool flanked = false;
      for (int u = u0; u <= u1 && !flanked; ++u) flanked = row[u] > 0 && row[u] < nearer * z;
      if (!flanked) continue;
      depth->at<float>(y, x) = 0;
      if (ids) ids->at<int>(y, x) = -1;
    }
  }
}

}  // namespace fovea
