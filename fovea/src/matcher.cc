#include "fovea/matcher.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "fovea/params.h"

namespace fovea {

void Nl1Options::Check() const {
  rig::CheckParam(params::kNl1WindowHalfPx, window_half_px);
  rig::CheckParam(params::kNl1MinTextureDn, min_texture_dn);
  rig::CheckParam(params::kNl1LrTolerancePx, lr_tolerance_px);
  rig::CheckParam(params::kNl1Cost, cost);
}

Nl1Matcher::Nl1Matcher(const Nl1Options& options) : options_(options) { options_.Check(); }

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

// The hot loops are written for the compiler to vectorize. With GCC on
// x86-64 each is also built for AVX2 and picked at load time by the CPU
// (the same arithmetic in the same order: results do not depend on which
// runs; no FMA is enabled).
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define FOVEA_SIMD_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define FOVEA_SIMD_CLONES
#endif
// The level is matched in strips of this many rows; each disparity's costs
// span only the columns some pixel of the strip needs them at.
constexpr int kStripRows = 16;

// The matching costs of one strip of rows: the cost at (x, y, d) is that of
// the left window centred at (x, y) against the right window at (x - d, y),
// +inf where the right window leaves the image. Each disparity d holds the
// columns [x0[d], x0[d] + width[d]), x fastest (Row). Row y needs d only
// over [RowFirst(y, d), RowEnd(y, d)), a part of those (empty: first >=
// end); a fill that costs O(window area) computes only that part.
struct CostVolume {
  int y0 = 0, rows = 0, dlo = 0, nd = 0;
  std::vector<int> x0, width;
  std::vector<size_t> offset;
  std::vector<float> c;
  std::vector<int> row_first, row_end;  ///< [(y - y0) * nd + d - dlo]
  float* Row(int y, int d) {
    const int i = d - dlo;
    return &c[offset[i] + static_cast<size_t>(y - y0) * width[i]];
  }
  int RowFirst(int y, int d) const { return row_first[(y - y0) * nd + d - dlo]; }
  int RowEnd(int y, int d) const { return row_end[(y - y0) * nd + d - dlo]; }
};

// The rows of a strip and their windows, per disparity d, for the
// box-summed costs: diff[row * span + i] = op(a, b) of the left pixel at
// column x0 - h + i and the right pixel d to its left, 0 where that right
// pixel leaves the image (those columns are masked later). Inlined into
// each caller, so that it is built with the caller's instruction set.
template <typename In, typename Out, typename Op>
inline __attribute__((always_inline)) void StripDifferences(const cv::Mat& a, const cv::Mat& b,
                                                            const CostVolume& v, int d, int h,
                                                            int x0, int span, Op op,
                                                            std::vector<Out>* diff) {
  const int first = std::clamp(d - (x0 - h), 0, span),
            last = std::clamp(a.cols + d - (x0 - h), 0, span);
  diff->resize(static_cast<size_t>(v.rows + 2 * h) * span);
  for (int row = 0; row < v.rows + 2 * h; ++row) {
    const In* __restrict pa = a.ptr<In>(v.y0 - h + row) + (x0 - h);
    const In* __restrict pb = b.ptr<In>(v.y0 - h + row) + (x0 - h - d);
    Out* __restrict out = &(*diff)[static_cast<size_t>(row) * span];
    std::fill(out, out + first, Out{0});
    for (int i = first; i < last; ++i) out[i] = op(pa[i], pb[i]);
    std::fill(out + last, out + span, Out{0});
  }
}

// The pre-normalized cost: each image less its local mean (a, b), then
// the mean over the window of |a - b|, box-summed for a whole strip and
// disparity at once: O(1) per pixel and disparity in the window's area
// (passes of 2h + 1 additions along contiguous rows, which the compiler
// vectorizes).
FOVEA_SIMD_CLONES void FillPrenormalized(const cv::Mat& a, const cv::Mat& b, int h, CostVolume* v) {
  const int n = 2 * h + 1, cols = a.cols;
  const float scale = 1.0f / (n * n);
  std::vector<float> diff, vsum;
  for (int d = v->dlo; d < v->dlo + v->nd; ++d) {
    const int width = v->width[d - v->dlo];
    if (width <= 0) continue;
    const int x0 = v->x0[d - v->dlo], span = width + 2 * h;
    vsum.resize(span);
    StripDifferences<float>(
        a, b, *v, d, h, x0, span, [](float p, float q) { return std::abs(p - q); }, &diff);
    // Column sums of n diff rows, run down the strip (add the row entering
    // the window, subtract the one leaving), then n-wide row sums.
    float* __restrict vs = vsum.data();
    std::fill(vs, vs + span, 0.0f);
    for (int k = 0; k < n - 1; ++k) {
      const float* __restrict dk = &diff[static_cast<size_t>(k) * span];
      for (int i = 0; i < span; ++i) vs[i] += dk[i];
    }
    // Right windows inside the image: x - d - h >= 0 and x - d + h < cols.
    const int valid0 = std::clamp(d + h - x0, 0, width),
              valid1 = std::clamp(cols + d - h - x0, valid0, width);
    for (int y = 0; y < v->rows; ++y) {
      const float* __restrict enter = &diff[static_cast<size_t>(y + n - 1) * span];
      for (int i = 0; i < span; ++i) vs[i] += enter[i];
      float* __restrict out = v->Row(v->y0 + y, d);
      std::fill(out, out + valid0, kInf);
      for (int i = valid0; i < valid1; ++i) out[i] = vs[i];
      for (int k = 1; k < n; ++k)
        for (int i = valid0; i < valid1; ++i) out[i] += vs[i + k];
      for (int i = valid0; i < valid1; ++i) out[i] *= scale;
      std::fill(out + valid1, out + width, kInf);
      const float* __restrict leave = &diff[static_cast<size_t>(y) * span];
      for (int i = 0; i < span; ++i) vs[i] -= leave[i];
    }
  }
}

// The zero-mean SSD: sum ((L - mean L) - (R - mean R))^2 with both means
// over the windows compared, as the paper's cost, but squared, so that it
// runs: with D = L - R over the window of N pixels it is
// sum D^2 - (sum D)^2 / N, two box sums of one difference image per
// disparity. The sums are exact integers (8-bit images; column sums run
// down the strip, then (2h + 1)-wide row sums); the cost is the root mean
// square, sqrt(N sum D^2 - (sum D)^2) / N, in grey levels like the L1
// costs, and V-shaped about a match like them (the equiangular sub-pixel
// fit applies). O(1) per pixel and disparity in the window's area.
FOVEA_SIMD_CLONES void FillZeroMeanSsd(const cv::Mat& l, const cv::Mat& r, int h, CostVolume* v) {
  const int n = 2 * h + 1, cols = l.cols;
  const double area = static_cast<double>(n) * n;
  const float scale = static_cast<float>(1.0 / area);
  std::vector<int32_t> diff, s1, s2, w1, w2;
  for (int d = v->dlo; d < v->dlo + v->nd; ++d) {
    const int width = v->width[d - v->dlo];
    if (width <= 0) continue;
    const int x0 = v->x0[d - v->dlo], span = width + 2 * h;
    s1.assign(span, 0);
    s2.assign(span, 0);
    w1.resize(width);
    w2.resize(width);
    StripDifferences<uchar>(
        l, r, *v, d, h, x0, span, [](uchar p, uchar q) { return int32_t{p} - int32_t{q}; }, &diff);
    int32_t* __restrict c1 = s1.data();
    int32_t* __restrict c2 = s2.data();
    for (int k = 0; k < n - 1; ++k) {
      const int32_t* __restrict dk = &diff[static_cast<size_t>(k) * span];
      for (int i = 0; i < span; ++i) {
        c1[i] += dk[i];
        c2[i] += dk[i] * dk[i];
      }
    }
    // Right windows inside the image: x - d - h >= 0 and x - d + h < cols.
    const int valid0 = std::clamp(d + h - x0, 0, width),
              valid1 = std::clamp(cols + d - h - x0, valid0, width);
    int32_t* __restrict r1 = w1.data();
    int32_t* __restrict r2 = w2.data();
    for (int y = 0; y < v->rows; ++y) {
      const int32_t* __restrict enter = &diff[static_cast<size_t>(y + n - 1) * span];
      for (int i = 0; i < span; ++i) {
        c1[i] += enter[i];
        c2[i] += enter[i] * enter[i];
      }
      float* __restrict out = v->Row(v->y0 + y, d);
      std::fill(out, out + valid0, kInf);
      for (int i = valid0; i < valid1; ++i) {
        r1[i] = c1[i];
        r2[i] = c2[i];
      }
      for (int k = 1; k < n; ++k)
        for (int i = valid0; i < valid1; ++i) {
          r1[i] += c1[i + k];
          r2[i] += c2[i + k];
        }
      // N sum D^2 and (sum D)^2 reach 2^37 for the largest window: their
      // difference is exact in doubles, then rounded once to a float.
      for (int i = valid0; i < valid1; ++i) {
        const double sum = r1[i];
        out[i] = std::sqrt(static_cast<float>(area * r2[i] - sum * sum)) * scale;
      }
      std::fill(out + valid1, out + width, kInf);
      const int32_t* __restrict leave = &diff[static_cast<size_t>(y) * span];
      for (int i = 0; i < span; ++i) {
        c1[i] -= leave[i];
        c2[i] -= leave[i] * leave[i];
      }
    }
  }
}

// Eight floats (GCC's vector extensions: one AVX2 register in the AVX2
// clone, two SSE registers otherwise), for sums the compiler does not keep
// in registers itself. Loaded and stored with memcpy; |v| by clearing the
// sign bit, as std::abs does.
typedef float Floats8 __attribute__((vector_size(32)));
typedef int32_t Ints8 __attribute__((vector_size(32)));

// The paper's cost: sum |(L - mean L) - (R - mean R)| with both means over
// the windows being compared, which no running sum can share: O(window
// area) per pixel and disparity. Per disparity, the strip's differences
// L - R are taken once; each row then sums |(L - R) - (mean L - mean R)|
// over the window only at the columns it needs (CostVolume::RowFirst), the
// window's offsets a loop over contiguous columns that the compiler
// vectorizes (each pixel's sum in the same order as one pixel at a time).
// `l`, `r`: the images as CV_32F; `ml`, `mr`: their window means.
FOVEA_SIMD_CLONES void FillWindowMean(const cv::Mat& l, const cv::Mat& r, const cv::Mat& ml,
                                      const cv::Mat& mr, int h, CostVolume* v) {
  const float scale = 1.0f / ((2 * h + 1) * (2 * h + 1));
  const int cols = l.cols;
  std::vector<float> diff, offset, acc;
  for (int d = v->dlo; d < v->dlo + v->nd; ++d) {
    const int x0 = v->x0[d - v->dlo], width = v->width[d - v->dlo];
    if (width <= 0) continue;
    // Right windows inside the image: x - d - h >= 0 and x - d + h < cols.
    const int valid0 = std::clamp(d + h - x0, 0, width);
    const int valid1 = std::clamp(cols + d - h - x0, valid0, width);
    // L - R over the strip's rows and their windows; the windows of the
    // columns [valid0, valid1) only read where the right pixel lies in the
    // image.
    const int span = width + 2 * h;
    StripDifferences<float>(
        l, r, *v, d, h, x0, span, [](float p, float q) { return p - q; }, &diff);
    offset.resize(width);
    acc.resize(width);
    for (int y = v->y0; y < v->y0 + v->rows; ++y) {
      float* out = v->Row(y, d);
      // The row's columns, as offsets into the strip's [x0, x0 + width).
      const int c0 = std::clamp(v->RowFirst(y, d) - x0, valid0, valid1);
      const int c1 = std::clamp(v->RowEnd(y, d) - x0, c0, valid1);
      std::fill(out, out + c0, kInf);
      std::fill(out + c1, out + width, kInf);
      const int n = c1 - c0;
      if (n <= 0) continue;
      const float* __restrict pml = ml.ptr<float>(y) + x0 + c0;
      const float* __restrict pmr = mr.ptr<float>(y) + x0 + c0 - d;
      float* __restrict o = offset.data();
      for (int i = 0; i < n; ++i) o[i] = pml[i] - pmr[i];
      // diff's row of y - h + dy, from the column x0 + c0 - h.
      const float* row0 = &diff[static_cast<size_t>(y - v->y0) * span] + c0;
      // Blocks of 16 columns, their sums held in two registers of 8 floats
      // over the whole window (GCC's vector extensions: AVX2 registers in
      // the AVX2 clone); then the columns left, one pass per window offset.
      // Both add the window's terms in the same order.
      int i0 = 0;
      for (; i0 + 16 <= n; i0 += 16) {
        Floats8 c_lo = {}, c_hi = {}, o_lo, o_hi, l_lo, l_hi;
        std::memcpy(&o_lo, o + i0, sizeof o_lo);
        std::memcpy(&o_hi, o + i0 + 8, sizeof o_hi);
        for (int dy = 0; dy <= 2 * h; ++dy) {
          const float* pd = row0 + static_cast<size_t>(dy) * span + i0;
          for (int dx = 0; dx <= 2 * h; ++dx) {
            std::memcpy(&l_lo, pd + dx, sizeof l_lo);
            std::memcpy(&l_hi, pd + dx + 8, sizeof l_hi);
            c_lo += reinterpret_cast<Floats8>(reinterpret_cast<Ints8>(l_lo - o_lo) & 0x7fffffff);
            c_hi += reinterpret_cast<Floats8>(reinterpret_cast<Ints8>(l_hi - o_hi) & 0x7fffffff);
          }
        }
        c_lo *= scale;
        c_hi *= scale;
        std::memcpy(out + c0 + i0, &c_lo, sizeof c_lo);
        std::memcpy(out + c0 + i0 + 8, &c_hi, sizeof c_hi);
      }
      if (i0 < n) {
        float* __restrict c = acc.data();
        const int m = n - i0;
        std::fill(c, c + m, 0.0f);
        for (int dy = 0; dy <= 2 * h; ++dy) {
          const float* __restrict pd = row0 + static_cast<size_t>(dy) * span + i0;
          for (int dx = 0; dx <= 2 * h; ++dx)
            for (int i = 0; i < m; ++i) c[i] += std::abs(pd[i + dx] - o[i0 + i]);
        }
        for (int i = 0; i < m; ++i) out[c0 + i0 + i] = c[i] * scale;
      }
    }
  }
}

// The sub-pixel offset of a minimum c1 between c0 and c2 by the equiangular
// (V-shaped) fit, which suits an L1 cost better than a parabola: on the
// benchmark fixations it halves the parabola's pixel-locking bias
// (README, "The foveated matcher").
double SubPixel(double c0, double c1, double c2) {
  const double slope = std::max(c0 - c1, c2 - c1);
  return slope > 0 ? std::clamp(0.5 * (c0 - c2) / slope, -0.5, 0.5) : 0.0;
}

// Each pixel's integer search band (lo > hi: none).
struct Bands {
  cv::Mat lo, hi;  ///< CV_32S
};

// The bands of rows [y0, y1) after the range and texture tests, counted in
// `counts`; `image` is the left image as CV_32F, `ml` its window means.
FOVEA_SIMD_CLONES void SearchBands(const cv::Mat& image, const cv::Mat& ml, const cv::Mat& lo_px,
                                   const cv::Mat& hi_px, const Nl1Options& options, int y0, int y1,
                                   Bands* b, DisparityMap* counts) {
  const int h = options.window_half_px, n = 2 * h + 1;
  const float min_sum = static_cast<float>(options.min_texture_dn * n * n);
  std::vector<float> mad(image.cols);
  for (int y = y0; y < y1; ++y) {
    const float* lo = lo_px.ptr<float>(y);
    const float* hi = hi_px.ptr<float>(y);
    int x0 = image.cols - h, x1 = h;  // the row's searched span
    for (int x = h; x < image.cols - h; ++x)
      if (lo[x] <= hi[x]) {
        x0 = std::min(x0, x);
        x1 = x + 1;
      }
    if (x0 >= x1) continue;
    // Texture: each window's absolute deviation from its mean, summed row by
    // row of the window over the whole span (loops the compiler vectorizes).
    const float* __restrict m = ml.ptr<float>(y);
    float* __restrict acc = mad.data();
    std::fill(acc + x0, acc + x1, 0.0f);
    for (int dy = -h; dy <= h; ++dy) {
      const float* __restrict p = image.ptr<float>(y + dy);
      for (int dx = -h; dx <= h; ++dx)
        for (int x = x0; x < x1; ++x) acc[x] += std::abs(p[x + dx] - m[x]);
    }
    int* blo = b->lo.ptr<int>(y);
    int* bhi = b->hi.ptr<int>(y);
    for (int x = x0; x < x1; ++x) {
      if (!(lo[x] <= hi[x])) continue;
      ++counts->searched;
      if (acc[x] < min_sum) {
        ++counts->rejected_texture;
        continue;
      }
      // Only disparities whose right window lies in the image: the clamp also
      // keeps a band from a ray grazing the right camera finite.
      const float dmin = static_cast<float>(x - (image.cols - 1 - h)),
                  dmax = static_cast<float>(x - h);
      const float l = std::clamp(std::floor(lo[x]) - 1, dmin - 1, dmax + 1);
      const float u = std::clamp(std::ceil(hi[x]) + 1, dmin - 1, dmax + 1);
      blo[x] = static_cast<int>(l);
      bhi[x] = static_cast<int>(u);
    }
  }
}

// Sizes `v` for the strip of rows [y0, y1): the union of its pixels' bands,
// and for each disparity the columns of the pixels whose band holds it.
// False when no pixel of the strip is searched.
bool SizeVolume(const Bands& bands, int y0, int y1, int h, CostVolume* v) {
  const int cols = bands.lo.cols;
  int dlo = std::numeric_limits<int>::max(), dhi = std::numeric_limits<int>::min();
  for (int y = y0; y < y1; ++y) {
    const int* lo = bands.lo.ptr<int>(y);
    const int* hi = bands.hi.ptr<int>(y);
    for (int x = h; x < cols - h; ++x)
      if (lo[x] <= hi[x]) {
        dlo = std::min(dlo, lo[x]);
        dhi = std::max(dhi, hi[x]);
      }
  }
  if (dlo > dhi) return false;
  v->y0 = y0;
  v->rows = y1 - y0;
  v->dlo = dlo;
  v->nd = dhi - dlo + 1;
  // Per row, a superset of each disparity's columns: scanning left to
  // right, the first column at which the hull of the bands seen so far
  // reaches it; scanning back, the last. O(columns + disparities) per row;
  // a column that does not need d only costs its computation
  // (RowWinners checks each pixel's own band).
  std::vector<int> xmin(v->nd, cols), xmax(v->nd, -1);
  v->row_first.assign(static_cast<size_t>(v->rows) * v->nd, cols);
  v->row_end.assign(static_cast<size_t>(v->rows) * v->nd, 0);
  // Widens the hull [seen_lo, seen_hi] (empty: seen_lo > seen_hi) by the
  // band [lo, hi], calling mark(d) for each disparity it adds.
  auto widen = [](int lo, int hi, int* seen_lo, int* seen_hi, auto&& mark) {
    if (*seen_lo > *seen_hi) {
      for (int d = lo; d <= hi; ++d) mark(d);
      *seen_lo = lo;
      *seen_hi = hi;
      return;
    }
    for (int d = lo; d < *seen_lo; ++d) mark(d);
    for (int d = *seen_hi + 1; d <= hi; ++d) mark(d);
    *seen_lo = std::min(*seen_lo, lo);
    *seen_hi = std::max(*seen_hi, hi);
  };
  for (int y = y0; y < y1; ++y) {
    const int* lo = bands.lo.ptr<int>(y);
    const int* hi = bands.hi.ptr<int>(y);
    int* first = &v->row_first[static_cast<size_t>(y - y0) * v->nd];
    int* end = &v->row_end[static_cast<size_t>(y - y0) * v->nd];
    int seen_lo = 1, seen_hi = 0;
    for (int x = h; x < cols - h; ++x)
      if (lo[x] <= hi[x])
        widen(lo[x], hi[x], &seen_lo, &seen_hi, [&](int d) { first[d - dlo] = x; });
    seen_lo = 1;
    seen_hi = 0;
    for (int x = cols - h - 1; x >= h; --x)
      if (lo[x] <= hi[x])
        widen(lo[x], hi[x], &seen_lo, &seen_hi, [&](int d) { end[d - dlo] = x + 1; });
    for (int i = 0; i < v->nd; ++i)
      if (first[i] < end[i]) {
        xmin[i] = std::min(xmin[i], first[i]);
        xmax[i] = std::max(xmax[i], end[i] - 1);
      }
  }
  v->x0.assign(v->nd, 0);
  v->width.assign(v->nd, 0);
  v->offset.assign(v->nd, 0);
  size_t total = 0;
  for (int i = 0; i < v->nd; ++i) {
    v->offset[i] = total;
    if (xmax[i] < 0) continue;
    v->x0[i] = xmin[i];
    // A disparity only in a gap the hull bridged (bands [0, 1] then [5, 6])
    // comes out with its last column before its first: no column needs it.
    v->width[i] = std::max(0, xmax[i] + 1 - xmin[i]);
    total += static_cast<size_t>(v->rows) * v->width[i];
  }
  v->c.resize(total);
  return true;
}

// Where x's band [lo, hi] holds dd and c[x] beats best[x], x in [x0, x1):
// best[x] = c[x], best_d[x] = dd. Branch-free, so that it vectorizes.
FOVEA_SIMD_CLONES void TakeLower(const float* __restrict c, const int* __restrict lo,
                                 const int* __restrict hi, int dd, int x0, int x1,
                                 float* __restrict best, int* __restrict best_d) {
  for (int x = x0; x < x1; ++x) {
    const bool take = (lo[x] <= dd) & (dd <= hi[x]) & (c[x] < best[x]);
    best[x] = take ? c[x] : best[x];
    best_d[x] = take ? dd : best_d[x];
  }
}

// The same for the best cost more than one disparity from best_d[x].
FOVEA_SIMD_CLONES void TakeSecond(const float* __restrict c, const int* __restrict lo,
                                  const int* __restrict hi, int dd, int x0, int x1,
                                  const int* __restrict best_d, float* __restrict second) {
  for (int x = x0; x < x1; ++x) {
    const bool take = (lo[x] <= dd) & (dd <= hi[x]) & ((best_d[x] < dd - 1) | (best_d[x] > dd + 1));
    second[x] = (take & (c[x] < second[x])) ? c[x] : second[x];
  }
}

// Winner-take-all along one row of a strip's volume, disparity by
// disparity over contiguous columns (loops the compiler vectorizes): each
// left pixel's best cost over its band and the best cost not adjacent to
// it, and each right pixel's best over the left pixels whose bands reach it.
// Ties go to the smaller disparity.
struct RowWinners {
  explicit RowWinners(int cols)
      : cost(cols), second(cols), right_cost(cols), d(cols), right_d(cols) {}
  std::vector<float> cost, second, right_cost;
  std::vector<int> d, right_d;
  int dlo = 0, nd = 0;
  std::vector<const float*> row;  ///< row[dd - dlo][x]: this row's cost at (x, dd)
  std::vector<int> x0, x1;        ///< the columns row[dd - dlo] holds

