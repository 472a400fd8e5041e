// An emulated daisy chain of indexers on a pseudo-terminal: the driver opens
// Path() as if it were the serial port. Motion follows trapezoidal profiles
// from the commanded acceleration and velocity; faults can be injected.
#pragma once

#include <atomic>
#include <chrono>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace rig {

enum class IndexerFault {
  kNone,
  kNoReply,         ///< commands are carried out but never answered
  kGarbled,         ///< answers are garbage bytes
  kPartialLine,     ///< answers stop half way, no prompt
  kFaultStatus,     ///< drive fault: moves stop, status shows the fault bit
  kDropConnection,  ///< the line closes at the next command
  kSlowReply,       ///< answers come after a delay
};

class IndexerEmulator {
 public:
  /// Units answering on the chain (addresses 1 to 99).
  explicit IndexerEmulator(const std::vector<int>& units);
  ~IndexerEmulator();
  IndexerEmulator(const IndexerEmulator&) = delete;
  IndexerEmulator& operator=(const IndexerEmulator&) = delete;

  /// The pseudo-terminal's device path (/dev/pts/N) for the driver.
  const std::string& Path() const { return path_; }

  void SetFault(IndexerFault fault, std::chrono::milliseconds delay = std::chrono::milliseconds(0));

  /// Kills received by a unit, its commanded position now, every line received.
  int Kills(int unit) const;
  long Position(int unit) const;
  bool Moving(int unit) const;
  std::vector<std::string> Received() const;

 private:
  struct Unit {
    long position = 0;  ///< at rest, or where the current move started
    long target = 0;
    long distance = 0;
    double velocity = 10000, acceleration = 100000;
    bool absolute = true;
    bool moving = false;
    std::chrono::steady_clock::time_point start;
    double duration_s = 0;
    int kills = 0;
  };
  void Serve();
  std::string Handle(const std::string& line);
  long Now(const Unit& u) const;  ///< commanded position along the profile
  void Settle(Unit& u) const;     ///< ends a finished move
  static std::string Reply(const std::string& text, bool ok);

  std::string path_;
  int master_ = -1, slave_ = -1;
  mutable std::mutex mutex_;
  std::map<int, Unit> units_;
  std::vector<std::string> received_;
  IndexerFault fault_ = IndexerFault::kNone;
  std::chrono::milliseconds delay_{0};
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

}  // namespace rig
