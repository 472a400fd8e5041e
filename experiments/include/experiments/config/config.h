// A run's configuration: every parameter, its documented default and its
// allowed range, in one table; read from YAML (yaml-cpp), checked before any
// work starts, and written back out in full beside the results.
#pragma once

#include <yaml-cpp/node/node.h>

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "experiments/usage_error.h"
#include "fovea/ddr.h"
#include "sim/config.h"

namespace experiments {

struct RunConfig {
  RunConfig() { rig.noise.read_noise_sigma_dn = 2.0; }
  std::string scene;  ///< catalog name or path; empty = the default scene
  uint64_t seed = 0;  ///< the one seed: sensor noise and fixation draws
  /// "fovea": the FOVEA loop; "static_sgbm": the baseline it is compared
  /// with, StereoSGBM on a static parallel pair at the home pose and the
  /// widest baseline, scored the same way.
  std::string method = "fovea";
  std::string matcher = "nl1";  ///< per-level matcher of the foveated stage
  sim::SimRigConfig rig;        ///< the simulated rig (its seed is `seed`)
  /// The real rig (rig.type: hardware): stages on a serial port (or the
  /// in-process emulator), two cameras, a calibration file. Axis limits and
  /// steps per unit are the rig.* ones above.
  struct Hardware {
    std::string type = "sim";
    std::string port;
    int baud = 9600;
    bool emulate_stages = false;
    std::string units = "1,2,3,4,5,6";       ///< indexer addresses in rig::Axis order
    std::string directions = "1,1,1,1,1,1";  ///< motor direction signs in rig::Axis order
    std::string left_camera, right_camera, calibration;
    double frame_timeout_s = 2;
    double baseline_velocity_m_s = 0.05;
    double pan_tilt_velocity_rad_s = 1.0;
  } hardware;
  double static_baseline_m = 0;  ///< static_sgbm's baseline; 0 = the widest useful
  fovea::FoveaOptions fovea;

  /// Checks what single ranges cannot (the parts against each other);
  /// throws UsageError naming the key.
  void Check() const;
};

/// Six whole numbers from "a,b,c,d,e,f"; throws UsageError naming `key`.
std::array<int, 6> SixInts(const std::string& text, const std::string& key);

/// One parameter: a path in the YAML file ("idr.unique_share"), what it is,
/// and where it lives in a RunConfig.
struct ConfigParam {
  template <class T>
  ConfigParam(std::string path_, std::string doc_, T* target_, double lo_ = 0, double hi_ = 0,
              std::vector<std::string> choices_ = {})
      : path(std::move(path_)),
        doc(std::move(doc_)),
        target(target_),
        lo(lo_),
        hi(hi_),
        choices(std::move(choices_)) {}
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

/// The same for a command-line flag that sets parameter `path`: the flag's
/// value is checked against the table like a YAML value, and a message names
/// the flag ("--sigma (idr.log_sigma_px): 0 is out of range [1, 8]").
void SetParamFromFlag(RunConfig* config, const std::string& flag, const std::string& path,
                      const std::string& value);

/// The one number parser of flags and YAML values: a finite decimal number
/// ("3", "-0.5", "2e-3") and nothing else (no NaN, infinity, hex, spaces or
/// trailing characters).
std::optional<double> ParseNumber(const std::string& text);

/// The comma-separated fields of `text`, empty ones included ("a,,b" has 3).
std::vector<std::string> SplitFields(const std::string& text);

/// The full effective configuration as YAML, each key with its meaning and
/// range as a comment.
std::string DumpConfig(const RunConfig& config);

/// Every parameter's path and value as text (as ParamText), in table order.
std::vector<std::pair<std::string, std::string>> ParamValues(const RunConfig& config);

/// Every parameter as "path=value" lines in table order: the canonical text
/// that names a run (see ConfigHash).
std::string CanonicalConfig(const RunConfig& config);

/// A stable 64-bit FNV-1a hash of CanonicalConfig, as 16 hex digits: the
/// same on every machine and build.
std::string ConfigHash(const RunConfig& config);

/// The value of one parameter as text (as written in the YAML file).
std::string ParamText(RunConfig* config, const std::string& path);

/// Parses a YAML file (rig::ReadInputFile: a regular file of at most 64 MiB);
/// throws UsageError prefixed with `where` when it cannot be read, is not
/// YAML (with the line), holds more than one document, repeats a key in a
/// mapping, or holds more than a million values.
YAML::Node LoadYamlFile(const std::string& path, const std::string& where);

/// The same for YAML text.
YAML::Node ParseYaml(const std::string& text, const std::string& where);

/// Reads the keys of a YAML mapping over `config` (as LoadConfig does for a
/// file); `where` prefixes every error message.
void ApplyYaml(const YAML::Node& root, RunConfig* config, const std::string& where);

}  // namespace experiments
