// fovea sweep: a grid of runs from a sweep file, in parallel child processes,
// restartable and shardable; fovea collect: merge shards and write the CSV;
// fovea report: an HTML page for a run or a sweep.
#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <thread>

#include "commands.h"
#include "experiments/config/sweep.h"
#include "experiments/output/compare.h"
#include "experiments/output/output.h"
#include "experiments/output/report.h"
#include "experiments/output/run_folder.h"

namespace experiments {
namespace fs = std::filesystem;
namespace {

using Clock = std::chrono::steady_clock;

std::string SelfExe() {
  std::error_code ec;
  const fs::path p = fs::read_symlink("/proc/self/exe", ec);
  if (ec)
    throw std::runtime_error("cannot find the fovea program itself (/proc/self/exe): " +
                             ec.message());
  return p.string();
}

std::string Duration(double s) {
  char buf[32];
  const long t = static_cast<long>(s + 0.5);
  if (t >= 3600)
    std::snprintf(buf, sizeof buf, "%ldh%02ldm", t / 3600, (t / 60) % 60);
  else if (t >= 60)
    std::snprintf(buf, sizeof buf, "%ldm%02lds", t / 60, t % 60);
  else
    std::snprintf(buf, sizeof buf, "%lds", t);
  return buf;
}

// Runs done / total with an estimate of the time left: a bar redrawn in
// place on a terminal, a plain line per finished run otherwise.
class Progress {
 public:
  Progress(int total, int already_done)
      : total_(total), done_(already_done), start_(Clock::now()), tty_(isatty(2)) {}
  void Finished(const std::string& id, bool ok, double seconds) {
    ++done_;
    ++this_session_;
    const double elapsed = std::chrono::duration<double>(Clock::now() - start_).count();
    const double left = elapsed / this_session_ * (total_ - done_);
    if (tty_) {
      const int width = 30, filled = total_ ? width * done_ / total_ : width;
      std::fprintf(stderr, "\r[%s%s] %d/%d runs, %s elapsed, ~%s left%s",
                   std::string(filled, '#').c_str(), std::string(width - filled, '.').c_str(),
                   done_, total_, Duration(elapsed).c_str(), Duration(left).c_str(),
                   ok ? "   " : " (a run failed)");
      if (done_ == total_) std::fputc('\n', stderr);
    } else {
      std::fprintf(stderr, "fovea sweep: %d/%d runs done (%s %s in %.1f s), about %s left\n", done_,
                   total_, id.c_str(), ok ? "finished" : "FAILED", seconds, Duration(left).c_str());
    }
    std::fflush(stderr);
  }

 private:
  int total_, done_, this_session_ = 0;
  Clock::time_point start_;
  bool tty_;
};

volatile sig_atomic_t g_stop = 0;
void OnSignal(int sig) { g_stop = sig; }

// Starts `fovea run --config CONFIG --out OUT` with its output in LOG; the
// child dies with the sweep (PR_SET_PDEATHSIG), so a killed sweep leaves
// no runs behind, only staging folders that the next start clears.
pid_t Spawn(const std::string& exe, const std::string& config, const std::string& out,
            const std::string& log) {
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("cannot start a run: fork failed");
  if (pid == 0) {
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (getppid() != parent) _exit(127);
    const int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) {
      dup2(fd, 1);
      dup2(fd, 2);
      close(fd);
    }
    execl(exe.c_str(), exe.c_str(), "run", "--config", config.c_str(), "--out", out.c_str(),
          static_cast<char*>(nullptr));
    _exit(127);
  }
  return pid;
}

void RemoveStaging(const std::string& runs_dir, const std::string& id) {
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(runs_dir, ec))
    if (e.path().filename().string().rfind("." + id + ".partial-", 0) == 0)
      fs::remove_all(e.path(), ec);
}

struct SweepArgs {
  std::string file, out, shard;
  int jobs = -1;
  bool no_report = false, resume = false;
};

