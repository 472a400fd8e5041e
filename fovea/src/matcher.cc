#include "fovea/matcher.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <future>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "fovea/params.h"

namespace fovea {

void Nl1Options::Check() const {
  rig::CheckParam(params::kNl1WindowHalfPx, window_half_px);
  rig::CheckParam(params::kNl1MinTextureDn, min_texture_dn);
  rig::CheckParam(params::kNl1LrTolerancePx, lr_tolerance_px);
  rig::CheckParam(params::kNl1WeakWindowHalfPx, weak_window_half_px);
  rig::CheckParam(params::kNl1WeakTextureDn, weak_texture_dn);
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
// Crops with at least this many pixels to search (before the texture
// test) are matched on two threads (Nl1Matcher::MatchCrop).
constexpr int kThreadedMinPixels = 8192;
// Within a row, the columns are grouped in chunks of this many (chunk k:
// [k * kChunkCols, (k + 1) * kChunkCols) of the matched crop), the block of
// columns the paper's cost sums in registers (FillWindowMean).
constexpr int kChunkCols = 16;

// The matching costs of one strip of rows: the cost at (x, y, d) is that of
// the left window centred at (x, y) against the right window at (x - d, y),
// +inf where the right window leaves the image. Each disparity d holds the
// columns [x0[d], x0[d] + width[d]), x fastest (Row). Row y needs d only
// over its runs (ForRuns): the columns of the chunks in which some pixel's
// band holds d, adjacent chunks merged (and runs narrower than a chunk
// widened to one where the image allows). The fills compute and the
// searches read only those: elsewhere a row's costs are not set (the fills
// that box-sum whole rows set them all). Beside a depth edge a row's
// pixels search disparities far apart, and its hull of each disparity's
// columns held 2.7 times the cells its pixels need (cylinder_planes, the
// full-resolution periphery).
struct CostVolume {
  int y0 = 0, rows = 0, dlo = 0, nd = 0;
  std::vector<int> x0, width;
  std::vector<size_t> offset;
  std::vector<float> c;
  /// Columns [begin, end) of a row; the next run of the same row and
  /// disparity (-1: none).
  struct Run {
    int begin, end, next;
  };
  std::vector<Run> runs;
  std::vector<int> head, tail;  ///< [(y - y0) * nd + d - dlo]: first and last run, -1: none
  float* Row(int y, int d) {
    const int i = d - dlo;
    return &c[offset[i] + static_cast<size_t>(y - y0) * width[i]];
  }
  /// The first run of row y at disparity d (-1: none).
  int Head(int y, int d) const { return head[static_cast<size_t>(y - y0) * nd + d - dlo]; }
  /// The last run of row y at disparity d (one exists).
  const Run& Last(int y, int d) const {
    return runs[tail[static_cast<size_t>(y - y0) * nd + d - dlo]];
  }
  /// f(begin, end) for each run of row y at disparity d, left to right.
  template <typename F>
  void ForRuns(int y, int d, F&& f) const {
    for (int r = Head(y, d); r >= 0; r = runs[r].next) f(runs[r].begin, runs[r].end);
  }
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

// Sixteen 16-bit integers (GCC's vector extensions: one AVX2 register in
// the AVX2 clone, two SSE registers otherwise), for sums the compiler does
// not keep in registers itself. Loaded and stored with memcpy.
typedef int16_t Shorts16 __attribute__((vector_size(32)));

// The paper's cost, sum_i |D_i - o| over the window's n = (2h + 1)^2
// pixels, with D = L - R and o = S / n their mean (S = sum_i D_i: the two
// windows' sums less each other), in exact integers. With q = floor(o),
// r = S - n q in [0, n) and e_i = D_i - q:
//   sum_i |D_i - o| = sum_i |e_i - r / n|
//                   = 2 A - r - (r / n) (2 P - n),
// where A = sum_i max(e_i, 0) = sum_i max(D_i, q) - n q and P counts the
// e_i > 0 (for an integer e_i and 0 <= r / n < 1, |e_i - r / n| is
// e_i - r / n where e_i > 0 and r / n - e_i elsewhere; sum_i e_i = r). So n
// times the sum is the integer n (2 A - r) - r (2 P - n), and the cost,
// the mean absolute difference, is that over n^2: one rounding, in float.
// For 8-bit images and a window of at most 11 x 11 pixels
// (kMaxBlockHalfPx), sum_i max(D_i, q) and P fit 16-bit integers: 16
// columns per AVX2 register, where float sums held 8.
struct WindowMeanCost {
  int n;         ///< pixels in the window
  float inv_n2;  ///< 1 / n^2
  /// The cost from A, r and P, in integers of type Int: 32-bit for windows
  /// of at most 11 x 11 pixels (n (2 A - r) < 2^24), 64-bit beyond.
  template <typename Int>
  float FromParts(Int a, Int r, Int positive) const {
    return static_cast<float>(n * (2 * a - r) - r * (2 * positive - n)) * inv_n2;
  }
  /// The cost from sum_i max(D_i, q), P, the window's S and q.
  float operator()(int sum_max, int positive, int s, int q) const {
    return FromParts<int64_t>(sum_max - int64_t{n} * q, s - int64_t{n} * q, positive);
  }
};
// The largest window half width whose sums fit 16-bit integers: n * 255
// <= 32767 for n = (2h + 1)^2.
constexpr int kMaxBlockHalfPx = 5;

// The paper's cost at 16 adjacent columns. `row0`: the differences D = L -
// R of the window's first row, from its first column, rows `span` apart;
// `s`, `q`: each column's S and floor(S / n); `out`: the costs. The window
// half width is kHalf, or h where kHalf is 0 (for the default window the
// compiler unrolls the loops). sum_i max(D_i, q) is taken as the sum of
// the D_i above q plus q for each of the others.
template <int kHalf>
inline __attribute__((always_inline)) void WindowBlock(const int16_t* row0, int span, const int* s,
                                                       const int16_t* q, int h,
                                                       const WindowMeanCost& cost, float* out) {
  const int half = kHalf > 0 ? kHalf : h;
  Shorts16 m, above_sum = {}, not_above = {};
  std::memcpy(&m, q, sizeof m);
  for (int dy = 0; dy <= 2 * half; ++dy) {
    const int16_t* pd = row0 + static_cast<size_t>(dy) * span;
    for (int dx = 0; dx <= 2 * half; ++dx) {
      Shorts16 l;
      std::memcpy(&l, pd + dx, sizeof l);
      const Shorts16 above = l > m;  // -1 where D_i > q
      above_sum += l & above;
      not_above += above;  // minus P
    }
  }
  // The costs, in 32-bit integers (at most 11 x 11 pixels).
  int16_t sa[16], na[16];
  std::memcpy(sa, &above_sum, sizeof sa);
  std::memcpy(na, &not_above, sizeof na);
  for (int i = 0; i < 16; ++i)
    // A = sum_i max(D_i, q) - n q = (D_i above q) + (n - P) q - n q.
    out[i] = cost.FromParts<int>(sa[i] + na[i] * q[i], s[i] - cost.n * q[i], -na[i]);
}

// The paper's cost: sum |(L - mean L) - (R - mean R)| with both means over
// the windows being compared, which no running sum can share: O(window
// area) per pixel and disparity. Per disparity, the strip's differences
// L - R are taken once; each row then sums over the window only at the
// columns it needs (CostVolume::ForRuns), in exact integers
// (WindowMeanCost): blocks of 16 columns (WindowBlock), the columns of a
// row too narrow for one, or of a window too wide for 16-bit sums, a
// column at a time with the same integers.
// `l`, `r`: the 8-bit images; `sl`, `sr`: their window sums (CV_32S).
FOVEA_SIMD_CLONES void FillWindowMean(const cv::Mat& l, const cv::Mat& r, const cv::Mat& sl,
                                      const cv::Mat& sr, int h, CostVolume* v) {
  const int cols = l.cols;
  const WindowMeanCost cost{
      (2 * h + 1) * (2 * h + 1),
      1.0f / static_cast<float>((2 * h + 1) * (2 * h + 1) * (2 * h + 1) * (2 * h + 1))};
  const float inv_n = 1.0f / static_cast<float>(cost.n);
  std::vector<int16_t> diff, q;
  std::vector<int> s;
  for (int d = v->dlo; d < v->dlo + v->nd; ++d) {
    const int x0 = v->x0[d - v->dlo], width = v->width[d - v->dlo];
    if (width <= 0) continue;
    // Right windows inside the image: x - d - h >= 0 and x - d + h < cols.
    const int valid0 = std::clamp(d + h - x0, 0, width);
    const int valid1 = std::clamp(cols + d - h - x0, valid0, width);
    // L - R over the strip's rows and their windows, each row of
    // differences only over the columns the windows of its rows' runs read
    // (the rows' first run's first column to their last run's end), and
    // only where the right pixel lies in the image (the columns [valid0,
    // valid1) read no other).
    const int span = width + 2 * h, rows = v->rows + 2 * h;
    diff.resize(static_cast<size_t>(rows) * span);
    for (int row = 0; row < rows; ++row) {
      int a = span, b = 0;
      // The rows whose windows hold it: y - y0 <= row <= y - y0 + 2h.
      for (int y = std::max(v->y0, v->y0 + row - 2 * h);
           y <= std::min(v->y0 + v->rows - 1, v->y0 + row); ++y) {
        const int first = v->Head(y, d);
        if (first < 0) continue;
        a = std::min(a, v->runs[first].begin - x0);
        b = std::max(b, v->Last(y, d).end - x0 + 2 * h);
      }
      a = std::max(a, valid0);
      b = std::min(b, valid1 + 2 * h);
      const uchar* __restrict pl = l.ptr<uchar>(v->y0 - h + row) + (x0 - h);
      const uchar* __restrict pr = r.ptr<uchar>(v->y0 - h + row) + (x0 - h - d);
      int16_t* __restrict pd = &diff[static_cast<size_t>(row) * span];
      for (int i = a; i < b; ++i) pd[i] = static_cast<int16_t>(int16_t{pl[i]} - int16_t{pr[i]});
    }
    s.resize(width);
    q.resize(width);
    for (int y = v->y0; y < v->y0 + v->rows; ++y) {
      float* out = v->Row(y, d);
      // The runs, in a loop rather than through ForRuns: a lambda would be
      // built for the baseline instruction set only. Their columns whose
      // right window leaves the image cost +inf; no band reads any other
      // column outside them.
      for (int run = v->Head(y, d); run >= 0; run = v->runs[run].next) {
        // The run's columns, as offsets into the strip's [x0, x0 + width).
        const int begin = v->runs[run].begin - x0, end = v->runs[run].end - x0;
        const int c0 = std::clamp(begin, valid0, valid1), c1 = std::clamp(end, c0, valid1);
        std::fill(out + begin, out + c0, kInf);
        std::fill(out + c1, out + end, kInf);
        const int n = c1 - c0;
        if (n <= 0) continue;
        const int* __restrict psl = sl.ptr<int>(y) + x0 + c0;
        const int* __restrict psr = sr.ptr<int>(y) + x0 + c0 - d;
        int* __restrict ps = s.data();
        int16_t* __restrict pq = q.data();
        for (int i = 0; i < n; ++i) {
          ps[i] = psl[i] - psr[i];
          // floor(S / n) = floor((S + 1/2) / n) for an integer S, and
          // (S + 1/2) / n lies at least 1 / 2n from an integer, further
          // than the float product's error and the rounding of the sum
          // below (|S| / n <= 255). Shifted by 256 to be positive, the
          // conversion's truncation is the floor.
          pq[i] = static_cast<int16_t>(
              static_cast<int>((static_cast<float>(ps[i]) + 0.5f) * inv_n + 256.0f) - 256);
        }
        // diff's row of y - h + dy, from the column x0 + c0 - h.
        const int16_t* row0 = &diff[static_cast<size_t>(y - v->y0) * span] + c0;
        // Blocks of 16 columns (SizeVolume widens narrower runs where it
        // can); the last columns of a run as a block that overlaps the one
        // before (the same costs again).
        const bool blocks = h <= kMaxBlockHalfPx && n >= 16;
        for (int i0 = 0; blocks && i0 < n; i0 += 16) {
          const int at = std::min(i0, n - 16);
          if (h == 3)
            WindowBlock<3>(row0 + at, span, ps + at, pq + at, h, cost, out + c0 + at);
          else
            WindowBlock<0>(row0 + at, span, ps + at, pq + at, h, cost, out + c0 + at);
        }
        if (!blocks)
          for (int i = 0; i < n; ++i) {
            int sum_max = 0, positive = 0;
            for (int dy = 0; dy <= 2 * h; ++dy) {
              const int16_t* pd = row0 + static_cast<size_t>(dy) * span + i;
              for (int dx = 0; dx <= 2 * h; ++dx) {
                sum_max += std::max<int>(pd[dx], pq[i]);
                positive += pd[dx] > pq[i];
              }
            }
            out[c0 + i] = cost(sum_max, positive, ps[i], pq[i]);
          }
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
// each row's runs of each disparity (CostVolume), and for each disparity the
// columns of its runs. False when no pixel of the strip is searched.
// O(cells / kChunkCols) beyond a pass over the bands.
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
  v->runs.clear();
  v->head.assign(static_cast<size_t>(v->rows) * v->nd, -1);
  v->tail.assign(static_cast<size_t>(v->rows) * v->nd, -1);
  std::vector<int> xmin(v->nd, cols), xmax(v->nd, -1);
  // Scanning a row's chunks left to right, a disparity's run opens at the
  // first chunk whose band holds it and closes before the first that does
  // not: only the disparities at which two neighbouring chunks' bands
  // differ are touched (O(chunks + runs) per row).
  auto open = [&](size_t row, int d, int first) {
    const int i = d - dlo;
    v->runs.push_back({first, 0, -1});
    const int r = static_cast<int>(v->runs.size()) - 1;
    int& tail = v->tail[row + i];
    (tail >= 0 ? v->runs[tail].next : v->head[row + i]) = r;
    tail = r;
  };
  auto close = [&](size_t row, int d, int end) {
    const int i = d - dlo;
    v->runs[v->tail[row + i]].end = end;
  };
  for (int y = y0; y < y1; ++y) {
    const int* lo = bands.lo.ptr<int>(y);
    const int* hi = bands.hi.ptr<int>(y);
    const size_t row = static_cast<size_t>(y - y0) * v->nd;
    int prev_lo = 1, prev_hi = 0, prev_end = 0;  // the previous chunk's band and end
    for (int k = h / kChunkCols; k * kChunkCols < cols - h; ++k) {
      // The chunk's searched pixels: their columns [first, end) and bands' union.
      int first = cols, end = 0, blo = std::numeric_limits<int>::max(),
          bhi = std::numeric_limits<int>::min();
      for (int x = std::max(h, k * kChunkCols); x < std::min(cols - h, (k + 1) * kChunkCols); ++x)
        if (lo[x] <= hi[x]) {
          first = std::min(first, x);
          end = x + 1;
          blo = std::min(blo, lo[x]);
          bhi = std::max(bhi, hi[x]);
        }
      if (blo > bhi) {
        blo = 1;
        bhi = 0;
      }
      // Close the runs the chunk's band leaves, open those it enters.
      for (int d = prev_lo; d <= prev_hi; ++d)
        if (d < blo || d > bhi)
          close(row, d, prev_end);
        else
          d = bhi;  // [blo, bhi] goes on: skip to its end
      for (int d = blo; d <= bhi; ++d)
        if (d < prev_lo || d > prev_hi)
          open(row, d, first);
        else
          d = prev_hi;
      prev_lo = blo;
      prev_hi = bhi;
      if (blo <= bhi) prev_end = end;
    }
    for (int d = prev_lo; d <= prev_hi; ++d) close(row, d, prev_end);
  }
  // A run narrower than a block is widened to one where the image has the
  // columns (right windows inside it: x - d - h >= 0 and x - d + h <
  // cols): FillWindowMean computes whole blocks, and the costs beside a
  // run are true costs that no band reads.
  for (int y = y0; y < y1; ++y)
    for (int i = 0; i < v->nd; ++i) {
      const int d = dlo + i;
      const int lo = std::max(h, d + h), hi = std::min(cols - h, cols + d - h);
      int prev = -1;
      for (int r = v->Head(y, d); r >= 0; r = v->runs[r].next) {
        CostVolume::Run& run = v->runs[r];
        // Its columns inside the image [vb, ve), widened; never narrowed
        // (its columns outside cost +inf).
        const int vb = std::max(run.begin, lo), ve = std::min(run.end, hi);
        if (vb < ve && ve - vb < kChunkCols && hi - lo >= kChunkCols) {
          const int e = std::min(hi, std::max(ve, vb + kChunkCols));
          run.begin = std::min(run.begin, std::max(lo, e - kChunkCols));
          run.end = std::max(run.end, e);
        }
        xmin[i] = std::min(xmin[i], run.begin);
        xmax[i] = std::max(xmax[i], run.end - 1);
        // Widened back over the run before it: one run.
        if (prev >= 0 && run.begin <= v->runs[prev].end) {
          v->runs[prev].end = std::max(v->runs[prev].end, run.end);
          v->runs[prev].next = run.next;
        } else {
          prev = r;
        }
      }
      v->tail[static_cast<size_t>(y - y0) * v->nd + i] = prev;
    }
  v->x0.assign(v->nd, 0);
  v->width.assign(v->nd, 0);
  v->offset.assign(v->nd, 0);
  size_t total = 0;
  for (int i = 0; i < v->nd; ++i) {
    v->offset[i] = total;
    if (xmax[i] < 0) continue;  // a disparity no pixel's band holds
    v->x0[i] = xmin[i];
    v->width[i] = xmax[i] + 1 - xmin[i];
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

  /// The cost at (x, dd) of the row, +inf outside the strip's columns of
  /// dd; only read where x's band holds dd (inside its runs).
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
    // Only each disparity's runs: elsewhere no pixel's band holds it.
    for (int dd = v.dlo; dd < v.dlo + v.nd; ++dd) {
      const float* c = row[dd - v.dlo];
      v.ForRuns(y, dd, [&](int x0, int x1) {
        // Left pixels x: cost[x], d[x]. Right pixels x - dd: right_cost, right_d.
        TakeLower(c, lo, hi, dd, x0, x1, cost.data(), d.data());
        const int r0 = std::max(x0, dd), r1 = std::min(x1, cols + dd);
        if (r1 > r0) TakeLower(c, lo, hi, dd, r0, r1, right_cost.data() - dd, right_d.data() - dd);
      });
    }
    // The best cost more than one disparity away from the winner.
    for (int dd = v.dlo; dd < v.dlo + v.nd; ++dd) {
      const float* c = row[dd - v.dlo];
      v.ForRuns(y, dd, [&](int x0, int x1) {
        TakeSecond(c, lo, hi, dd, x0, x1, d.data(), second.data());
      });
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

// Adds `from`'s counts to `to`'s.
void AddCounts(const DisparityMap& from, DisparityMap* to) {
  to->searched += from.searched;
  to->matched += from.matched;
  to->rejected_texture += from.rejected_texture;
  to->rejected_lr += from.rejected_lr;
  to->rejected_edge += from.rejected_edge;
}

// The searched pixels (lo <= hi): their bounding box, inclusive (x1 < 0:
// none), the union of their bands, and how many there are.
struct Searched {
  int x0, x1, y0, y1;
  float dlo, dhi;
  int count;
};
Searched FindSearched(const cv::Mat& lo_px, const cv::Mat& hi_px) {
  Searched s{lo_px.cols,
             -1,
             lo_px.rows,
             -1,
             std::numeric_limits<float>::infinity(),
             -std::numeric_limits<float>::infinity(),
             0};
  for (int y = 0; y < lo_px.rows; ++y) {
    const float* lo = lo_px.ptr<float>(y);
    const float* hi = hi_px.ptr<float>(y);
    for (int x = 0; x < lo_px.cols; ++x)
      if (lo[x] <= hi[x]) {
        s.x0 = std::min(s.x0, x);
        s.x1 = std::max(s.x1, x);
        s.y0 = std::min(s.y0, y);
        s.y1 = std::max(s.y1, y);
        s.dlo = std::min(s.dlo, lo[x]);
        s.dhi = std::max(s.dhi, hi[x]);
        ++s.count;
      }
  }
  return s;
}

}  // namespace

DisparityMap Nl1Matcher::Match(const cv::Mat& left, const cv::Mat& right, const cv::Mat& lo_px,
                               const cv::Mat& hi_px) const {
  CV_Assert(left.type() == CV_8UC1 && right.type() == CV_8UC1 && left.size() == right.size());
  CV_Assert(lo_px.type() == CV_32F && hi_px.type() == CV_32F && lo_px.size() == left.size() &&
            hi_px.size() == left.size());
  const int h = options_.window_half_px, hw = options_.weak_window_half_px;
  if (hw <= h || options_.weak_texture_dn <= 0 || left.rows <= 2 * hw || left.cols <= 2 * hw)
    return MatchOneWindow(options_, left, right, lo_px, hi_px);
  // Split the searched pixels by the wide window's standard deviation
  // (from box sums of I and I^2, O(1) per pixel, over the searched pixels'
  // bounding box): faint ones, whose wide window lies in the image, take the
  // wide window, the rest the narrow one.
  const Searched searched = FindSearched(lo_px, hi_px);
  const int x0 = std::max(searched.x0, hw), y0 = std::max(searched.y0, hw);
  const int x1 = std::min(searched.x1, left.cols - hw - 1),
            y1 = std::min(searched.y1, left.rows - hw - 1);
  cv::Mat narrow_lo = lo_px.clone(), wide_lo = lo_px.clone();
  const float none = std::numeric_limits<float>::infinity();
  wide_lo.setTo(none);
  if (x0 <= x1 && y0 <= y1) {
    // The box with its windows' margin: the filters' borders never reach a
    // pixel that is judged.
    const cv::Rect box(x0 - hw, y0 - hw, x1 - x0 + 2 * hw + 1, y1 - y0 + 2 * hw + 1);
    const int nw = 2 * hw + 1;
    cv::Mat image, mean, mean_sq;
    left(box).convertTo(image, CV_32F);
    cv::boxFilter(image, mean, CV_32F, cv::Size(nw, nw));
    cv::sqrBoxFilter(image, mean_sq, CV_32F, cv::Size(nw, nw));
    const float max_var = static_cast<float>(options_.weak_texture_dn * options_.weak_texture_dn);
    for (int y = y0; y <= y1; ++y) {
      const float* m = mean.ptr<float>(y - box.y);
      const float* m2 = mean_sq.ptr<float>(y - box.y);
      const float* lo = lo_px.ptr<float>(y);
      float* nlo = narrow_lo.ptr<float>(y);
      float* wlo = wide_lo.ptr<float>(y);
      for (int x = x0; x <= x1; ++x)
        if (m2[x - box.x] - m[x - box.x] * m[x - box.x] < max_var) {
          wlo[x] = lo[x];
          nlo[x] = none;
        }
    }
  }
  Nl1Options wide = options_;
  wide.window_half_px = hw;
  DisparityMap out = MatchOneWindow(options_, left, right, narrow_lo, hi_px);
  const DisparityMap w = MatchOneWindow(wide, left, right, wide_lo, hi_px);
  // The faint pixels lie in the box [x0, x1] x [y0, y1] (none if it is empty).
  for (int y = y0; y <= y1; ++y) {
    const float* wd = w.disparity_px.ptr<float>(y);
    const float* wc = w.confidence.ptr<float>(y);
    const float* wlo = wide_lo.ptr<float>(y);
    float* d = out.disparity_px.ptr<float>(y);
    float* c = out.confidence.ptr<float>(y);
    for (int x = x0; x <= x1; ++x)
      if (wlo[x] != none) {
        d[x] = wd[x];
        c[x] = wc[x];
      }
  }
  AddCounts(w, &out);
  return out;
}

DisparityMap Nl1Matcher::MatchOneWindow(const Nl1Options& options, const cv::Mat& left,
                                        const cv::Mat& right, const cv::Mat& lo_px,
                                        const cv::Mat& hi_px) {
  // Only the rectangle the searched pixels need is matched (a level's
  // fovea is a small part of its image): their bounding box and windows,
  // and on the right the columns their bands reach.
  const int h = options.window_half_px;
  const auto [x0, x1, y0, y1, dlo, dhi, count] = FindSearched(lo_px, hi_px);
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
  MatchCrop(options, left(crop), right(crop), lo_px(crop), hi_px(crop), count, &part);
  part.disparity_px = out.disparity_px;
  part.confidence = out.confidence;
  return part;
}

void Nl1Matcher::MatchCrop(const Nl1Options& options, const cv::Mat& left, const cv::Mat& right,
                           const cv::Mat& lo_px, const cv::Mat& hi_px, int searched,
                           DisparityMap* result) {
  const int h = options.window_half_px, n = 2 * h + 1;
  DisparityMap& out = *result;
  if (left.rows < n || left.cols < n) return;
  cv::Mat ml;  // the left window means, for the texture test
  cv::boxFilter(left, ml, CV_32F, cv::Size(n, n));
  const bool prenormalized = options.cost == "prenormalized";
  const bool zero_mean_ssd = options.cost == "zero_mean_ssd";
  cv::Mat image, sl, sr, a, b;
  left.convertTo(image, CV_32F);
  if (zero_mean_ssd) {
    // The 8-bit images themselves.
  } else if (!prenormalized) {
    // The 8-bit images and their window sums.
    cv::boxFilter(left, sl, CV_32S, cv::Size(n, n), cv::Point(-1, -1), false);
    cv::boxFilter(right, sr, CV_32S, cv::Size(n, n), cv::Point(-1, -1), false);
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
  // Strips of rows are independent: every other strip from `first` on,
  // each with its own bands, texture test and cost volume, into `o` (rows
  // apart from the other half's, in the same maps).
  auto match_strips = [&](int first, DisparityMap* o) {
    CostVolume v;
    RowWinners w(left.cols);
    for (int y0 = h + first * kStripRows; y0 < left.rows - h; y0 += 2 * kStripRows) {
      const int y1 = std::min(y0 + kStripRows, left.rows - h);
      SearchBands(image, ml, lo_px, hi_px, options, y0, y1, &bands, o);
      if (!SizeVolume(bands, y0, y1, h, &v)) continue;
      if (prenormalized)
        FillPrenormalized(a, b, h, &v);
      else if (zero_mean_ssd)
        FillZeroMeanSsd(left, right, h, &v);
      else
        FillWindowMean(left, right, sl, sr, h, &v);
      for (int y = y0; y < y1; ++y) {
        w.Find(v, bands, y);
        MatchRow(bands, y, options.lr_tolerance_px, &w, o);
      }
    }
  };
  // A large crop (a full-resolution periphery) is matched on two threads,
  // the machine's two cores: half its strips each, interleaved so that
  // both get a like share of the bands. A fovea's crop is too small to pay
  // for a thread. The same result either way.
  DisparityMap odd;  // the second thread's counts; its maps are `out`'s
  odd.disparity_px = out.disparity_px;
  odd.confidence = out.confidence;
  std::future<void> other;
  if (searched >= kThreadedMinPixels)
    other = std::async(std::launch::async, match_strips, 1, &odd);
  else
    match_strips(1, &out);
  match_strips(0, &out);
  if (other.valid()) other.get();
  AddCounts(odd, &out);
}

}  // namespace fovea
