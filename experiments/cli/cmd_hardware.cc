// fovea indexer-emulator: the emulated indexer chain on a pseudo-terminal,
// for trying the serial driver (or any terminal program) without hardware.
#include <signal.h>

#include <chrono>
#include <cstdio>
#include <thread>

#include "commands.h"
#include "experiments/output/output.h"
#include "rig/hardware/indexer_emulator.h"
#include "scene_options.h"

namespace experiments {
namespace {
volatile sig_atomic_t g_quit = 0;
void OnQuit(int) { g_quit = 1; }
}  // namespace

void AddHardwareCommands(CLI::App& app, std::function<int()>* run) {
  auto units = std::make_shared<std::vector<int>>(std::vector<int>{1, 2, 3, 4, 5, 6});
  auto seconds = std::make_shared<double>(0);
  CLI::App* cmd = app.add_subcommand(
      "indexer-emulator", "emulate the chain of indexers on a pseudo-terminal (prints its path)");
  cmd->add_option("--units", *units, "unit addresses on the chain")
      ->delimiter(',')
      ->check(CLI::Range(1, 99));
  cmd->add_option("--seconds", *seconds, "stop after this long (0 = until SIGINT/SIGTERM)")
      ->check(NumberIn(0, 1e7));
  cmd->callback([units, seconds, run] {
    *run = [units, seconds] {
      for (size_t i = 0; i < units->size(); ++i)
        for (size_t j = 0; j < i; ++j)
          if ((*units)[i] == (*units)[j])
            throw UsageError("--units: address " + std::to_string((*units)[i]) + " appears twice");
      rig::IndexerEmulator emulator(*units);
      std::printf("%s\n", emulator.Path().c_str());
      std::fflush(stdout);
      std::fprintf(stderr, "fovea indexer-emulator: %zu units on %s (Ctrl-C to stop)\n",
                   units->size(), emulator.Path().c_str());
      signal(SIGINT, OnQuit);
      signal(SIGTERM, OnQuit);
      const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(*seconds);
      while (!g_quit && (*seconds == 0 || std::chrono::steady_clock::now() < end))
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
      return 0;
    };
  });
}

}  // namespace experiments