  /// The cost at (x, dd) of the row, +inf where it was not computed.
  float At(int x, int dd) const {
    const int i = dd - dlo;
    return i >= 0 && i < nd && x >= x0[i] && x < x1[i] ? row[i][x] : kInf;
  }

  void Find(const CostVolume& v, const Bands& bands, int y) {
    const int* lo = bands.lo.ptr<int>(y);
    const int* hi = bands.hi.ptr<int>(y);
    const int cols = static_cast<int>(cost.size());
    std::fill(cost.begin(), cost.end(), kInf);
    std::fill(second.begin(), second.end(), kInf);
    std::fill(right_cost.begin(), right_cost.end(), kInf);
    dlo = v.dlo;
    nd = v.nd;
    row.resize(nd);
    x0.resize(nd);
    x1.resize(nd);
    for (int i = 0; i < nd; ++i) {
      x0[i] = v.x0[i];
      x1[i] = v.x0[i] + v.width[i];
      row[i] = v.width[i] > 0
                   ? &v.c[v.offset[i] + static_cast<size_t>(y - v.y0) * v.width[i]] - v.x0[i]
                   : nullptr;
    }
    for (int dd = v.dlo; dd < v.dlo + v.nd; ++dd) {
      const int i = dd - v.dlo, x0 = v.x0[i], x1 = x0 + v.width[i];
      if (x1 <= x0) continue;
      const float* c = row[i];
      // Left pixels x: cost[x], d[x]. Right pixels x - dd: right_cost, right_d.
      TakeLower(c, lo, hi, dd, x0, x1, cost.data(), d.data());
      const int r0 = std::max(x0, dd), r1 = std::min(x1, cols + dd);
      if (r1 > r0) TakeLower(c, lo, hi, dd, r0, r1, right_cost.data() - dd, right_d.data() - dd);
    }
    // The best cost more than one disparity away from the winner.
    for (int dd = v.dlo; dd < v.dlo + v.nd; ++dd) {
      const int i = dd - v.dlo, x0 = v.x0[i], x1 = x0 + v.width[i];
      if (x1 <= x0) continue;
      const float* c = row[i];
      TakeSecond(c, lo, hi, dd, x0, x1, d.data(), second.data());
    }
  }
};

// The winners of row y: each searched left pixel's disparity, refined to a
// sub-pixel, where its minimum lies inside its band and the matched right
// pixel's own winner agrees (left-right check), with its confidence.
void MatchRow(const Bands& bands, int y, double lr_tolerance_px, const RowWinners* w,
              DisparityMap* out) {
  const int* blo = bands.lo.ptr<int>(y);
  const int* bhi = bands.hi.ptr<int>(y);
  float* disparity = out->disparity_px.ptr<float>(y);
  float* confidence = out->confidence.ptr<float>(y);
  for (int x = 0; x < bands.lo.cols; ++x) {
    const int lo = blo[x], hi = bhi[x];
    if (lo > hi) continue;
    const float c1 = w->cost[x];
    if (!std::isfinite(c1)) {
      ++out->rejected_edge;
      continue;
    }
    // The minimum needs a finite neighbour on both sides in the band.
    const int d = w->d[x];
    const float c0 = d > lo ? w->At(x, d - 1) : kInf;
    const float c2 = d < hi ? w->At(x, d + 1) : kInf;
    if (!std::isfinite(c0) || !std::isfinite(c2)) {
      ++out->rejected_edge;
      continue;
    }
    const double sub = SubPixel(c0, c1, c2);
    // Left-right check: the matched right pixel's own winner among the left
    // pixels whose bands reach it, from the same costs.
    const int xr = x - d, dr = w->right_d[xr];
    if (!std::isfinite(w->right_cost[xr])) {
      ++out->rejected_lr;
      continue;
    }
    double right = dr;  // the right pixel's disparity, sub-pixel where it can be
    // Its neighbours: the left pixels beside its match, at the disparities
    // beside, where those pixels' bands hold them.
    auto candidate = [&](int xl, int dl) {
      return xl >= 0 && xl < bands.lo.cols && blo[xl] <= dl && dl <= bhi[xl] ? w->At(xl, dl) : kInf;
    };
    const float r0 = candidate(xr + dr - 1, dr - 1), r2 = candidate(xr + dr + 1, dr + 1);
    const bool right_refined = std::isfinite(r0) && std::isfinite(r2);
    if (right_refined) right += SubPixel(r0, w->right_cost[xr], r2);
    const double left = d + sub;
    if (std::abs(right - left) > lr_tolerance_px) {
      ++out->rejected_lr;
      continue;
    }
    // Both views' estimates of the same point, averaged: their window
    // biases (a slanted surface is foreshortened in one view) cancel.
    disparity[x] = static_cast<float>(right_refined ? 0.5 * (left + right) : left);
    const float second = w->second[x];
    const float margin = std::isfinite(second) ? (second - c1) / (second + 1e-3f) : 1.0f;
    confidence[x] = std::clamp(margin, 0.0f, 1.0f);
    ++out->matched;
  }
}

}  // namespace