// Holds the sweep folder's locks while a sweep runs in it, so that two
// sweeps never run the same runs: a whole sweep takes `.sweep.lock`
// exclusively; a shard takes it shared (shards of one sweep may share a
// folder) and its own `.shard-I-of-N.lock` exclusively. The lock files hold
// the pid. flock: released when the process ends, however it ends.
class SweepLock {
 public:
  SweepLock(const std::string& dir, int shard_i, int shard_n) {
    const bool whole = shard_n == 1;
    Take(dir + "/.sweep.lock", whole ? LOCK_EX : LOCK_SH, dir);
    if (!whole)
      Take(dir + "/.shard-" + std::to_string(shard_i) + "-of-" + std::to_string(shard_n) + ".lock",
           LOCK_EX, dir);
  }
  ~SweepLock() {
    for (const int fd : fds_) close(fd);
  }
  SweepLock(const SweepLock&) = delete;
  SweepLock& operator=(const SweepLock&) = delete;

 private:
  void Take(const std::string& path, int mode, const std::string& dir) {
    const int fd = open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0)
      throw std::runtime_error("cannot lock the sweep folder '" + rig::ClipForMessage(dir) + "'");
    fds_.push_back(fd);
    if (flock(fd, mode | LOCK_NB) != 0) {
      char pid[32] = "";
      const ssize_t n = pread(fd, pid, sizeof pid - 1, 0);
      if (n > 0) pid[n] = '\0';
      throw std::runtime_error("'" + rig::ClipForMessage(dir) +
                               "' is in use by another fovea sweep" +
                               (n > 0 ? std::string(" (pid ") + pid + ")" : std::string()) +
                               "; wait for it to end, or choose another --out");
    }
    if (mode == LOCK_EX) {
      const std::string me = std::to_string(getpid());
      if (ftruncate(fd, 0) != 0 || pwrite(fd, me.data(), me.size(), 0) < 0) {
        // The pid is only for the message; the lock holds without it.
      }
    }
  }
  std::vector<int> fds_;
};

// The output-folder policy for a sweep: a new or empty folder, or, with
// --resume, one holding this very sweep.
void CheckSweepFolder(const std::string& dir, const std::string& grid_text, bool resume) {
  std::error_code ec;
  if (!fs::exists(fs::symlink_status(dir, ec)) || (fs::is_directory(dir) && fs::is_empty(dir, ec)))
    return;
  const std::string at = "--out: '" + rig::ClipForMessage(dir) + "'";
  if (!fs::is_directory(fs::symlink_status(dir, ec)))
    throw UsageError(at + " exists and is not a folder");
  if (!fs::exists(dir + "/grid.json"))
    throw UsageError(at + " exists and is not a sweep folder (no grid.json); choose another --out");
  if (ReadFile(dir + "/grid.json") != grid_text)
    throw UsageError(at + " holds a different sweep (its grid.json differs); choose another --out");
  if (!resume) throw UsageError(at + " holds this sweep already; pass --resume to continue it");
}

// A rough duration of one run, seconds on one core of the 2-core
// development machine: scene load and reference view, then per fixation
// (measured: 25 fixations at 640x480 about 15 s, 3 at 320x240 about 7 s).
double RoughRunSeconds(const RunConfig& c) {
  const double pixels = double(c.rig.width_px) * c.rig.height_px / (640.0 * 480.0);
  if (c.method == "static_sgbm") return 5 + 2 * pixels;
  return 5 + pixels * (2 + 0.35 * c.fovea.fixations);
}

// Writes results.csv (and report.html) when every run has a result;
// returns the ids without one.
std::vector<std::string> Finish(const std::string& dir, const nlohmann::json& grid, bool report) {
  std::vector<std::string> missing;
  const std::string csv = ResultsCsv(dir, grid, &missing);
  if (missing.empty()) {
    WriteTextAtomic(dir + "/results.csv", csv);
    if (report) WriteReport(dir);
  }
  return missing;
}

