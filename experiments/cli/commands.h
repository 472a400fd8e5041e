// The fovea command line: one function per subcommand, registered on CLI11.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>

namespace experiments {

/// Each registers its subcommand on `app` and sets `*run` to the action to
/// perform when that subcommand is chosen.
void AddRenderCommand(CLI::App& app, std::function<int()>* run);
void AddBenchCommand(CLI::App& app, std::function<int()>* run);
void AddCatalogCommands(CLI::App& app, std::function<int()>* run);
void AddIdrCommand(CLI::App& app, std::function<int()>* run);
void AddFixateCommand(CLI::App& app, std::function<int()>* run);
void AddRunCommand(CLI::App& app, std::function<int()>* run);
void AddSweepCommands(CLI::App& app, std::function<int()>* run);
void AddHardwareCommands(CLI::App& app, std::function<int()>* run);
void AddCalibrateCommands(CLI::App& app, std::function<int()>* run);

}  // namespace experiments
