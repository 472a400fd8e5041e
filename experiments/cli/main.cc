// fovea: the testbed's one command-line program.
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <new>
#include <opencv2/core/utils/logger.hpp>
#include <string>

#ifdef __GLIBC__
#include <malloc.h>
#endif

#include "commands.h"
#include "experiments/output/output.h"

namespace {

// Longest error line printed: messages echo at most rig::kMaxEchoChars of any
// input, and this catches what a library put in its own text.
constexpr size_t kMaxErrorChars = 300;

// One line on stderr, whatever the message held.
void PrintError(const std::string& message) {
  std::string line = "fovea: error: " + message;
  for (char& c : line)
    if (c == '\n' || c == '\r' || c == '\t') c = ' ';
  while (!line.empty() && line.back() == ' ') line.pop_back();
  if (line.size() > kMaxErrorChars) line = line.substr(0, kMaxErrorChars - 3) + "...";
  std::fprintf(stderr, "%s\n", line.c_str());
}

// Exit codes: 2 for what the user typed or wrote (flags, configs, sweep and
// scene files), 1 for failures while working (devices, files, the rig).
int Report(std::exception_ptr error) {
  try {
    std::rethrow_exception(error);
  } catch (const CLI::ParseError& e) {
    PrintError(e.what());
    return 2;
  } catch (const rig::InputError& e) {  // UsageError, sim::SceneError
    PrintError(e.what());
    return 2;
  } catch (const std::bad_alloc&) {
    PrintError("out of memory");
    return 1;
  } catch (const std::exception& e) {
    PrintError(e.what());
    return 1;
  } catch (...) {
    PrintError("an unknown error");
    return 1;
  }
}

}  // namespace

int main(int argc, char** argv) {
#ifdef __GLIBC__
  // A run allocates and frees image-sized buffers (renders, cost volumes,
  // the scorer's per-pixel errors) every fixation. With glibc's defaults
  // each comes fresh from the kernel, zeroed page by page: on the
  // development VM, keeping them halved the per-fixation scoring time. Kept
  // in the heap instead (buffers up to 32 MB, the most glibc allows, and
  // no trimming below 1 GB), the run's peak memory is simply kept.
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
#endif
  // An exception escaping where it cannot be caught (a destructor, a
  // thread) still ends in one line and exit 1, not an abort.
  std::set_terminate([] {
    if (const std::exception_ptr e = std::current_exception())
      Report(e);
    else
      PrintError("internal error (std::terminate)");
    std::_Exit(1);
  });
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
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    return Report(std::current_exception());
  } catch (...) {
    return Report(std::current_exception());
  }
  try {
    return run ? run() : 2;
  } catch (...) {
    std::fflush(stdout);
    return Report(std::current_exception());
  }
}
