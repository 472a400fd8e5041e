#include "scene_options.h"

#include <cmath>

#include "experiments/output/output.h"
#include "scenes/catalog.h"

namespace experiments {

void SceneOptions::Register(CLI::App* cmd, bool with_state) {
  cmd->add_option("--scene", scene, "catalog scene name or path to an MJCF file")
      ->default_str(scenes::kDefaultScene);
  cmd->add_option("--noise", noise, "sensor read noise, grey levels (0 = off; rig.noise_sigma_dn)");
  cmd->add_option("--seed", seed, "seed of the sensor noise (and of every draw)");
  if (with_state) {
    auto* s = cmd->add_option("--state", state,
                              "stage state: left baseline m, left pan deg, left tilt deg, right "
                              "baseline m, right pan deg, right tilt deg (comma separated)");
    auto* b =
        cmd->add_option("--baseline", baseline, "parallel, level cameras this far apart (metres)")
            ->check(NumberIn(1e-4, 10));
    s->excludes(b);
  }
}

void SceneOptions::ApplyTo(RunConfig* config) const {
  if (!scene.empty()) SetParamFromFlag(config, "--scene", "scene", scene);
  if (!noise.empty()) SetParamFromFlag(config, "--noise", "rig.noise_sigma_dn", noise);
  if (!seed.empty()) SetParamFromFlag(config, "--seed", "seed", seed);
}

std::optional<rig::StageState> SceneOptions::TargetState() const {
  if (!baseline.empty()) return rig::StageState::Parallel(*ParseNumber(baseline));
  if (state.empty()) return std::nullopt;
  const std::vector<std::string> fields = SplitFields(state);
  if (fields.size() != rig::kNumAxes)
    throw UsageError("--state needs exactly 6 comma-separated numbers, got '" +
                     rig::ClipForMessage(state) + "'");
  std::array<double, rig::kNumAxes> v{};
  for (int i = 0; i < rig::kNumAxes; ++i) {
    const std::optional<double> x = ParseNumber(fields[i]);
    if (!x) throw UsageError("--state: '" + rig::ClipForMessage(fields[i]) + "' is not a number");
    v[i] = *x;
  }
  for (int i : {1, 2, 4, 5}) v[i] *= M_PI / 180;  // degrees on the command line
  return rig::StageState::FromArray(v);
}

std::unique_ptr<sim::Simulation> LoadSceneOf(const RunConfig& config) {
  sim::SimRigConfig rig = config.rig;
  rig.seed = config.seed;
  return scenes::LoadScene(config.scene.empty() ? scenes::kDefaultScene : config.scene, rig);
}

namespace {
std::string Shown(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.10g", v);
  return text;
}
}  // namespace

CLI::Validator NumberIn(double lo, double hi, bool whole) {
  return CLI::Validator(
      [lo, hi, whole](std::string& text) -> std::string {
        const std::string shown = "'" + rig::ClipForMessage(text) + "'";
        const std::optional<double> v = ParseNumber(text);
        if (!v) return "expected a number, got " + shown;
        if (whole && *v != std::floor(*v)) return "expected a whole number, got " + shown;
        if (*v < lo || *v > hi)
          return shown + " is out of range [" + Shown(lo) + ", " + Shown(hi) + "]";
        return "";
      },
      "NUMBER in [" + Shown(lo) + ", " + Shown(hi) + "]");
}

void AddForceFlag(CLI::App* cmd, bool* force) {
  cmd->add_flag("--force", *force,
                "replace an earlier result of fovea at --out (never anything else)");
}

ExistingOutput ExistingPolicy(bool force) {
  return force ? ExistingOutput::kReplace : ExistingOutput::kRefuse;
}

}  // namespace experiments