DisparityMap Nl1Matcher::Match(const cv::Mat& left, const cv::Mat& right, const cv::Mat& lo_px,
                               const cv::Mat& hi_px) const {
  CV_Assert(left.type() == CV_8UC1 && right.type() == CV_8UC1 && left.size() == right.size());
  CV_Assert(lo_px.type() == CV_32F && hi_px.type() == CV_32F && lo_px.size() == left.size() &&
            hi_px.size() == left.size());
  // Only the rectangle the searched pixels need is matched (a level's
  // fovea is a small part of its image): their bounding box and windows,
  // and on the right the columns their bands reach.
  const int h = options_.window_half_px;
  int x0 = left.cols, x1 = -1, y0 = left.rows, y1 = -1;
  float dlo = std::numeric_limits<float>::infinity(), dhi = -dlo;
  for (int y = 0; y < left.rows; ++y) {
    const float* lo = lo_px.ptr<float>(y);
    const float* hi = hi_px.ptr<float>(y);
    for (int x = 0; x < left.cols; ++x)
      if (lo[x] <= hi[x]) {
        x0 = std::min(x0, x);
        x1 = std::max(x1, x);
        y0 = std::min(y0, y);
        y1 = std::max(y1, y);
        dlo = std::min(dlo, lo[x]);
        dhi = std::max(dhi, hi[x]);
      }
  }
  DisparityMap out;
  out.disparity_px = cv::Mat(left.size(), CV_32F, cv::Scalar(std::nanf("")));
  out.confidence = cv::Mat(left.size(), CV_32F, cv::Scalar(0));
  if (x1 < 0) return out;
  auto clamp_x = [&](double x) {
    return static_cast<int>(std::clamp(x, 0.0, static_cast<double>(left.cols)));
  };
  const int c0 = clamp_x(std::min<double>(x0, x0 - std::ceil(dhi) - 1) - h);
  const int c1 = clamp_x(std::max<double>(x1, x1 - std::floor(dlo) + 1) + h + 1);
  const cv::Rect crop(c0, std::max(0, y0 - h), c1 - c0,
                      std::min(left.rows, y1 + h + 1) - std::max(0, y0 - h));
  DisparityMap part;  // views of `out`'s maps: the crop writes into them
  part.disparity_px = out.disparity_px(crop);
  part.confidence = out.confidence(crop);
  MatchCrop(left(crop), right(crop), lo_px(crop), hi_px(crop), &part);
  part.disparity_px = out.disparity_px;
  part.confidence = out.confidence;
  return part;
}

