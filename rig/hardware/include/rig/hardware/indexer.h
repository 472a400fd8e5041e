// The serial stage driver: six axes, each a unit on a daisy chain of
// Compumotor 6000-style indexers, spoken to in an address-prefixed ASCII
// language (rig/README.md). The language is one table (IndexerDialect), so a
// different controller is a new table, not a new driver.
#pragma once

#include <array>
#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "rig/types.h"

namespace rig {

/// What the driver can ask of an indexer.
enum class IndexerCommand {
  kAcceleration,     ///< set acceleration, steps/s^2
  kVelocity,         ///< set velocity, steps/s
  kDistance,         ///< set distance (absolute: target), steps
  kAbsoluteMode,     ///< positions are absolute
  kIncrementalMode,  ///< positions are relative to the current one
  kGo,               ///< start the move
  kStop,             ///< decelerate to a stop (immediate)
  kKill,             ///< stop at once, abandon the move (immediate)
  kPositionReport,   ///< query: commanded position, steps
  kStatus,           ///< query: axis status bits
  kCount
};

/// One controller language: command templates ("{u}" is the unit address,
/// "{v}" the value), reply prefixes, prompts and status bits.
struct IndexerDialect {
  std::string name;
  std::array<std::string, static_cast<int>(IndexerCommand::kCount)> templates;
  std::string line_end = "\r";           ///< ends every command
  std::string ok_prompt = "> ";          ///< after a good command (error level 4), at a line start
  std::string error_prompt = "? ";       ///< after a rejected one, its error text before
  std::string position_reply = "*TPC";   ///< followed by a signed step count
  std::string status_reply = "*TAS";     ///< followed by 32 bits in groups of 4
  int moving_bit = 0;                    ///< bit numbers (0 = first character) in the status
  int fault_bit = 13;                    ///< drive fault
  int limit_bits[4] = {14, 15, 16, 17};  ///< hardware and soft limits hit

  std::string Format(IndexerCommand command, int unit, const std::string& value = "") const;

  /// What the bytes received so far after a command say: no whole reply yet
  /// (kIncomplete), a reply ended by the ok prompt (kOk, `text` the reply
  /// before it, trimmed), one ended by the error prompt (kRejected, `text`
  /// the error), or bytes no indexer sends (kGarbled: outside printable
  /// ASCII, CR and LF). Total for any input.
  struct Reply {
    enum Status { kIncomplete, kOk, kRejected, kGarbled } status = kIncomplete;
    std::string text;
  };
  Reply ParseReply(const std::string& received) const;

  /// The step count of a position report ("*TPC+12800" -> 12800); nullopt
  /// when the reply is not one or its number does not fit a long.
  std::optional<long> ParsePosition(const std::string& reply) const;

  /// The 32 status bits of a status report ("*TAS0000_0000_..."), as '0'
  /// and '1' characters; nullopt when the reply is not one.
  std::optional<std::string> ParseStatus(const std::string& reply) const;

  /// Compumotor 6000-series style: "1_A25000", "1_!K", "1_TPC" -> "*TPC+12800".
  static const IndexerDialect& Compumotor6k();
};

/// A byte pipe to the indexers: LibSerial on a port, or anything else.
class SerialLine {
 public:
  virtual ~SerialLine() = default;
  virtual void Write(const std::string& bytes) = 0;
  /// Reads what is available, waiting at most `timeout`; "" when nothing
  /// came. Throws RigError when the line is gone.
  virtual std::string ReadSome(std::chrono::milliseconds timeout) = 0;
  /// For the signal handler: a file descriptor write(2) may use, or -1.
  virtual int NativeHandle() const { return -1; }
};

/// Opens a serial port with LibSerial, 8N1, no flow control. Throws
/// RigError naming the port when it cannot be opened, and naming the rate
/// when `baud` is not one LibSerial knows.
std::unique_ptr<SerialLine> OpenSerialPort(const std::string& port, int baud);

/// One axis: its unit address and how its steps relate to metres or radians.
struct IndexerAxis {
  int unit = 1;
  double steps_per_unit = 1;  ///< steps per metre or per radian
  int sign = 1;               ///< +1 or -1: motor direction against the axis
  double velocity = 1;        ///< metres or radians per second
  double acceleration = 1;    ///< per second squared
  double min = 0, max = 0;    ///< soft limits, metres or radians
};

struct IndexerOptions {
  std::array<IndexerAxis, kNumAxes> axes;  ///< in Axis order
  std::chrono::milliseconds reply_timeout{1000};
  int retries = 1;  ///< resend once on a timeout (waiting a quarter as long), then fail
  double move_timeout_margin_s = 2;  ///< a move may take its profile time x2 plus this
  std::chrono::milliseconds poll_interval{20};
  int position_tolerance_steps = 0;  ///< read-back against command
  void Check() const;                ///< throws RigError naming the axis
};

/// Drives the six axes. Every error kills all axes (best effort) and throws
/// RigError naming the unit, the command and what went wrong; no wait is
/// unbounded. A destroyed driver with a move pending kills all axes, and
/// SIGINT/SIGTERM kill all axes of every live driver before the process ends.
class IndexerDriver {
 public:
  IndexerDriver(std::unique_ptr<SerialLine> line, const IndexerOptions& options,
                const IndexerDialect& dialect = IndexerDialect::Compumotor6k());
  ~IndexerDriver();
  IndexerDriver(const IndexerDriver&) = delete;
  IndexerDriver& operator=(const IndexerDriver&) = delete;

  /// Sends one command and returns the reply text before the prompt.
  std::string Send(IndexerCommand command, int unit, const std::string& value = "");

  /// Moves all axes to `target` (absolute), waits for all to report ready,
  /// reads the positions back and checks them against the command. Throws
  /// before sending anything if an axis is outside its soft limits.
  MoveResult MoveTo(const StageState& target);

  /// Positions read back from the indexers.
  StageState Position();
  std::array<long, kNumAxes> PositionSteps();

  /// Status bits of one axis, e.g. "0000_0000_...".
  std::string Status(Axis axis);

  /// Kill on every axis; errors are swallowed (used on the error paths).
  void KillAll() noexcept;
  void StopAll();

  long ToSteps(Axis axis, double value) const;
  double FromSteps(Axis axis, long steps) const;

 private:
  std::string Exchange(const std::string& line, const std::string& what);
  [[noreturn]] void Fail(const std::string& message);

  std::unique_ptr<SerialLine> line_;
  IndexerOptions options_;
  const IndexerDialect& dialect_;
  bool move_pending_ = false;
  std::string pending_;  ///< bytes read past the last prompt
  std::string kill_bytes_;
  int kill_slot_ = -1;  ///< in the signal handler's table
};

}  // namespace rig
