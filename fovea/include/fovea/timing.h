// Wall-clock timing of pipeline stages, shared by the pipeline and the
// experiment harness (compute times in the records and summaries).
#pragma once

#include <chrono>

namespace fovea {

using Clock = std::chrono::steady_clock;

/// Seconds elapsed since `t0`.
inline double Since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

}  // namespace fovea
