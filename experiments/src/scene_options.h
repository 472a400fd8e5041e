// Command-line options shared by the subcommands that load a scene.
#pragma once

#include <CLI/CLI.hpp>
#include <memory>
#include <optional>
#include <string>

#include "rig/types.h"
#include "sim/simulation.h"

namespace experiments {

struct SceneOptions {
  std::string scene;  ///< catalog name or path; empty = the default scene
  double noise_sigma_dn = 0;
  uint64_t seed = 0;
  std::string state;  ///< "LB,LPAN,LTILT,RB,RPAN,RTILT" in metres and degrees
  std::optional<double> baseline_m;

  /// Registers --scene, --noise and --seed (and --state/--baseline if
  /// `with_state`) on `cmd`.
  void Register(CLI::App* cmd, bool with_state);
  /// The stage state asked for, or `home` if none; throws UsageError for a
  /// malformed --state.
  rig::StageState TargetState(const rig::StageState& home) const;
  std::unique_ptr<sim::Simulation> Load() const;
};

}  // namespace experiments
