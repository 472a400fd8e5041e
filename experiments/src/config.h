// A run's configuration: every parameter, its documented default and its
// allowed range, in one table; read from YAML (yaml-cpp), checked before any
// work starts, and written back out in full beside the results.
#pragma once

#include <cstdint>
#include <string>
#include <variant>
#include <vector>

#include "fovea/ddr.h"

namespace experiments {

struct RunConfig {
  std::string scene;                 ///< catalog name or path; empty = the default scene
  uint64_t seed = 0;                 ///< the one seed: sensor noise and fixation draws
  std::string matcher = "nl1";       ///< per-level matcher of the foveated stage
  double noise_sigma_dn = 2.0;       ///< sensor read noise, grey levels
  fovea::FoveaOptions fovea;
};

/// One parameter: a path in the YAML file ("idr.unique_share"), what it is,
/// and where it lives in a RunConfig.
struct ConfigParam {
  template <class T>
  ConfigParam(std::string path_, std::string doc_, T* target_, double lo_ = 0, double hi_ = 0,
              std::vector<std::string> choices_ = {})
      : path(std::move(path_)), doc(std::move(doc_)), target(target_), lo(lo_), hi(hi_), choices(std::move(choices_)) {}
  std::string path;
  std::string doc;
  std::variant<double*, int*, bool*, std::string*, uint64_t*> target;
  double lo = 0, hi = 0;             ///< inclusive range for numbers
  std::vector<std::string> choices;  ///< allowed values for a string (empty = any)
};

/// Every parameter of `config`, bound to its fields, in file order.
std::vector<ConfigParam> ConfigParams(RunConfig* config);

/// Reads a YAML file over the defaults. Throws UsageError naming the key and
/// the problem (unknown key, wrong type, out of range, unreadable file).
RunConfig LoadConfig(const std::string& path);

/// Sets one parameter from its text form (as in a YAML scalar); throws
/// UsageError like LoadConfig.
void SetParam(RunConfig* config, const std::string& path, const std::string& value);

/// The full effective configuration as YAML, each key with its meaning and
/// range as a comment.
std::string DumpConfig(const RunConfig& config);

}  // namespace experiments
