#include "fovea/stats.h"

#include <catch2/catch.hpp>
#include <limits>
#include <random>

namespace {
// The value std::nth_element puts at rank k of a copy.
double ByNthElement(std::vector<double> v, size_t k) {
  std::nth_element(v.begin(), v.begin() + static_cast<long>(k), v.end());
  return v[k];
}
}  // namespace

TEST_CASE("NthSmallest gives nth_element's value at every rank tried", "[stats]") {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(0, 1);
  const double inf = std::numeric_limits<double>::infinity();
  // Scores as the scorer sees them (errors from 1e-5 to 1, many equal, some
  // zero), denormals and +inf; sizes below and above the radix pass's start.
  for (const size_t n : {1ul, 7ul, 4095ul, 4096ul, 50000ul}) {
    std::vector<double> v(n);
    for (size_t i = 0; i < n; ++i) {
      const double r = unit(rng);
      v[i] = r < 0.05   ? 0.0
             : r < 0.1  ? 1e-3
             : r < 0.12 ? std::numeric_limits<double>::denorm_min() * (1 + i % 5)
             : r < 0.13 ? inf
                        : std::pow(10.0, -5 * unit(rng));
    }
    for (const double q : {0.0, 0.1, 0.5, 0.8, 0.9, 1.0}) {
      const auto k = static_cast<size_t>(q * double(n - 1));
      INFO("n " << n << ", k " << k);
      std::vector<double> copy = v;
      CHECK(fovea::NthSmallest(&copy, k) == ByNthElement(v, k));
    }
  }
  // Negative values, -0 and NaN-free mixed signs take nth_element's path:
  // still the same value.
  std::vector<double> mixed(10000);
  for (size_t i = 0; i < mixed.size(); ++i) mixed[i] = unit(rng) - 0.5;
  mixed[17] = -0.0;
  for (const size_t k : {0ul, 5000ul, 9999ul}) {
    std::vector<double> copy = mixed;
    CHECK(fovea::NthSmallest(&copy, k) == ByNthElement(mixed, k));
  }
  // Quantile keeps its rule: rank round(q (n - 1)), if_empty for none.
  CHECK(fovea::Quantile({3, 1, 2, 5}, 0.5) == 3);
  CHECK(fovea::Quantile({}, 0.5, -1) == -1);
}
