// The serial stage driver against the indexer emulator on a pseudo-terminal:
// every command, every injected fault, and a long random sequence of moves.
#include "rig/hardware/indexer.h"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <random>

#include "rig/hardware/indexer_emulator.h"

namespace {

using Clock = std::chrono::steady_clock;
using rig::Axis;
using rig::IndexerCommand;
using rig::IndexerFault;

const std::vector<int> kUnits = {1, 2, 3, 4, 5, 6};

// Baselines 400 steps/mm, pan/tilt 6400 steps/degree (the TAVT's), fast
// profiles so that the tests move quickly; the right pan turns the other way.
rig::IndexerOptions Options(std::chrono::milliseconds timeout = std::chrono::milliseconds(300)) {
  rig::IndexerOptions o;
  const double rad = 6400 * 180 / M_PI;
  for (int i = 0; i < rig::kNumAxes; ++i) {
    rig::IndexerAxis& a = o.axes[i];
    a.unit = i + 1;
    const bool baseline = i == 0 || i == 3;
    a.steps_per_unit = baseline ? 400000 : rad;
    a.velocity = baseline ? 5 : 20;
    a.acceleration = baseline ? 500 : 2000;
    a.min = baseline ? (i == 0 ? -0.3 : 0.0005) : -0.5;
    a.max = baseline ? (i == 0 ? -0.0005 : 0.3) : 0.5;
  }
  o.axes[4].sign = -1;
  o.reply_timeout = timeout;
  o.poll_interval = std::chrono::milliseconds(2);
  o.move_timeout_margin_s = 1;
  return o;
}

rig::StageState Pose(double lb, double lp, double lt, double rb, double rp, double rt) {
  return rig::StageState::FromArray({lb, lp, lt, rb, rp, rt});
}

double Seconds(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

}  // namespace

TEST_CASE("indexer driver: every command against the emulator", "[indexer]") {
  rig::IndexerEmulator emulator(kUnits);
  rig::IndexerDriver driver(rig::OpenSerialPort(emulator.Path(), 9600), Options());
  CHECK(driver.Send(IndexerCommand::kAcceleration, 2, "10000000").empty());
  CHECK(driver.Send(IndexerCommand::kVelocity, 2, "1000000").empty());
  CHECK(driver.Send(IndexerCommand::kIncrementalMode, 2).empty());
  CHECK(driver.Send(IndexerCommand::kDistance, 2, "250").empty());
  CHECK(driver.Send(IndexerCommand::kGo, 2).empty());
  CHECK(driver.Send(IndexerCommand::kPositionReport, 2).rfind("*TPC+", 0) == 0);
  const std::string status = driver.Send(IndexerCommand::kStatus, 2);
  CHECK(status.rfind("*TAS", 0) == 0);
  CHECK(status.size() == 4 + 32 + 7);
  while (emulator.Moving(2)) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  CHECK(driver.Send(IndexerCommand::kPositionReport, 2) == "*TPC+250");
  CHECK(driver.Send(IndexerCommand::kGo, 2).empty());  // incremental: another 250
  while (emulator.Moving(2)) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  CHECK(emulator.Position(2) == 500);
  CHECK(driver.Send(IndexerCommand::kAbsoluteMode, 2).empty());
  CHECK(driver.Send(IndexerCommand::kDistance, 2, "-40000").empty());
  CHECK(driver.Send(IndexerCommand::kGo, 2).empty());
  std::this_thread::sleep_for(std::chrono::milliseconds(5));
  CHECK(driver.Status(Axis::kLeftPan)[0] == '1');  // moving
  CHECK(driver.Send(IndexerCommand::kStop, 2).empty());
  const long stopped = emulator.Position(2);
  CHECK(stopped > -40000);
  CHECK(stopped < 500);
  CHECK_FALSE(emulator.Moving(2));
  CHECK(driver.Send(IndexerCommand::kKill, 3).empty());
  CHECK(emulator.Kills(3) == 1);
  // A rejected command is an error naming it, and kills every axis.
  CHECK_THROWS_WITH(driver.Send(IndexerCommand::kDistance, 1, "1.5"),
                    Catch::Contains("rejected") && Catch::Contains("1_D1.5"));
  for (const int u : kUnits) CHECK(emulator.Kills(u) >= 1);
}

TEST_CASE("indexer driver: moves, read-back and soft limits", "[indexer]") {
  rig::IndexerEmulator emulator(kUnits);
  rig::IndexerDriver driver(rig::OpenSerialPort(emulator.Path(), 115200), Options());
  const rig::StageState target = Pose(-0.06, 0.05, -0.02, 0.06, -0.05, 0.01);
  const rig::MoveResult r = driver.MoveTo(target);
  const auto want = target.ToArray(), got = r.reached.ToArray();
  for (int i = 0; i < rig::kNumAxes; ++i) CHECK(got[i] == Approx(want[i]).margin(1e-5));
  CHECK(emulator.Position(1) == -24000);                                 // -0.06 m x 400000
  CHECK(emulator.Position(5) == std::lround(0.05 * 6400 * 180 / M_PI));  // sign -1 on the right pan
  // Outside a soft limit: refused before a byte is sent.
  const size_t sent = emulator.Received().size();
  CHECK_THROWS_WITH(driver.MoveTo(Pose(-0.06, 0.7, 0, 0.06, 0, 0)),
                    Catch::Contains("soft limits") && Catch::Contains("left pan"));
  CHECK(emulator.Received().size() == sent);
}

TEST_CASE(
    "indexer driver: each injected fault is a clear error within twice the timeout, all axes "
    "killed",
    "[indexer]") {
  // A failed command costs 1.25x the timeout plus a 50 ms drain of the
  // kills' replies; a long timeout keeps the bound's slack (0.7 s) clear of a
  // loaded machine's scheduling stalls (the sanitizer build beside the fuzzers
  // once took 0.63 s against 0.43 s expected at a 0.3 s timeout).
  const auto timeout = std::chrono::milliseconds(1000);
  struct Case {
    IndexerFault fault;
    const char* expect;
    bool kills_reach;  // whether the kill can still reach the units
  };
  const std::vector<Case> cases = {
      {IndexerFault::kNoReply, "no complete reply", true},
      {IndexerFault::kGarbled, "garbled", true},
      {IndexerFault::kPartialLine, "no complete reply", true},
      {IndexerFault::kFaultStatus, "drive fault", true},
      {IndexerFault::kDropConnection, "closed", false},
      {IndexerFault::kSlowReply, "no complete reply", true},
  };
  for (const Case& c : cases) {
    INFO("fault " << static_cast<int>(c.fault));
    rig::IndexerEmulator emulator(kUnits);
    rig::IndexerDriver driver(rig::OpenSerialPort(emulator.Path(), 9600), Options(timeout));
    // A healthy move sends every command the faulted one sends before its
    // fault can show (a drive fault shows only in the status after GO): its
    // time is the line's cost on this machine, so a loaded machine (the
    // sanitizer build beside the fuzzers) does not count against the driver.
    const auto h0 = Clock::now();
    driver.MoveTo(Pose(-0.05, 0, 0, 0.05, 0, 0));
    const double healthy = Seconds(h0);
    emulator.SetFault(c.fault, std::chrono::milliseconds(3 * timeout));
    const auto t0 = Clock::now();
    CHECK_THROWS_WITH(driver.MoveTo(Pose(-0.1, 0.1, 0, 0.1, -0.1, 0)), Catch::Contains(c.expect));
    const double took = Seconds(t0);
    INFO("healthy move " << healthy << " s, faulted " << took << " s");
    CHECK(took < healthy + 2 * std::chrono::duration<double>(timeout).count());
    if (c.kills_reach)
      for (const int u : kUnits) CHECK(emulator.Kills(u) >= 1);
  }
  // A slow reply inside the timeout is only slow.
  rig::IndexerEmulator emulator(kUnits);
  rig::IndexerDriver driver(rig::OpenSerialPort(emulator.Path(), 9600), Options(timeout));
  emulator.SetFault(IndexerFault::kSlowReply, std::chrono::milliseconds(20));
  CHECK_NOTHROW(driver.MoveTo(Pose(-0.02, 0, 0, 0.02, 0, 0)));
  CHECK(emulator.Position(4) == 8000);
}

TEST_CASE("indexer driver: a long random sequence of moves ends where commanded", "[indexer]") {
  rig::IndexerEmulator emulator(kUnits);
  const rig::IndexerOptions options = Options();
  rig::IndexerDriver driver(rig::OpenSerialPort(emulator.Path(), 38400), options);
  std::mt19937 rng(7);
  std::array<long, rig::kNumAxes> steps{};
  for (int k = 0; k < 60; ++k) {
    std::array<double, rig::kNumAxes> v{};
    for (int i = 0; i < rig::kNumAxes; ++i) {
      const rig::IndexerAxis& a = options.axes[i];
      v[i] = std::uniform_real_distribution<double>(a.min, a.max)(rng);
      steps[i] = driver.ToSteps(static_cast<Axis>(i), v[i]);
    }
    driver.MoveTo(rig::StageState::FromArray(v));
  }
  for (int i = 0; i < rig::kNumAxes; ++i) CHECK(emulator.Position(i + 1) == steps[i]);
  CHECK(driver.PositionSteps() == steps);
}

TEST_CASE("serial ports: a missing port and a wrong baud rate are one-line errors", "[indexer]") {
  CHECK_THROWS_WITH(rig::OpenSerialPort("/dev/ttyNOPE0", 9600),
                    Catch::Contains("/dev/ttyNOPE0") && Catch::Contains("does not exist"));
  CHECK_THROWS_WITH(rig::OpenSerialPort("/dev/null", 12345), Catch::Contains("baud rate 12345"));
}

TEST_CASE("indexer driver: SIGTERM and a driver destroyed mid-move kill every axis", "[indexer]") {
  rig::IndexerEmulator emulator(kUnits);
  // In a child process: start a move on every axis, then be terminated.
  const pid_t child = fork();
  REQUIRE(child >= 0);
  if (child == 0) {
    signal(SIGTERM, SIG_DFL);  // as in a plain program (Catch2 has its own handler)
    rig::IndexerDriver driver(rig::OpenSerialPort(emulator.Path(), 9600), Options());
    for (const int u : kUnits) {
      driver.Send(IndexerCommand::kVelocity, u, "100");
      driver.Send(IndexerCommand::kDistance, u, "100000");
      driver.Send(IndexerCommand::kGo, u);
    }
    raise(SIGTERM);
    _exit(0);  // not reached: the handler re-raises with the default action
  }
  int status = 0;
  waitpid(child, &status, 0);
  CHECK(WIFSIGNALED(status));
  CHECK(WTERMSIG(status) == SIGTERM);
  const auto deadline = Clock::now() + std::chrono::seconds(2);
  while (emulator.Kills(6) == 0 && Clock::now() < deadline)
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  for (const int u : kUnits) {
    CHECK(emulator.Kills(u) == 1);
    CHECK_FALSE(emulator.Moving(u));
  }
  // A driver that goes away while a move is pending kills the axes.
  {
    rig::IndexerDriver driver(rig::OpenSerialPort(emulator.Path(), 9600), Options());
    emulator.SetFault(IndexerFault::kFaultStatus);  // the move never completes...
    CHECK_THROWS(driver.MoveTo(Pose(-0.1, 0, 0, 0.1, 0, 0)));
  }
  for (const int u : kUnits) CHECK(emulator.Kills(u) == 2);
}

TEST_CASE("indexer replies: framing, position and status parsed or refused, never misread",
          "[indexer]") {
  const rig::IndexerDialect& d = rig::IndexerDialect::Compumotor6k();
  using R = rig::IndexerDialect::Reply;
  CHECK(d.ParseReply("").status == R::kIncomplete);
  CHECK(d.ParseReply("*TPC+12").status == R::kIncomplete);
  const R ok = d.ParseReply("*TPC+12800\r\n> ");
  CHECK(ok.status == R::kOk);
  CHECK(ok.text == "*TPC+12800");
  const R bad = d.ParseReply("ERROR: bad command\r\n? ");
  CHECK(bad.status == R::kRejected);
  CHECK(bad.text == "ERROR: bad command");
  CHECK(d.ParseReply("*TPC+1\x01\r\n> ").status == R::kGarbled);
  CHECK(d.ParseReply("> ").status == R::kOk);  // a bare prompt: an empty reply
  // Positions: signed whole step counts that fit a long, nothing else.
  CHECK(d.ParsePosition("*TPC+12800") == 12800L);
  CHECK(d.ParsePosition("*TPC-5") == -5L);
  CHECK(d.ParsePosition("*TPC0") == 0L);
  for (const char* unreadable : {"*TPC", "*TPC+", "*TPC 12", "*TPC+12x", "*TPE+12", "TPC+12",
                                 "*TPC+99999999999999999999999", "*TPC--1"})
    CHECK_FALSE(d.ParsePosition(unreadable));
  // Status: exactly 32 bits in groups.
  const std::string bits = "1000_0000_0000_0100_0000_0000_0000_0001";
  const std::optional<std::string> parsed = d.ParseStatus("*TAS" + bits);
  REQUIRE(parsed);
  CHECK(*parsed == "10000000000001000000000000000001");
  CHECK_FALSE(d.ParseStatus("*TAS1000_0000"));
  CHECK_FALSE(d.ParseStatus("*TAS" + bits + "1"));
  CHECK_FALSE(d.ParseStatus("*TAS" + bits.substr(0, 38) + "2"));
}
