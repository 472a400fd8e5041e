#include "scene_options.h"

#include <cmath>
#include <sstream>

#include "output.h"
#include "scenes/catalog.h"

namespace experiments {

void SceneOptions::Register(CLI::App* cmd, bool with_state) {
  cmd->add_option("--scene", scene, "catalog scene name or path to an MJCF file")
      ->default_str(scenes::kDefaultScene);
  cmd->add_option("--noise", noise_sigma_dn, "sensor read noise, grey levels (0 = off)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--seed", seed, "seed of the sensor noise");
  if (with_state) {
    auto* s = cmd->add_option("--state", state,
                              "stage state: left baseline m, left pan deg, left tilt deg, right "
                              "baseline m, right pan deg, right tilt deg (comma separated)");
    auto* b = cmd->add_option("--baseline", baseline_m,
                              "parallel, level cameras this far apart (metres)");
    s->excludes(b);
  }
}

rig::StageState SceneOptions::TargetState(const rig::StageState& home) const {
  if (baseline_m) return rig::StageState::Parallel(*baseline_m);
  if (state.empty()) return home;
  std::array<double, rig::kNumAxes> v{};
  std::stringstream in(state);
  std::string field;
  int n = 0;
  while (std::getline(in, field, ',')) {
    if (n >= rig::kNumAxes) break;
    try {
      size_t used = 0;
      v[n] = std::stod(field, &used);
      if (used != field.size() || !std::isfinite(v[n])) throw std::invalid_argument(field);
    } catch (const std::exception&) {
      throw UsageError("--state: '" + field + "' is not a number");
    }
    ++n;
  }
  if (n != rig::kNumAxes || in.good())
    throw UsageError("--state needs exactly 6 comma-separated numbers, got '" + state + "'");
  for (int i : {1, 2, 4, 5}) v[i] *= M_PI / 180;  // degrees on the command line
  return rig::StageState::FromArray(v);
}

std::unique_ptr<sim::Simulation> SceneOptions::Load() const {
  sim::SimRigConfig config;
  config.noise.read_noise_sigma_dn = noise_sigma_dn;
  config.seed = seed;
  return scenes::LoadScene(scene.empty() ? scenes::kDefaultScene : scene, config);
}

}  // namespace experiments
