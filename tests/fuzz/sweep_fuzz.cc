// libFuzzer target: the sweep-file reader. Any bytes as a sweep file: its
// grid is built and every run's config checked, or it is refused with an
// input error; every run of a grid has its own id.
#include <cstdint>
#include <cstdlib>
#include <set>
#include <string>

#include "experiments/config/sweep.h"
#include "experiments/usage_error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  experiments::Sweep sweep;
  try {
    sweep = experiments::ParseSweep(text, "fuzz/sweep.yaml");
  } catch (const rig::InputError&) {
    return 0;
  }
  if (sweep.runs.empty() || static_cast<long>(sweep.runs.size()) > experiments::kMaxSweepRuns)
    std::abort();
  std::set<std::string> ids;
  for (const experiments::SweepRun& run : sweep.runs)
    if (!ids.insert(run.id).second || run.id != experiments::ConfigHash(run.config)) std::abort();
  experiments::GridJson(sweep);
  return 0;
}
