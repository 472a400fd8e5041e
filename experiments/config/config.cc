#include "experiments/config/config.h"

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>

namespace experiments {
namespace {

std::string FormatNumber(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

std::string Range(const ConfigParam& p) {
  if (std::holds_alternative<bool*>(p.target)) return "true or false";
  if (std::holds_alternative<std::string*>(p.target)) {
    if (p.choices.empty()) return "any text";
    std::string s = "one of";
    for (size_t i = 0; i < p.choices.size(); ++i) s += (i ? ", " : " ") + p.choices[i];
    return s;
  }
  return "[" + FormatNumber(p.lo) + ", " + FormatNumber(p.hi) + "]";
}

// Valid UTF-8 with no control character but tab and newline: the text a
// string parameter may hold, which a YAML dump writes and reads back exactly.
bool IsPlainText(const std::string& text) {
  for (size_t i = 0; i < text.size();) {
    const auto c = static_cast<unsigned char>(text[i]);
    int n = 0;  // continuation bytes
    if (c >= 0xc2 && c <= 0xdf)
      n = 1;
    else if (c >= 0xe0 && c <= 0xef)
      n = 2;
    else if (c >= 0xf0 && c <= 0xf4)
      n = 3;
    else if (c >= 0x80)
      return false;
    if (i + n >= text.size()) return false;
    unsigned long code = n == 0 ? c : c & (0x7f >> (n + 1));
    for (int k = 1; k <= n; ++k) {
      const auto cc = static_cast<unsigned char>(text[i + k]);
      if ((cc & 0xc0) != 0x80) return false;
      code = (code << 6) | (cc & 0x3f);
    }
    const bool control = code < 0x20 ? code != '\t' && code != '\n' : code >= 0x7f && code < 0xa0;
    // Control characters, overlong forms, surrogates, past U+10FFFF.
    if (control || (n == 2 && code < 0x800) || (n == 3 && (code < 0x10000 || code > 0x10ffff)) ||
        (code >= 0xd800 && code <= 0xdfff))
      return false;
    i += n + 1;
  }
  return true;
}

// `label` names the parameter in messages: "key 'idr.sigma'" or "--sigma".
void Assign(const ConfigParam& p, const std::string& text, const std::string& label) {
  auto fail = [&](const std::string& why) { throw UsageError(label + ": " + why); };
  const std::string shown = "'" + rig::ClipForMessage(text) + "'";
  if (auto* b = std::get_if<bool*>(&p.target)) {
    if (text == "true")
      **b = true;
    else if (text == "false")
      **b = false;
    else
      fail("expected true or false, got " + shown);
    return;
  }
  if (auto* s = std::get_if<std::string*>(&p.target)) {
    if (!p.choices.empty() &&
        std::find(p.choices.begin(), p.choices.end(), text) == p.choices.end())
      fail(shown + " is not " + Range(p));
    if (!IsPlainText(text))
      fail("expected UTF-8 text without control characters (tabs and newlines aside)");
    **s = text;
    return;
  }
  const std::optional<double> v = ParseNumber(text);
  if (!v) fail("expected a number, got " + shown);
  const bool integral = !std::holds_alternative<double*>(p.target);
  if (integral && *v != std::floor(*v)) fail("expected a whole number, got " + shown);
  if (*v < p.lo || *v > p.hi) fail(rig::ClipForMessage(text) + " is out of range " + Range(p));
  // Written as digits, a whole number is compared exactly: a double rounds
  // 2^53 + 1 down to 2^53.
  long long exact = 0;
  const auto digits = std::from_chars(text.data(), text.data() + text.size(), exact);
  if (integral && digits.ptr == text.data() + text.size() &&
      (digits.ec != std::errc() || exact < static_cast<long long>(p.lo) ||
       exact > static_cast<long long>(p.hi)))
    fail(rig::ClipForMessage(text) + " is out of range " + Range(p));
  if (auto* d = std::get_if<double*>(&p.target))
    **d = *v;
  else if (auto* i = std::get_if<int*>(&p.target))
    **i = static_cast<int>(*v);
  else if (auto* u = std::get_if<uint64_t*>(&p.target))
    **u = static_cast<uint64_t>(*v);
}

std::string ValueText(const ConfigParam& p) {
  if (auto* b = std::get_if<bool*>(&p.target)) return **b ? "true" : "false";
  if (auto* s = std::get_if<std::string*>(&p.target)) return (*s)->empty() ? "\"\"" : **s;
  if (auto* d = std::get_if<double*>(&p.target)) return FormatNumber(**d);
  if (auto* i = std::get_if<int*>(&p.target)) return std::to_string(**i);
  return std::to_string(**std::get_if<uint64_t*>(&p.target));
}

// The value as YAML text that reads back the same: a string stays plain
// only where YAML reads it back unchanged as a value (no '#', ': ', newline,
// leading space, null word); else it is double-quoted with escapes.
std::string YamlValueText(const ConfigParam& p) {
  auto* s = std::get_if<std::string*>(&p.target);
  if (!s) return ValueText(p);
  YAML::Emitter plain;
  plain << **s;
  static const std::set<std::string> kNullWords = {"", "~", "null", "Null", "NULL"};
  if (plain.c_str() == **s && !kNullWords.count(**s)) return **s;
  YAML::Emitter quoted;
  quoted << YAML::DoubleQuoted << **s;
  return quoted.c_str();
}

}  // namespace

std::optional<double> ParseNumber(const std::string& text) {
  double v = 0;
  const char* b = text.data();
  const auto r = std::from_chars(b, b + text.size(), v);
  if (r.ec != std::errc() || r.ptr != b + text.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

std::vector<ConfigParam> ConfigParams(RunConfig* c) {
  fovea::FoveaOptions& f = c->fovea;
  constexpr double kBig = 1e9;
  return {
      {"scene", "catalog scene name or path to an MJCF scene file (empty: cylinder_planes)",
       &c->scene},
      {"seed", "the one seed: sensor noise and every fixation draw", &c->seed, 0,
       9007199254740992.0},
      {"method",
       "fovea: the FOVEA loop; static_sgbm: the baseline, StereoSGBM on the static pair at the "
       "home pose and widest baseline",
       &c->method,
       0,
       0,
       {"fovea", "static_sgbm"}},
      {"matcher", "matcher of the foveated stage", &c->matcher, 0, 0, {"nl1", "sgbm"}},
      {"rig.width_px", "image width, pixels", &c->rig.width_px, 64, 4096},
      {"rig.height_px", "image height, pixels", &c->rig.height_px, 48, 4096},
      {"rig.horizontal_fov_deg",
       "lens: horizontal field of view edge to edge, degrees (16 mm lens: 30)",
       &c->rig.horizontal_fov_deg, 5, 100},
      {"rig.carriage_max_m", "baseline axes: each carriage's travel from the rail centre, metres",
       &c->rig.carriage_max_m, 0.01, 2},
      {"rig.home_baseline_m", "baseline at the home pose (the reference view's pose), metres",
       &c->rig.home_baseline_m, 0.002, 4},
      {"rig.pan_limit_deg", "pan axes: symmetric travel limit, degrees", &c->rig.pan_limit_deg, 1,
       179},
      {"rig.tilt_limit_deg", "tilt axes: symmetric travel limit, degrees", &c->rig.tilt_limit_deg,
       1, 89},
      {"rig.baseline_steps_per_mm", "baseline axes: motor steps per millimetre",
       &c->rig.baseline_steps_per_mm, 1, 1e6},
      {"rig.pan_tilt_steps_per_deg", "pan and tilt axes: motor steps per degree",
       &c->rig.pan_tilt_steps_per_deg, 1, 1e6},
      {"rig.type",
       "sim: the simulated TAVT; hardware: serial stages and cameras (the keys below)",
       &c->hardware.type,
       0,
       0,
       {"sim", "hardware"}},
      {"rig.port", "hardware: the stages' serial port (e.g. /dev/ttyUSB0)", &c->hardware.port},
      {"rig.baud", "hardware: the serial port's baud rate", &c->hardware.baud, 1200, 230400},
      {"rig.emulate_stages",
       "hardware: drive the indexer emulator (a pseudo-terminal in this process) instead of "
       "rig.port",
       &c->hardware.emulate_stages},
      {"rig.units",
       "hardware: indexer unit addresses of the six axes (left baseline, pan, tilt, right "
       "baseline, pan, tilt)",
       &c->hardware.units},
      {"rig.directions",
       "hardware: motor direction of each axis against the rig's convention, +1 or -1, same order",
       &c->hardware.directions},
      {"rig.left_camera",
       "hardware: left camera: V4L2 index or path, video file, or image sequence "
       "(rec/left_%05d.png)",
       &c->hardware.left_camera},
      {"rig.right_camera", "hardware: right camera, as rig.left_camera", &c->hardware.right_camera},
      {"rig.calibration", "hardware: calibration file (fovea calibrate, or OpenCV YAML by hand)",
       &c->hardware.calibration},
      {"rig.frame_timeout_s", "hardware: longest wait for a camera frame, seconds",
       &c->hardware.frame_timeout_s, 0.01, 60},
      {"rig.baseline_velocity_m_s",
       "hardware: baseline axes' speed, metres per second (acceleration 10x per second)",
       &c->hardware.baseline_velocity_m_s, 1e-4, 1},
      {"rig.pan_tilt_velocity_rad_s",
       "hardware: pan and tilt axes' speed, radians per second (acceleration 10x per second)",
       &c->hardware.pan_tilt_velocity_rad_s, 1e-3, 10},
      {"rig.record_dir",
       "sim: also write every capture to this folder (left_NNNNN.png, right_NNNNN.png) for replay",
       &c->rig.record_dir},
      {"rig.noise_sigma_dn", "sensor read noise, grey levels (0 = off)",
       &c->rig.noise.read_noise_sigma_dn, 0, 50},
      {"rig.blur_sigma_px", "optical blur before the noise, pixels (0 = off)",
       &c->rig.noise.blur_sigma_px, 0, 10},
      {"loop.fixations", "successful fixations to make", &f.fixations, 1, 10000},
      {"loop.stay_in_idr_view", "fixate only points inside the IDR view (the region the run maps)",
       &f.stay_in_idr_view},
      {"loop.fixate_holes",
       "beyond the paper: pixels the map is silent at are candidates, at the depth of the nearest "
       "mapped pixel (false: the paper's rule)",
       &f.fixate_holes},
      {"loop.stall_fixations",
       "stop when the foveal share grew by less than stall_growth over this many fixations (0 = "
       "never)",
       &f.stall_fixations, 0, 10000},
      {"loop.stall_growth", "see stall_fixations (share of the IDR view)", &f.stall_growth, 0, 1},
      {"loop.attempts_per_fixation",
       "attempt budget per fixation wanted (points that cannot be fixated)",
       &f.attempts_per_fixation, 1, 100},
      {"idr.log_sigma_px", "LoG scale of the zero crossings, pixels",
       &f.idr.zero_crossings.sigma_px, 1, 8},
      {"idr.unique_share", "share of zero crossings kept unambiguous at the initial baseline",
       &f.idr.unique_share, 0.5, 1},
      {"idr.z_min_m", "nearest scene distance, metres", &f.idr.z_min_m, 0.05, 10},
      {"idr.max_slant_deg", "largest surface slant for the expansion factor, degrees",
       &f.idr.max_slant_deg, 0, 89},
      {"idr.max_expansion", "cap on the baseline expansion factor per stage", &f.idr.max_expansion,
       1.1, 16},
      {"idr.vergent_search_px", "P: the vergent stage resolves +-P px (IDR termination)",
       &f.idr.vergent_search_px, 0.5, 64},
      {"idr.max_stages", "baseline stage budget", &f.idr.max_stages, 1, 20},
      {"idr.patch_size_px", "IDR patch size, pixels", &f.idr.patch_size_px, 4, 128},
      {"foveal.baseline_m", "vergent baseline, metres", &f.fixation.baseline_m, 0.001, 0.6},
      {"foveal.choose_placement",
       "beyond the paper: place the carriages per fixation (symmetric, right or left carriage "
       "innermost) so that no mapped surface hides the point from either camera (false: symmetric "
       "about the rail centre)",
       &f.fixation.choose_placement},
      {"foveal.left_pair",
       "beyond the paper, with foveal.choose_placement: where the map hides a point from every "
       "right camera, pair the left camera with itself at two carriage positions (the home pose's "
       "and foveal.baseline_m to its left; motion stereo, the scene must hold still)",
       &f.fixation.left_pair},
      {"foveal.horizontal_disparity_limit_px",
       "the fovea's horizontal disparity limit (sets Z_T), pixels",
       &f.fixation.foveal.tessellation.horizontal_disparity_limit_px, 2, 256},
      {"foveal.max_levels", "resolution levels of the tessellation",
       &f.fixation.foveal.tessellation.max_levels, 1, 6},
      {"foveal.fovea_patch_px", "patch size at full resolution, pixels",
       &f.fixation.foveal.fovea_patch_px, 4, 64},
      {"foveal.periphery_patch_px",
       "patch size at coarser levels, full-resolution pixels (at least 4 pixels of the level)",
       &f.fixation.foveal.periphery_patch_px, 4, 64},
      {"foveal.silent_check",
       "beyond the paper: where the map is silent, also search every depth from idr.z_min_m to "
       "infinity and drop the Z_T matches it confidently contradicts (false: the paper's rule, Z_T "
       "only)",
       &f.silent_check},
      {"foveal.servo_tolerance_px", "servoing stops below this centre disparity, pixels",
       &f.fixation.servo.tolerance_px, 0.01, 10},
      {"foveal.servo_search_px", "servoing's first search on a mapped point: +- this many pixels",
       &f.fixation.servo.search_px, 1, 300},
      {"foveal.servo_unique_ratio",
       "servoing on a hole searches every depth and keeps its best match only if its cost is below "
       "this share of the best elsewhere (1 = any)",
       &f.fixation.servo.unique_ratio, 0.01, 1},
      {"foveal.servo_mutual_px",
       "beyond the paper: a converged servo's match must be mutual (the right centre window, "
       "searched back along the left image's row, lands within this many pixels of the left "
       "centre), else the point is refused (0 = no check)",
       &f.fixation.servo.mutual_tolerance_px, 0, 100},
      {"foveal.silent_confidence",
       "see foveal.silent_check: the wider search's match confidence needed to drop a band match",
       &f.fixation.foveal.silent_confidence, 0, 1},
      {"foveal.servo_max_steps", "servoing step budget", &f.fixation.servo.max_steps, 0, 50},
      {"selection.deterministic", "always fixate the composite's maximum instead of drawing",
       &f.selection.deterministic},
      {"selection.draw_scale", "scale s of the exponential draw", &f.selection.draw_scale, 0.001,
       100},
      {"selection.histogram_bins", "bins of the composite's histogram", &f.selection.histogram_bins,
       2, 4096},
      {"selection.border_px", "fixation candidates keep this far from the image edge, pixels",
       &f.selection.border_px, 0, 200},
      {"selection.refused_radius_m",
       "candidates this close to a point that could not be fixated are left out, metres",
       &f.selection.refused_radius_m, 0, 1},
      {"criteria.gradient", "use gradient attraction", &f.criteria.gradient},
      {"criteria.suppression", "use local suppression", &f.criteria.suppression},
      {"criteria.proximity_2d", "use 2D proximity", &f.criteria.proximity_2d},
      {"criteria.proximity_3d", "use 3D proximity", &f.criteria.proximity_3d},
      {"criteria.gradient_blur_px", "gradient attraction's smoothing scale, pixels",
       &f.criteria.gradient_blur_px, 0.1, 50},
      {"criteria.suppressed_weight",
       "local suppression's weight where the map is foveal (1 elsewhere)",
       &f.criteria.suppressed_weight, 0, 1},
      {"criteria.suppression_radius_m",
       "local suppression also covers this distance around earlier fixation points, metres",
       &f.criteria.suppression_radius_m, 0, 1},
      {"criteria.peripheral_weight",
       "local suppression's weight where the map is peripheral (1 = the paper's rule: foveal data "
       "only)",
       &f.criteria.peripheral_weight, 0, 1},
      {"criteria.revisit_radius_m",
       "local suppression's weight is 0 this close to an earlier fixation point (or a hole's point "
       "aimed at), metres",
       &f.criteria.revisit_radius_m, 0, 1},
      {"criteria.proximity_2d_scale_px", "2D proximity's scale s in exp(-r / s), pixels",
       &f.criteria.proximity_2d_scale_px, 1, kBig},
      {"criteria.proximity_3d_low", "3D proximity's weight outside the Z_T band (1 inside)",
       &f.criteria.proximity_3d_low, 0, 1},
      {"static.baseline_m",
       "static_sgbm's baseline, metres (0 = the widest at which a point at idr.z_min_m keeps "
       "within half the image width)",
       &c->static_baseline_m, 0, 4},
      {"integration.overlap_share",
       "overlap share at which new patches replace old ones (and finer data blocks new ones)",
       &f.integration.overlap_share, 0.01, 1},
  };
}

void SetParam(RunConfig* config, const std::string& path, const std::string& value) {
  for (const ConfigParam& p : ConfigParams(config))
    if (p.path == path) return Assign(p, value, "key '" + path + "'");
  throw UsageError("unknown key '" + rig::ClipForMessage(path) + "'");
}

void SetParamFromFlag(RunConfig* config, const std::string& flag, const std::string& path,
                      const std::string& value) {
  for (const ConfigParam& p : ConfigParams(config))
    if (p.path == path) return Assign(p, value, flag + " (" + path + ")");
  throw std::logic_error("flag " + flag + " names no parameter '" + path + "'");
}

namespace {
void Walk(const YAML::Node& node, const std::string& prefix,
          std::map<std::string, const ConfigParam*>& params, const std::string& where) {
  for (const auto& kv : node) {
    const std::string key = kv.first.as<std::string>();
    const std::string path = prefix.empty() ? key : prefix + "." + key;
    const auto it = params.find(path);
    if (kv.second.IsMap()) {
      if (it != params.end())
        throw UsageError(where + "key '" + path + "': expected a value, got a mapping");
      bool known_section = false;
      for (const auto& [name, p] : params) known_section |= name.rfind(path + ".", 0) == 0;
      if (!known_section)
        throw UsageError(where + "unknown key '" + rig::ClipForMessage(path) + "'");
      Walk(kv.second, path, params, where);
      continue;
    }
    if (it == params.end())
      throw UsageError(where + "unknown key '" + rig::ClipForMessage(path) + "'");
    if (!kv.second.IsScalar())
      throw UsageError(where + "key '" + path + "': expected a single value");
    Assign(*it->second, kv.second.Scalar(), where + "key '" + path + "'");
  }
}
}  // namespace

namespace {
// yaml-cpp keeps a mapping's repeated keys (the last wins on lookup) and lets
// aliases share nodes: refuse the first, and bound the walk for the second.
void CheckYamlTree(const YAML::Node& node, const std::string& where, long* budget) {
  constexpr long kMaxNodes = 1000000;
  if (++*budget > kMaxNodes)
    throw UsageError(where + "more than " + std::to_string(kMaxNodes) + " values");
  if (node.IsMap()) {
    std::set<std::string> keys;
    for (const auto& kv : node) {
      if (!kv.first.IsScalar()) throw UsageError(where + "a key that is not a single value");
      if (!keys.insert(kv.first.Scalar()).second)
        throw UsageError(where + "key '" + rig::ClipForMessage(kv.first.Scalar()) +
                         "' appears twice");
      CheckYamlTree(kv.second, where, budget);
    }
  } else if (node.IsSequence()) {
    for (const auto& item : node) CheckYamlTree(item, where, budget);
  }
}

// Records where each document of a YAML stream starts (nothing else).
class DocumentStarts : public YAML::EventHandler {
 public:
  std::vector<YAML::Mark> starts;
  void OnDocumentStart(const YAML::Mark& mark) override { starts.push_back(mark); }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
  void OnAlias(const YAML::Mark&, YAML::anchor_t) override {}
  void OnScalar(const YAML::Mark&, const std::string&, YAML::anchor_t,
                const std::string&) override {}
  void OnSequenceStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                       YAML::EmitterStyle::value) override {}
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark&, const std::string&, YAML::anchor_t,
                  YAML::EmitterStyle::value) override {}
  void OnMapEnd() override {}
};

}  // namespace

YAML::Node ParseYaml(const std::string& text, const std::string& where) {
  auto invalid = [&](const YAML::Mark& mark, const std::string& why) {
    return UsageError(where + "not valid YAML (line " + std::to_string(mark.line + 1) + ": " +
                      rig::ClipForMessage(why) + ")");
  };
  YAML::Node root;
  try {
    // One document, counted by the parser itself, which stops at the second
    // (yaml-cpp 0.7's LoadAll never ends on a stray ',': its parser does not
    // advance, so a document starting where the last one did is an error).
    std::istringstream in(text);
    YAML::Parser parser(in);
    DocumentStarts documents;
    while (documents.starts.size() < 2 && parser.HandleNextDocument(documents)) {
    }
    if (documents.starts.size() == 2) {
      if (documents.starts[1].pos == documents.starts[0].pos)
        throw invalid(documents.starts[0], "unreadable text");
      throw UsageError(where + "holds more than one YAML document (a second starts at line " +
                       std::to_string(documents.starts[1].line + 1) + "); expected one");
    }
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw invalid(e.mark, e.msg);
  }
  long budget = 0;
  CheckYamlTree(root, where, &budget);
  return root;
}

YAML::Node LoadYamlFile(const std::string& path, const std::string& where) {
  std::string text;
  try {
    text = rig::ReadInputFile(path, "file");
  } catch (const rig::InputError& e) {
    throw UsageError(where + e.what());
  }
  return ParseYaml(text, where);
}

RunConfig LoadConfig(const std::string& path) {
  const std::string where = "config " + rig::ClipForMessage(path) + ": ";
  const YAML::Node root = LoadYamlFile(path, where);
  RunConfig config;
  ApplyYaml(root, &config, where);
  try {
    config.Check();
  } catch (const UsageError& e) {
    throw UsageError(where + e.what());
  }
  return config;
}

void ApplyYaml(const YAML::Node& root, RunConfig* config, const std::string& where) {
  if (root.IsNull()) return;
  if (!root.IsMap()) throw UsageError(where + "expected a mapping of keys at the top level");
  const std::vector<ConfigParam> params = ConfigParams(config);
  std::map<std::string, const ConfigParam*> by_path;
  for (const ConfigParam& p : params) by_path[p.path] = &p;
  Walk(root, "", by_path, where);
}

void RunConfig::Check() const {
  try {
    fovea.Check();
  } catch (const std::invalid_argument& e) {
    throw UsageError(e.what());
  }
  sim::SimRigConfig r = rig;
  r.seed = seed;
  try {
    r.Check();
  } catch (const sim::SceneError& e) {
    throw UsageError(e.what());
  }
  const auto units = SixInts(hardware.units, "rig.units");
  for (int i = 0; i < 6; ++i) {
    if (units[i] < 1 || units[i] > 99)
      throw UsageError("key 'rig.units': addresses must be 1 to 99");
    for (int j = 0; j < i; ++j)
      if (units[j] == units[i])
        throw UsageError("key 'rig.units': address " + std::to_string(units[i]) + " appears twice");
  }
  for (const int d : SixInts(hardware.directions, "rig.directions"))
    if (d != 1 && d != -1) throw UsageError("key 'rig.directions': each must be 1 or -1");
  if (hardware.type == "hardware") {
    if (hardware.port.empty() && !hardware.emulate_stages)
      throw UsageError(
          "key 'rig.port': a hardware rig needs the stages' serial port (or rig.emulate_stages: "
          "true)");
    if (hardware.left_camera.empty())
      throw UsageError("key 'rig.left_camera': a hardware rig needs a left camera");
    if (hardware.right_camera.empty())
      throw UsageError("key 'rig.right_camera': a hardware rig needs a right camera");
    if (hardware.calibration.empty())
      throw UsageError("key 'rig.calibration': a hardware rig needs a calibration file");
  }
  const double widest = 2 * rig.carriage_max_m;
  if (rig.home_baseline_m > widest)
    throw UsageError("key 'rig.home_baseline_m': " + FormatNumber(rig.home_baseline_m) +
                     " is wider than the carriages allow (2 x rig.carriage_max_m = " +
                     FormatNumber(widest) + ")");
  if (fovea.fixation.baseline_m > widest)
    throw UsageError("key 'foveal.baseline_m': " + FormatNumber(fovea.fixation.baseline_m) +
                     " is wider than the carriages allow (2 x rig.carriage_max_m = " +
                     FormatNumber(widest) + ")");
}

std::vector<std::string> SplitFields(const std::string& text) {
  std::vector<std::string> fields;
  size_t start = 0;
  for (size_t comma; (comma = text.find(',', start)) != std::string::npos; start = comma + 1)
    fields.push_back(text.substr(start, comma - start));
  fields.push_back(text.substr(start));
  return fields;
}

std::array<int, 6> SixInts(const std::string& text, const std::string& key) {
  const std::vector<std::string> fields = SplitFields(text);
  std::array<int, 6> v{};
  bool ok = fields.size() == v.size();
  for (size_t i = 0; ok && i < v.size(); ++i) {
    const std::optional<double> x = ParseNumber(fields[i]);
    ok = x && *x == std::floor(*x) && std::abs(*x) <= 1e6;
    v[i] = ok ? static_cast<int>(*x) : 0;
  }
  if (!ok)
    throw UsageError("key '" + key + "': expected six whole numbers separated by commas, got '" +
                     rig::ClipForMessage(text) + "'");
  return v;
}

std::vector<std::pair<std::string, std::string>> ParamValues(const RunConfig& const_config) {
  RunConfig config = const_config;
  std::vector<std::pair<std::string, std::string>> values;
  for (const ConfigParam& p : ConfigParams(&config)) values.emplace_back(p.path, ValueText(p));
  return values;
}

std::string CanonicalConfig(const RunConfig& config) {
  std::string text;
  for (const auto& [path, value] : ParamValues(config)) text += path + "=" + value + "\n";
  return text;
}

std::string ConfigHash(const RunConfig& config) {
  uint64_t h = 1469598103934665603ull;
  for (const unsigned char ch : CanonicalConfig(config)) {
    h ^= ch;
    h *= 1099511628211ull;
  }
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

std::string ParamText(RunConfig* config, const std::string& path) {
  for (const ConfigParam& p : ConfigParams(config))
    if (p.path == path) return ValueText(p);
  throw UsageError("unknown key '" + path + "'");
}

std::string DumpConfig(const RunConfig& const_config) {
  RunConfig config = const_config;
  std::ostringstream out;
  out << "# FOVEA run configuration: every parameter, with its meaning and range.\n";
  std::string section;
  for (const ConfigParam& p : ConfigParams(&config)) {
    const size_t dot = p.path.find('.');
    const std::string sec = dot == std::string::npos ? "" : p.path.substr(0, dot);
    const std::string key = dot == std::string::npos ? p.path : p.path.substr(dot + 1);
    if (sec != section) {
      out << sec << ":\n";
      section = sec;
    }
    const std::string indent = sec.empty() ? "" : "  ";
    out << indent << key << ": " << YamlValueText(p) << "  # " << p.doc << "; " << Range(p) << "\n";
  }
  return out.str();
}

}  // namespace experiments
