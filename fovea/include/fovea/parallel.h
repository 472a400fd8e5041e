// Splitting independent work between the machine's two cores.
#pragma once

#include <cstddef>
#include <future>

namespace fovea {

/// Calls f(begin, end) over [0, n): with `two_threads` (and n >= 2), f(0,
/// n / 2) on a second thread and f(n / 2, n) on the caller's, returning when
/// both are done; otherwise f(0, n) on the caller's. Each call must touch
/// only what its own range owns, so that the result does not depend on the
/// split.
template <typename F>
void ForHalves(std::size_t n, bool two_threads, F&& f) {
  if (!two_threads || n < 2) {
    f(std::size_t{0}, n);
    return;
  }
  auto first = std::async(std::launch::async, [&f, n] { f(std::size_t{0}, n / 2); });
  f(n / 2, n);
  first.get();
}

}  // namespace fovea