// Runs `pending` as `jobs` parallel `fovea run` processes into DIR/runs/,
// with a progress display; on SIGINT/SIGTERM stops them all (g_stop set).
// Returns the ids of the runs that failed.
std::vector<std::string> RunPending(const std::string& dir, const std::string& exe,
                                    const std::vector<const SweepRun*>& pending, int jobs, int done,
                                    int total) {
  struct sigaction sa {};
  sa.sa_handler = OnSignal;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  Progress progress(total, done);
  std::map<pid_t, std::pair<const SweepRun*, Clock::time_point>> running;
  std::vector<std::string> failed;
  size_t next = 0;
  while ((next < pending.size() || !running.empty()) && !g_stop) {
    while (next < pending.size() && static_cast<int>(running.size()) < jobs && !g_stop) {
      const SweepRun& r = *pending[next++];
      const std::string config = dir + "/configs/" + r.id + ".yaml";
      WriteTextAtomic(config, DumpConfig(r.config));
      RemoveStaging(dir + "/runs", r.id);
      running[Spawn(exe, config, dir + "/runs/" + r.id, dir + "/logs/" + r.id + ".log")] = {
          &r, Clock::now()};
    }
    int status = 0;
    const pid_t pid = waitpid(-1, &status, 0);
    if (pid < 0) continue;  // interrupted by a signal
    const auto it = running.find(pid);
    if (it == running.end()) continue;
    const SweepRun& r = *it->second.first;
    const double s = std::chrono::duration<double>(Clock::now() - it->second.second).count();
    running.erase(it);
    const bool ok = WIFEXITED(status) && WEXITSTATUS(status) == 0 &&
                    fs::exists(dir + "/runs/" + r.id + "/" + run_folder::kSummary);
    if (!ok) failed.push_back(r.id);
    progress.Finished(r.id, ok, s);
  }
  if (g_stop) {
    for (const auto& [pid, run] : running) kill(pid, SIGTERM);
    for (const auto& [pid, run] : running) waitpid(pid, nullptr, 0);
  }
  return failed;
}

int RunSweep(const SweepArgs& args) {
  const Sweep sweep = LoadSweep(args.file);
  const auto [shard_i, shard_n] =
      args.shard.empty() ? std::pair<int, int>{1, 1} : ParseShard(args.shard);
  int jobs = args.jobs >= 0 ? args.jobs : sweep.jobs;
  if (jobs == 0) jobs = std::max(1u, std::thread::hardware_concurrency());
  const std::string dir = NormalizeOutputPath(
      args.out.empty() ? "out/sweeps/" + fs::path(args.file).stem().string() : args.out, "--out");
  const nlohmann::json grid = GridJson(sweep);
  const std::string grid_text = grid.dump(1) + "\n";
  CheckSweepFolder(dir, grid_text, args.resume);
  EnsureDirectory(dir);
  const SweepLock lock(dir, shard_i, shard_n);
  EnsureDirectory(dir + "/runs");
  EnsureDirectory(dir + "/configs");
  EnsureDirectory(dir + "/logs");
  WriteTextAtomic(dir + "/grid.json", grid_text);
  WriteTextAtomic(dir + "/sweep.yaml", ReadFile(args.file));

  std::vector<const SweepRun*> mine, pending;
  for (size_t i = 0; i < sweep.runs.size(); ++i)
    if (static_cast<int>(i % shard_n) == shard_i - 1) mine.push_back(&sweep.runs[i]);
  double rough_s = 0;
  for (const SweepRun* r : mine)
    if (!fs::exists(dir + "/runs/" + r->id + "/summary.json")) {
      pending.push_back(r);
      rough_s += RoughRunSeconds(r->config);
    }
  std::fprintf(
      stderr,
      "fovea sweep: %zu runs%s, %zu already done, %zu to run on %d parallel jobs (roughly %s) -> "
      "%s\n",
      mine.size(),
      shard_n > 1 ? (" in shard " + args.shard + " of " + std::to_string(sweep.runs.size())).c_str()
                  : "",
      mine.size() - pending.size(), pending.size(), jobs,
      Duration(rough_s / std::max(1, std::min<int>(jobs, static_cast<int>(pending.size()))))
          .c_str(),
      dir.c_str());

  const std::vector<std::string> failed =
      RunPending(dir, SelfExe(), pending, jobs, static_cast<int>(mine.size() - pending.size()),
                 static_cast<int>(mine.size()));
  if (g_stop) {
    std::fprintf(stderr,
                 "\nfovea sweep: stopped by signal %d; the same command with --resume resumes it\n",
                 int(g_stop));
    return 130;
  }
  for (const std::string& id : failed)
    std::fprintf(stderr, "fovea sweep: run %s failed; see %s/logs/%s.log\n", id.c_str(),
                 dir.c_str(), id.c_str());
  const std::vector<std::string> missing = Finish(dir, grid, !args.no_report);
  if (missing.empty())
    std::fprintf(stderr, "fovea sweep: %zu runs -> %s/results.csv%s\n", sweep.runs.size(),
                 dir.c_str(), args.no_report ? "" : (", " + dir + "/report.html").c_str());
  else if (failed.empty())
    std::fprintf(stderr,
                 "fovea sweep: shard %s done; %zu runs of the sweep are in other shards (merge "
                 "with fovea collect "
                 "OUT SHARD_FOLDER... when all are done)\n",
                 args.shard.c_str(), missing.size());
  return failed.empty() ? 0 : 1;
}

