// fovea: the testbed's one command-line program.
#include <cstdio>
#include <exception>

#include <opencv2/core/utils/logger.hpp>

#include "commands.h"
#include "output.h"
#include "rig/types.h"
#include "sim/config.h"

int main(int argc, char** argv) {
  // Errors reach the user as one line of ours, not as OpenCV's own log.
  cv::utils::logging::setLogLevel(cv::utils::logging::LOG_LEVEL_SILENT);
  CLI::App app{"fovea: a foveated vergent active stereo testbed (Klarquist & Bovik 1998)"};
  app.require_subcommand(1);
  std::function<int()> run;
  experiments::AddRenderCommand(app, &run);
  experiments::AddBenchCommand(app, &run);
  experiments::AddCatalogCommands(app, &run);
  experiments::AddIdrCommand(app, &run);
  experiments::AddFixateCommand(app, &run);
  experiments::AddRunCommand(app, &run);
  experiments::AddSweepCommands(app, &run);
  experiments::AddHardwareCommands(app, &run);
  experiments::AddCalibrateCommands(app, &run);
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::fprintf(stderr, "fovea: error: %s\n", e.what());
    return 2;
  }
  try {
    return run ? run() : 2;
  } catch (const experiments::UsageError& e) {
    std::fprintf(stderr, "fovea: error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fovea: error: %s\n", e.what());
    return 1;
  }
}
