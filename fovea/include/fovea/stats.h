// Order statistics, one rule for the whole testbed (the algorithms' IDR
// quantiles and the harness's scores).
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

namespace fovea {

/// The q-quantile of `v` (0 <= q <= 1): its element of rank round(q (n - 1))
/// in sorted order, so q = 0 is the smallest, q = 1 the largest and q = 0.5
/// the median (the upper one for even n); `if_empty` when there are no
/// values.
inline double Quantile(std::vector<double> v, double q, double if_empty = 0) {
  if (v.empty()) return if_empty;
  const auto k = std::min(v.size() - 1, static_cast<size_t>(std::lround(q * double(v.size() - 1))));
  std::nth_element(v.begin(), v.begin() + static_cast<long>(k), v.end());
  return v[k];
}

}  // namespace fovea
