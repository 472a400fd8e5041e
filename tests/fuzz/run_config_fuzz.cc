// libFuzzer target: the run-config reader. Any bytes as a YAML config: it is
// read over the defaults and checked, or refused with an input error; a
// config that is read dumps to YAML that reads back to the same dump.
#include <cstdint>
#include <cstdlib>
#include <string>

#include "experiments/config/config.h"
#include "experiments/usage_error.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  experiments::RunConfig config;
  try {
    experiments::ApplyYaml(experiments::ParseYaml(text, "fuzz: "), &config, "fuzz: ");
    config.Check();
  } catch (const rig::InputError&) {
    return 0;  // refused with a message: what a bad config should get
  }
  const std::string dump = experiments::DumpConfig(config);
  experiments::RunConfig again;
  experiments::ApplyYaml(experiments::ParseYaml(dump, "dump: "), &again, "dump: ");
  if (experiments::DumpConfig(again) != dump) std::abort();  // the dump must read back the same
  if (experiments::ConfigHash(again) != experiments::ConfigHash(config)) std::abort();
  return 0;
}