void CopyRun(const fs::path& from, const fs::path& runs_dir, const std::string& id) {
  const fs::path tmp = runs_dir / ("." + id + ".partial-collect-" + std::to_string(getpid()));
  std::error_code ec;
  fs::remove_all(tmp, ec);
  fs::copy(from, tmp, fs::copy_options::recursive, ec);
  if (ec) throw std::runtime_error("cannot copy '" + from.string() + "': " + ec.message());
  fs::rename(tmp, runs_dir / id, ec);
  if (ec)
    throw std::runtime_error("cannot write '" + (runs_dir / id).string() + "': " + ec.message());
}

// Whether `dir` is an existing folder whose every entry is one of `shards`.
bool OnlyShards(const std::string& dir, const std::vector<std::string>& shards) {
  std::error_code ec;
  if (!fs::is_directory(fs::symlink_status(dir, ec))) return false;
  bool any = false;
  for (const fs::directory_entry& e : fs::directory_iterator(dir, ec)) {
    any = true;
    const bool shard = std::any_of(shards.begin(), shards.end(), [&](const std::string& s) {
      std::error_code eq;
      return fs::equivalent(e.path(), s, eq);
    });
    if (!shard) return false;
  }
  return any && !ec;
}

int Collect(const std::string& dir_arg, const std::vector<std::string>& shards, bool report) {
  const std::string dir = NormalizeOutputPath(dir_arg, "collect DIR");
  for (const std::string& s : shards)
    if (!fs::exists(s + "/grid.json"))
      throw UsageError("'" + rig::ClipForMessage(s) + "' is not a sweep folder (no grid.json)");
  for (const std::string& s : shards)
    if (ReadFile(s + "/grid.json") != ReadFile(shards[0] + "/grid.json"))
      throw UsageError("'" + rig::ClipForMessage(s) + "' holds a different sweep than '" +
                       rig::ClipForMessage(shards[0]) + "' (grid.json differs)");
  const bool fresh = !fs::exists(dir + "/grid.json");
  if (fresh && shards.empty())
    throw UsageError("'" + rig::ClipForMessage(dir) + "' is not a sweep folder (no grid.json)");
  // The grid, read and checked before anything is written: the shards'
  // (one text, checked above) where DIR has none yet, else DIR's own (each
  // shard's text is compared with it below).
  const nlohmann::json grid = ReadGridJson(fresh ? shards[0] : dir);
  if (fresh) {
    // Merging into a new or empty folder only, or one that holds nothing but
    // the shards being merged (sweep.sbatch writes them as DIR/shard-I):
    // never into one that holds something else.
    if (!OnlyShards(dir, shards)) CheckOutputTarget(dir, "collect DIR", ExistingOutput::kRefuse);
    EnsureDirectory(dir + "/runs");
    WriteTextAtomic(dir + "/grid.json", ReadFile(shards[0] + "/grid.json"));
    if (fs::exists(shards[0] + "/sweep.yaml"))
      WriteTextAtomic(dir + "/sweep.yaml", ReadFile(shards[0] + "/sweep.yaml"));
  }
  const std::string grid_text = ReadFile(dir + "/grid.json");
  EnsureDirectory(dir + "/runs");
  int copied = 0;
  for (const std::string& s : shards) {
    if (fs::equivalent(s, dir)) continue;
    if (ReadFile(s + "/grid.json") != grid_text)
      throw UsageError("'" + s + "' holds a different sweep than '" + dir +
                       "' (grid.json differs)");
    for (const auto& run : grid.at("runs")) {
      const std::string id = run.at("id").get<std::string>();
      if (fs::exists(s + "/runs/" + id + "/summary.json") &&
          !fs::exists(dir + "/runs/" + id + "/summary.json")) {
        CopyRun(s + "/runs/" + id, dir + "/runs", id);
        ++copied;
      }
    }
  }
  const std::vector<std::string> missing = Finish(dir, grid, report);
  if (!missing.empty()) {
    std::fprintf(
        stderr,
        "fovea collect: %zu of %zu runs have no result yet (first: %s); no results.csv written\n",
        missing.size(), grid.at("runs").size(), missing[0].c_str());
    return 1;
  }
  std::fprintf(stderr, "fovea collect: %d runs merged, %zu runs -> %s/results.csv\n", copied,
               grid.at("runs").size(), dir.c_str());
  return 0;
}

}  // namespace