void Nl1Matcher::MatchCrop(const cv::Mat& left, const cv::Mat& right, const cv::Mat& lo_px,
                           const cv::Mat& hi_px, DisparityMap* result) const {
  const int h = options_.window_half_px, n = 2 * h + 1;
  DisparityMap& out = *result;
  if (left.rows < n || left.cols < n) return;
  cv::Mat ml, mr;
  cv::boxFilter(left, ml, CV_32F, cv::Size(n, n));
  cv::boxFilter(right, mr, CV_32F, cv::Size(n, n));
  const bool prenormalized = options_.cost == "prenormalized";
  const bool zero_mean_ssd = options_.cost == "zero_mean_ssd";
  cv::Mat image, right_image, a, b;
  left.convertTo(image, CV_32F);
  if (zero_mean_ssd) {
    // The 8-bit images themselves.
  } else if (!prenormalized) {
    right.convertTo(right_image, CV_32F);
  } else {
    // Each image less its mean over twice the window: a narrower mean
    // filters away the texture's lower frequencies, and a band that misses
    // the truth then finds more false interior minima (matcher_test).
    const cv::Size wide(2 * n + 1, 2 * n + 1);
    cv::Mat mean;
    cv::boxFilter(image, mean, CV_32F, wide);
    cv::subtract(image, mean, a);
    cv::boxFilter(right, mean, CV_32F, wide);
    cv::subtract(right, mean, b, cv::noArray(), CV_32F);
  }
  Bands bands{cv::Mat(left.size(), CV_32S, cv::Scalar(1)),
              cv::Mat(left.size(), CV_32S, cv::Scalar(0))};
  // Strips of rows are independent, but matching them on OpenCV's thread
  // pool did not pay on the 2-core machine (the README's figures): serial.
  SearchBands(image, ml, lo_px, hi_px, options_, h, left.rows - h, &bands, &out);
  CostVolume v;
  RowWinners w(left.cols);
  for (int y0 = h; y0 < left.rows - h; y0 += kStripRows) {
    const int y1 = std::min(y0 + kStripRows, left.rows - h);
    if (!SizeVolume(bands, y0, y1, h, &v)) continue;
    if (prenormalized)
      FillPrenormalized(a, b, h, &v);
    else if (zero_mean_ssd)
      FillZeroMeanSsd(left, right, h, &v);
    else
      FillWindowMean(image, right_image, ml, mr, h, &v);
    for (int y = y0; y < y1; ++y) {
      w.Find(v, bands, y);
      MatchRow(bands, y, options_.lr_tolerance_px, &w, &out);
    }
  }
}

}  // namespace fovea
