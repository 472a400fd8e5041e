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

/// The read noise of the experiments' cameras, grey levels: runs, IDR and
/// fixation figures and the chessboards use it (the simulator's own default
/// is 0, for the tests).
constexpr double kExperimentNoiseSigmaDn = 2.0;

/// The run-level parameters: the harness's own, beside the algorithms'
/// (fovea/params.h) and the simulated rig's (sim::params).
namespace params {
using rig::ParamSpec;
inline constexpr const char* kMethods[] = {"fovea", "static_sgbm", nullptr};
inline constexpr const char* kMatchers[] = {"nl1", "sgbm", nullptr};
inline constexpr const char* kRigTypes[] = {"sim", "hardware", nullptr};
inline constexpr ParamSpec kScene{"scene",
                                  "catalog scene name, random[:SEED[:N]], or path to an MJCF scene "
                                  "file (empty: cylinder_planes)"};
inline constexpr ParamSpec kSeed{"seed", "the one seed: sensor noise and every fixation draw", 0,
                                 9007199254740992.0};
inline constexpr ParamSpec kMethod{"method",
                                   "fovea: the FOVEA loop; static_sgbm: the baseline, StereoSGBM "
                                   "on the static pair at the home pose and widest "
                                   "baseline",
                                   0, 0, kMethods};
inline constexpr ParamSpec kMatcher{"matcher", "matcher of the foveated stage", 0, 0, kMatchers};
inline constexpr ParamSpec kRigType{
    "rig.type", "sim: the simulated TAVT; hardware: serial stages and cameras (the keys below)", 0,
    0, kRigTypes};
inline constexpr ParamSpec kPort{"rig.port",
                                 "hardware: the stages' serial port (e.g. /dev/ttyUSB0)"};
inline constexpr ParamSpec kBaud{"rig.baud", "hardware: the serial port's baud rate", 1200, 230400};
inline constexpr ParamSpec kEmulateStages{
    "rig.emulate_stages",
    "hardware: drive the indexer emulator (a pseudo-terminal in this process) instead of rig.port"};
inline constexpr ParamSpec kUnits{"rig.units",
                                  "hardware: indexer unit addresses of the six axes (left "
                                  "baseline, pan, tilt, right baseline, pan, tilt)"};
inline constexpr ParamSpec kDirections{
    "rig.directions",
    "hardware: motor direction of each axis against the rig's convention, +1 or -1, same order"};
inline constexpr ParamSpec kLeftCamera{
    "rig.left_camera",
    "hardware: left camera: V4L2 index or path, video file, or image sequence (rec/left_%05d.png)"};
inline constexpr ParamSpec kRightCamera{"rig.right_camera",
                                        "hardware: right camera, as rig.left_camera"};
inline constexpr ParamSpec kCalibration{
    "rig.calibration",
    "calibration file (fovea calibrate, or OpenCV YAML by hand): what the rig believes it is; a "
    "hardware rig needs one, a simulated one without it believes its design"};
inline constexpr ParamSpec kFrameTimeoutS{
    "rig.frame_timeout_s", "hardware: longest wait for a camera frame, seconds", 0.01, 60};
inline constexpr ParamSpec kBaselineVelocityMS{
    "rig.baseline_velocity_m_s",
    "hardware: baseline axes' speed, metres per second (acceleration 10x per second)", 1e-4, 1};
inline constexpr ParamSpec kPanTiltVelocityRadS{
    "rig.pan_tilt_velocity_rad_s",
    "hardware: pan and tilt axes' speed, radians per second (acceleration 10x per second)", 1e-3,
    10};
inline constexpr ParamSpec kScoreCompareStatic{
    "score.compare_static",
    "a FOVEA run also maps the scene with the static StereoSGBM baseline (after its fixations) and "
    "compares the "
    "two on the pixels both map (summary: vs_static)"};
inline constexpr ParamSpec kStaticBaselineM{
    "static.baseline_m",
    "static_sgbm's baseline, metres (0 = the widest at which a point at idr.z_min_m keeps within "
    "half the image "
    "width)",
    0, 4};
}  // namespace params

struct RunConfig {
  RunConfig() { rig.noise.read_noise_sigma_dn = kExperimentNoiseSigmaDn; }
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
    std::string left_camera, right_camera;   // the calibration is rig.calibration (SimRigConfig)
    double frame_timeout_s = 2;
    double baseline_velocity_m_s = 0.05;
    double pan_tilt_velocity_rad_s = 1.0;
  } hardware;
  double static_baseline_m = 0;  ///< static_sgbm's baseline; 0 = the widest useful
  bool compare_static = true;    ///< a FOVEA run compares itself with the static baseline
  fovea::FoveaOptions fovea;

  /// Checks every parameter against its spec and the parts against each
  /// other; throws UsageError naming the key.
  void Check() const;
};

/// Six whole numbers from "a,b,c,d,e,f"; throws UsageError naming `key`.
std::array<int, 6> SixInts(const std::string& text, const std::string& key);

/// One parameter of a RunConfig: its spec (key, meaning, range) and the field
/// it sets. A parameter's default is the field's initial value.
struct ConfigParam {
  const rig::ParamSpec* spec;
  std::variant<double*, int*, bool*, std::string*, uint64_t*> target;
  const char* path() const { return spec->key; }
};

/// Every parameter of `config`, bound to its fields, in file order.
std::vector<ConfigParam> ConfigParams(RunConfig* config);

/// Reads a YAML file over the defaults. Throws UsageError naming the key and
/// the problem (unknown key, wrong type, out of range, unreadable file).
RunConfig LoadConfig(const std::string& path);

/// Sets one parameter from its text form (as in a YAML scalar); throws
/// UsageError like LoadConfig.
void SetParam(RunConfig* config, const std::string& path, const std::string& value);

/// Each "KEY=VALUE" of a repeatable --set flag, in order, through SetParam;
/// UsageError for an entry without '='.
void SetParams(RunConfig* config, const std::vector<std::string>& key_values);

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