void AddSweepCommands(CLI::App& app, std::function<int()>* run) {
  auto args = std::make_shared<SweepArgs>();
  CLI::App* cmd = app.add_subcommand(
      "sweep", "a grid of runs from a sweep file, in parallel, restartable, shardable");
  cmd->add_option("file", args->file, "sweep file: base config and axes (see experiments/sweeps/)")
      ->required();
  cmd->add_option("--out", args->out, "sweep folder (default out/sweeps/<file name>)");
  cmd->add_option("--jobs", args->jobs,
                  "parallel runs (0 = every core; default: the file's jobs, else every core)")
      ->check(CLI::Range(0, 1024));
  cmd->add_option("--shard", args->shard, "I/N: run only the I-th of N slices of the grid");
  cmd->add_flag("--no-report", args->no_report, "skip report.html");
  cmd->add_flag("--resume", args->resume,
                "continue the same sweep in --out: skip finished runs, redo half-built ones");
  cmd->callback([args, run] { *run = [args] { return RunSweep(*args); }; });

  auto dir = std::make_shared<std::string>();
  auto shards = std::make_shared<std::vector<std::string>>();
  auto no_report = std::make_shared<bool>(false);
  CLI::App* col =
      app.add_subcommand("collect", "merge sweep shards into DIR and write DIR/results.csv");
  col->add_option("dir", *dir, "sweep folder to write")->required();
  col->add_option("shards", *shards,
                  "shard folders to merge into it (none: DIR holds every shard's runs)");
  col->add_flag("--no-report", *no_report, "skip report.html");
  col->callback([dir, shards, no_report, run] {
    *run = [dir, shards, no_report] { return Collect(*dir, *shards, !*no_report); };
  });

  auto report_dir = std::make_shared<std::string>();
  CLI::App* rep =
      app.add_subcommand("report", "write DIR/report.html for a run folder or a sweep folder");
  rep->add_option("dir", *report_dir, "run or sweep folder")->required();
  rep->callback([report_dir, run] {
    *run = [report_dir] {
      const std::string page = WriteReport(*report_dir);
      std::fprintf(stderr, "fovea report: %s\n", page.c_str());
      return 0;
    };
  });

  struct CompareArgs {
    std::string base, variant, method = "fovea";
    bool json = false;
  };
  auto cmp_args = std::make_shared<CompareArgs>();
  CLI::App* cmp = app.add_subcommand(
      "compare",
      "pair two sweeps' runs by scene and seed: each figure's paired change and issue 19's lines");
  cmp->add_option("base", cmp_args->base, "sweep folder before the change")->required();
  cmp->add_option("variant", cmp_args->variant, "sweep folder after it")->required();
  cmp->add_option("--method", cmp_args->method,
                  "the runs to pair: fovea, or a baseline (static_sgbm, deterministic)")
      ->capture_default_str();
  cmp->add_flag("--json", cmp_args->json, "one JSON object on stdout");
  cmp->callback([cmp_args, run] {
    *run = [cmp_args] {
      const CompareArgs& a = *cmp_args;
      int base_unfinished = 0, variant_unfinished = 0;
      Comparison c = Compare(SweepSummaries(a.base, &base_unfinished),
                             SweepSummaries(a.variant, &variant_unfinished), a.method);
      c.base_unfinished = base_unfinished;
      c.variant_unfinished = variant_unfinished;
      if (c.pairs == 0)
        throw UsageError("no " + rig::ClipForMessage(a.method) +
                         " runs pair up by scene and seed between '" + rig::ClipForMessage(a.base) +
                         "' and '" + rig::ClipForMessage(a.variant) + "'");
      const std::string out = a.json ? ComparisonJson(c).dump(1) + "\n" : ComparisonText(c);
      std::fwrite(out.data(), 1, out.size(), stdout);
      return 0;
    };
  });
}

}  // namespace experiments
