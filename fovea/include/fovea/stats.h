// Order statistics, one rule for the whole testbed (the algorithms' IDR
// quantiles and the harness's scores).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

namespace fovea {

/// The element of rank k (0-based, k < size) of *v in sorted order: the
/// value std::nth_element puts at k. *v may be reordered. When every value
/// is non-negative (NaN and -0 aside), their bit patterns sort as the values
/// do: one pass counts them by their top 16 bits, and only the bucket that
/// holds rank k is searched (on a few hundred thousand scores, several times
/// faster than nth_element over all of them). Otherwise nth_element.
inline double NthSmallest(std::vector<double>* v, size_t k) {
  std::vector<double>& a = *v;
  constexpr size_t kRadixFrom = 4096;  // below, nth_element is as fast
  constexpr uint64_t kInfBits = 0x7ff0000000000000ull;
  if (a.size() >= kRadixFrom) {
    std::vector<uint32_t> count(size_t{1} << 16, 0);
    bool ordered = true;
    for (const double x : a) {
      uint64_t bits;
      std::memcpy(&bits, &x, sizeof bits);
      ordered &= bits <= kInfBits;  // the sign bit clear, not NaN
      ++count[bits >> 48];
    }
    if (ordered) {
      size_t below = 0, bucket = 0;
      while (below + count[bucket] <= k) below += count[bucket++];
      std::vector<double> in_bucket;
      in_bucket.reserve(count[bucket]);
      for (const double x : a) {
        uint64_t bits;
        std::memcpy(&bits, &x, sizeof bits);
        if ((bits >> 48) == bucket) in_bucket.push_back(x);
      }
      std::nth_element(in_bucket.begin(), in_bucket.begin() + static_cast<long>(k - below),
                       in_bucket.end());
      return in_bucket[k - below];
    }
  }
  std::nth_element(a.begin(), a.begin() + static_cast<long>(k), a.end());
  return a[k];
}

/// Quantile (below) of a non-empty *v without a copy: *v may be reordered.
inline double QuantileInPlace(std::vector<double>* v, double q) {
  const auto k =
      std::min(v->size() - 1, static_cast<size_t>(std::lround(q * double(v->size() - 1))));
  return NthSmallest(v, k);
}

/// The q-quantile of `v` (0 <= q <= 1): its element of rank round(q (n - 1))
/// in sorted order, so q = 0 is the smallest, q = 1 the largest and q = 0.5
/// the median (the upper one for even n); `if_empty` when there are no
/// values.
inline double Quantile(std::vector<double> v, double q, double if_empty = 0) {
  return v.empty() ? if_empty : QuantileInPlace(&v, q);
}

}  // namespace fovea
