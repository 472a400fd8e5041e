// Command-line options shared by the subcommands that load a scene.
#pragma once

#include <CLI/CLI.hpp>
#include <memory>
#include <optional>
#include <string>

#include "experiments/config/config.h"
#include "experiments/output/output.h"
#include "rig/types.h"
#include "sim/simulation.h"

namespace experiments {

/// --scene, --noise and --seed (and --state / --baseline) as typed; each is
/// checked against the parameter table (or its own range) before any work.
struct SceneOptions {
  std::string scene;     ///< catalog name or path; empty = the config's
  std::string noise;     ///< rig.noise_sigma_dn; empty = the command's default
  std::string seed;      ///< seed; empty = the config's
  std::string state;     ///< "LB,LPAN,LTILT,RB,RPAN,RTILT" in metres and degrees
  std::string baseline;  ///< parallel, level cameras this far apart, metres

  /// Registers --scene, --noise and --seed (and --state/--baseline if
  /// `with_state`) on `cmd`.
  void Register(CLI::App* cmd, bool with_state);
  /// Sets the scene, noise and seed given on `config` through the parameter
  /// table; UsageError naming the flag.
  void ApplyTo(RunConfig* config) const;
  /// The stage state asked for (--state or --baseline), nullopt for none;
  /// throws UsageError for a malformed --state.
  std::optional<rig::StageState> TargetState() const;
};

/// Loads the scene of `config` (the default scene if it names none) with its
/// simulated rig: image size, lens, limits, noise and the one seed.
std::unique_ptr<sim::Simulation> LoadSceneOf(const RunConfig& config);

/// A CLI11 check for a flag that is not a parameter: ParseNumber, within
/// [lo, hi], whole if `whole`.
CLI::Validator NumberIn(double lo, double hi, bool whole = false);

/// Registers --force: replace an earlier result of fovea at the output.
void AddForceFlag(CLI::App* cmd, bool* force);

/// The ExistingOutput policy a --force flag asks for.
ExistingOutput ExistingPolicy(bool force);

}  // namespace experiments
