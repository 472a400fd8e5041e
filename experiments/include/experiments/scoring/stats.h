// Order statistics for the ground-truth scores.
#pragma once

#include <algorithm>
#include <vector>

namespace experiments {

/// The q-quantile of `v`: its element of rank floor(q n) (the last for
/// q = 1), so q = 0.5 is the median (the upper one for even n); `if_empty`
/// when there are no values.
inline double Quantile(std::vector<double> v, double q, double if_empty = 0) {
  if (v.empty()) return if_empty;
  const size_t k = std::min(v.size() - 1, static_cast<size_t>(q * v.size()));
  std::nth_element(v.begin(), v.begin() + k, v.end());
  return v[k];
}

}  // namespace experiments
