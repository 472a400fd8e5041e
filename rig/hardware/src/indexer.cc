#include "rig/hardware/indexer.h"

#include <fcntl.h>
#include <libserial/SerialPort.h>
#include <poll.h>
#include <pty.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <thread>

#include "rig/input_file.h"

namespace rig {
namespace {

using Clock = std::chrono::steady_clock;

// ---- kill on SIGINT/SIGTERM: precomputed bytes written with write(2), the
// only thing a signal handler may safely do here.
struct KillSlot {
  volatile sig_atomic_t used = 0;
  int fd = -1;
  char bytes[512];
  int length = 0;
};
KillSlot g_slots[16];
struct sigaction g_previous_int, g_previous_term;

void KillOnSignal(int sig) {
  for (KillSlot& s : g_slots)
    if (s.used && s.fd >= 0) {
      ssize_t ignored = ::write(s.fd, s.bytes, s.length);
      (void)ignored;
    }
  sigaction(SIGINT, &g_previous_int, nullptr);
  sigaction(SIGTERM, &g_previous_term, nullptr);
  raise(sig);
}

int RegisterKill(int fd, const std::string& bytes) {
  if (fd < 0 || bytes.size() > sizeof(KillSlot::bytes)) return -1;
  // Ours goes in front of whatever handles the signal now (installed again
  // if someone replaced it since), and hands the signal on to it.
  for (const auto& [sig, previous] :
       {std::pair<int, struct sigaction*>{SIGINT, &g_previous_int},
        std::pair<int, struct sigaction*>{SIGTERM, &g_previous_term}}) {
    struct sigaction now {};
    sigaction(sig, nullptr, &now);
    if (now.sa_handler == KillOnSignal) continue;
    struct sigaction sa {};
    sa.sa_handler = KillOnSignal;
    sigaction(sig, &sa, previous);
  }
  for (int i = 0; i < 16; ++i)
    if (!g_slots[i].used) {
      g_slots[i].fd = fd;
      std::memcpy(g_slots[i].bytes, bytes.data(), bytes.size());
      g_slots[i].length = static_cast<int>(bytes.size());
      g_slots[i].used = 1;
      return i;
    }
  return -1;
}

class LibSerialLine : public SerialLine {
 public:
  LibSerialLine(const std::string& port, LibSerial::BaudRate baud) {
    try {
      port_.Open(port);
      port_.SetBaudRate(baud);
      port_.SetCharacterSize(LibSerial::CharacterSize::CHAR_SIZE_8);
      port_.SetParity(LibSerial::Parity::PARITY_NONE);
      port_.SetStopBits(LibSerial::StopBits::STOP_BITS_1);
      port_.SetFlowControl(LibSerial::FlowControl::FLOW_CONTROL_NONE);
    } catch (const std::exception& e) {
      CloseQuietly();  // LibSerial's own destructor would throw from here
      throw RigError("serial port '" + ClipForMessage(port) + "' cannot be opened: " + e.what());
    }
    name_ = port;
  }
  void Write(const std::string& bytes) override {
    try {
      port_.Write(bytes);
    } catch (const std::exception& e) {
      throw RigError("serial port '" + name_ + "': write failed: " + e.what());
    }
  }
  std::string ReadSome(std::chrono::milliseconds timeout) override {
    const int fd = port_.GetFileDescriptor();
    pollfd p{fd, POLLIN, 0};
    const int r = ::poll(&p, 1, static_cast<int>(timeout.count()));
    if (r < 0 && errno != EINTR)
      throw RigError("serial port '" + name_ + "': " + std::strerror(errno));
    if (r <= 0) return "";
    if (p.revents & (POLLHUP | POLLERR | POLLNVAL))
      throw RigError("serial port '" + name_ + "': the line was closed");
    char buf[512];
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n == 0 || (n < 0 && errno != EAGAIN && errno != EINTR))
      throw RigError("serial port '" + name_ + "': the line was closed");
    return n > 0 ? std::string(buf, static_cast<size_t>(n)) : "";
  }
  int NativeHandle() const override { return port_.GetFileDescriptor(); }
  ~LibSerialLine() override { CloseQuietly(); }

 private:
  // LibSerial's Close restores the port's settings and throws when the line
  // is gone (EIO) or is no terminal, leaving the port open, and its
  // destructor would then throw again (std::terminate).
  void CloseQuietly() noexcept {
    try {
      if (port_.IsOpen()) port_.Close();
    } catch (...) {
      // The line is gone: put a fresh pseudo-terminal under the descriptor
      // so that Close can restore settings and close it, then drop that.
      int master = -1, slave = -1;
      if (openpty(&master, &slave, nullptr, nullptr, nullptr) == 0) {
        ::dup2(slave, port_.GetFileDescriptor());
        ::close(slave);
        try {
          port_.Close();
        } catch (...) {
        }
        ::close(master);
      }
      if (port_.IsOpen()) {
        ::close(port_.GetFileDescriptor());
        owned_.release();  // NOLINT(bugprone-unused-return-value): its destructor would throw
      }
    }
  }

  std::unique_ptr<LibSerial::SerialPort> owned_ = std::make_unique<LibSerial::SerialPort>();
  LibSerial::SerialPort& port_ = *owned_;
  std::string name_;
};

bool Garbled(const std::string& s) {
  return std::any_of(s.begin(), s.end(), [](char c) {
    const auto u = static_cast<unsigned char>(c);
    return !(u == '\r' || u == '\n' || (u >= 32 && u < 127));
  });
}

std::string Trim(std::string s) {
  while (!s.empty() && (s.back() == '\r' || s.back() == '\n' || s.back() == ' ')) s.pop_back();
  size_t b = 0;
  while (b < s.size() && (s[b] == '\r' || s[b] == '\n' || s[b] == ' ')) ++b;
  return s.substr(b);
}

}  // namespace

IndexerDialect::Reply IndexerDialect::ParseReply(const std::string& received) const {
  if (Garbled(received)) return {Reply::kGarbled, ""};
  const std::string framed = "\n" + received;
  const size_t k_ok = framed.find("\n" + ok_prompt), k_bad = framed.find("\n" + error_prompt);
  if (k_bad != std::string::npos && (k_ok == std::string::npos || k_bad < k_ok))
    return {Reply::kRejected, Trim(framed.substr(0, k_bad))};
  if (k_ok != std::string::npos) return {Reply::kOk, Trim(framed.substr(0, k_ok))};
  return {Reply::kIncomplete, ""};
}

std::optional<long> IndexerDialect::ParsePosition(const std::string& reply) const {
  if (reply.rfind(position_reply, 0) != 0) return std::nullopt;
  const char* number = reply.c_str() + position_reply.size();
  if (*number != '+' && *number != '-' && !std::isdigit(static_cast<unsigned char>(*number)))
    return std::nullopt;
  errno = 0;
  char* end = nullptr;
  const long v = std::strtol(number, &end, 10);
  if (end == number || *end != '\0' || errno == ERANGE) return std::nullopt;
  return v;
}

std::optional<std::string> IndexerDialect::ParseStatus(const std::string& reply) const {
  if (reply.rfind(status_reply, 0) != 0) return std::nullopt;
  std::string bits;
  for (size_t i = status_reply.size(); i < reply.size(); ++i) {
    const char c = reply[i];
    if (c == '0' || c == '1')
      bits += c;
    else if (c != '_')
      return std::nullopt;
  }
  if (bits.size() != 32) return std::nullopt;
  return bits;
}

std::string IndexerDialect::Format(IndexerCommand command, int unit,
                                   const std::string& value) const {
  std::string t = templates[static_cast<int>(command)];
  for (size_t p; (p = t.find("{u}")) != std::string::npos;) t.replace(p, 3, std::to_string(unit));
  for (size_t p; (p = t.find("{v}")) != std::string::npos;) t.replace(p, 3, value);
  return t;
}

const IndexerDialect& IndexerDialect::Compumotor6k() {
  static const IndexerDialect d = [] {
    IndexerDialect x;
    x.name = "compumotor-6k";
    auto set = [&](IndexerCommand c, const char* t) { x.templates[static_cast<int>(c)] = t; };
    set(IndexerCommand::kAcceleration, "{u}_A{v}");
    set(IndexerCommand::kVelocity, "{u}_V{v}");
    set(IndexerCommand::kDistance, "{u}_D{v}");
    set(IndexerCommand::kAbsoluteMode, "{u}_MA1");
    set(IndexerCommand::kIncrementalMode, "{u}_MA0");
    set(IndexerCommand::kGo, "{u}_GO1");
    set(IndexerCommand::kStop, "{u}_!S");
    set(IndexerCommand::kKill, "{u}_!K");
    set(IndexerCommand::kPositionReport, "{u}_TPC");
    set(IndexerCommand::kStatus, "{u}_TAS");
    return x;
  }();
  return d;
}

// A serial port is a terminal device: refuse anything else (a regular file,
// /dev/null) before LibSerial's terminal calls fail on it.
void CheckSerialDevice(const std::string& port) {
  const std::string name = "serial port '" + ClipForMessage(port) + "'";
  struct stat st {};
  if (::stat(port.c_str(), &st) != 0) throw InputError(name + " does not exist");
  if (!S_ISCHR(st.st_mode))
    throw InputError(name + " is not a serial device (not a character device)");
  const int fd = ::open(port.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) throw RigError(name + " cannot be opened: " + std::strerror(errno));
  const bool tty = ::isatty(fd);
  ::close(fd);
  if (!tty) throw InputError(name + " is not a serial device (not a terminal)");
}

std::unique_ptr<SerialLine> OpenSerialPort(const std::string& port, int baud) {
  static const std::pair<int, LibSerial::BaudRate> kRates[] = {
      {1200, LibSerial::BaudRate::BAUD_1200},    {2400, LibSerial::BaudRate::BAUD_2400},
      {4800, LibSerial::BaudRate::BAUD_4800},    {9600, LibSerial::BaudRate::BAUD_9600},
      {19200, LibSerial::BaudRate::BAUD_19200},  {38400, LibSerial::BaudRate::BAUD_38400},
      {57600, LibSerial::BaudRate::BAUD_57600},  {115200, LibSerial::BaudRate::BAUD_115200},
      {230400, LibSerial::BaudRate::BAUD_230400}};
  for (const auto& [rate, code] : kRates)
    if (rate == baud) {
      CheckSerialDevice(port);
      return std::make_unique<LibSerialLine>(port, code);
    }
  throw RigError(
      "serial baud rate " + std::to_string(baud) +
      " is not a standard rate (1200, 2400, 4800, 9600, 19200, 38400, 57600, 115200, 230400)");
}

void IndexerOptions::Check() const {
  for (int i = 0; i < kNumAxes; ++i) {
    const IndexerAxis& a = axes[i];
    const std::string name = AxisName(static_cast<Axis>(i));
    if (a.unit < 1 || a.unit > 99)
      throw RigError("indexer axis " + name + ": unit must be 1 to 99");
    if (!(a.steps_per_unit > 0))
      throw RigError("indexer axis " + name + ": steps_per_unit must be positive");
    if (a.sign != 1 && a.sign != -1)
      throw RigError("indexer axis " + name + ": sign must be +1 or -1");
    if (!(a.velocity > 0) || !(a.acceleration > 0))
      throw RigError("indexer axis " + name + ": velocity and acceleration must be positive");
    if (!(a.max > a.min)) throw RigError("indexer axis " + name + ": soft limits need min < max");
    for (int j = 0; j < i; ++j)
      if (axes[j].unit == a.unit)
        throw RigError("indexer axis " + name + ": unit " + std::to_string(a.unit) + " used twice");
  }
  if (reply_timeout.count() <= 0) throw RigError("indexer: reply_timeout must be positive");
}

IndexerDriver::IndexerDriver(std::unique_ptr<SerialLine> line, const IndexerOptions& options,
                             const IndexerDialect& dialect)
    : line_(std::move(line)), options_(options), dialect_(dialect) {
  options_.Check();
  for (const IndexerAxis& a : options_.axes)
    kill_bytes_ += dialect_.Format(IndexerCommand::kKill, a.unit) + dialect_.line_end;
  kill_slot_ = RegisterKill(line_->NativeHandle(), kill_bytes_);
}

IndexerDriver::~IndexerDriver() {
  if (kill_slot_ >= 0) g_slots[kill_slot_].used = 0;
  if (move_pending_) KillAll();
}

void IndexerDriver::Fail(const std::string& message) {
  KillAll();
  move_pending_ = false;
  throw RigError(message);
}

std::string IndexerDriver::Exchange(const std::string& command, const std::string& what) {
  for (int attempt = 0; attempt <= options_.retries; ++attempt) {
    // The retry waits a quarter as long (a reply that was merely late comes
    // then): a command that fails costs at most 1.25x the timeout.
    const auto timeout = attempt == 0 ? options_.reply_timeout : options_.reply_timeout / 4;
    pending_.clear();
    line_->Write(command + dialect_.line_end);
    const auto deadline = Clock::now() + timeout;
    std::string buf;
    while (true) {
      const auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now());
      if (left.count() <= 0) break;
      buf += line_->ReadSome(left);
      const IndexerDialect::Reply reply = dialect_.ParseReply(buf);
      if (reply.status == IndexerDialect::Reply::kGarbled)
        throw RigError(what + ": garbled reply from the indexer");
      if (reply.status == IndexerDialect::Reply::kRejected)
        throw RigError(what + ": the indexer rejected it: " + ClipForMessage(reply.text));
      if (reply.status == IndexerDialect::Reply::kOk) return reply.text;
    }
  }
  throw RigError(what + ": no complete reply within " +
                 std::to_string(options_.reply_timeout.count()) + " ms (tried " +
                 std::to_string(options_.retries + 1) + " times)");
}

std::string IndexerDriver::Send(IndexerCommand command, int unit, const std::string& value) {
  const std::string line = dialect_.Format(command, unit, value);
  try {
    return Exchange(line, "unit " + std::to_string(unit) + " '" + line + "'");
  } catch (const RigError& e) {
    Fail(e.what());
  }
}

long IndexerDriver::ToSteps(Axis axis, double value) const {
  const IndexerAxis& a = options_.axes[static_cast<int>(axis)];
  return std::lround(a.sign * value * a.steps_per_unit);
}

double IndexerDriver::FromSteps(Axis axis, long steps) const {
  const IndexerAxis& a = options_.axes[static_cast<int>(axis)];
  return static_cast<double>(steps) / (a.sign * a.steps_per_unit);
}

std::array<long, kNumAxes> IndexerDriver::PositionSteps() {
  std::array<long, kNumAxes> steps{};
  for (int i = 0; i < kNumAxes; ++i) {
    const int unit = options_.axes[i].unit;
    const std::string reply = Send(IndexerCommand::kPositionReport, unit);
    const std::optional<long> v = dialect_.ParsePosition(reply);
    if (!v)
      Fail("unit " + std::to_string(unit) + ": unreadable position report '" +
           ClipForMessage(reply) + "'");
    steps[i] = *v;
  }
  return steps;
}

StageState IndexerDriver::Position() {
  const auto steps = PositionSteps();
  std::array<double, kNumAxes> v{};
  for (int i = 0; i < kNumAxes; ++i) v[i] = FromSteps(static_cast<Axis>(i), steps[i]);
  return StageState::FromArray(v);
}

std::string IndexerDriver::Status(Axis axis) {
  const int unit = options_.axes[static_cast<int>(axis)].unit;
  const std::string reply = Send(IndexerCommand::kStatus, unit);
  const std::optional<std::string> bits = dialect_.ParseStatus(reply);
  if (!bits)
    Fail("unit " + std::to_string(unit) + ": unreadable status report '" + ClipForMessage(reply) +
         "'");
  return *bits;
}

void IndexerDriver::KillAll() noexcept {
  try {
    line_->Write(kill_bytes_);
    // Drain the kills' replies briefly; never wait long on an error path.
    const auto deadline = Clock::now() + std::chrono::milliseconds(50);
    while (Clock::now() < deadline) line_->ReadSome(std::chrono::milliseconds(10));
  } catch (...) {
  }
  move_pending_ = false;
}

void IndexerDriver::StopAll() {
  for (const IndexerAxis& a : options_.axes) Send(IndexerCommand::kStop, a.unit);
  move_pending_ = false;
}

MoveResult IndexerDriver::MoveTo(const StageState& target) {
  const auto values = target.ToArray();
  for (int i = 0; i < kNumAxes; ++i) {
    const IndexerAxis& a = options_.axes[i];
    if (!(values[i] >= a.min - 1e-12 && values[i] <= a.max + 1e-12))
      throw RigError(std::string("move refused: ") + AxisName(static_cast<Axis>(i)) + " " +
                     std::to_string(values[i]) + " is outside its soft limits [" +
                     std::to_string(a.min) + ", " + std::to_string(a.max) + "]");
  }
  const auto t0 = Clock::now();
  const auto start = PositionSteps();
  std::array<long, kNumAxes> goal{};
  double profile_s = 0;
  for (int i = 0; i < kNumAxes; ++i) {
    const IndexerAxis& a = options_.axes[i];
    goal[i] = ToSteps(static_cast<Axis>(i), values[i]);
    const double v = a.velocity * a.steps_per_unit, acc = a.acceleration * a.steps_per_unit;
    const double d = std::abs(static_cast<double>(goal[i] - start[i]));
    profile_s = std::max(profile_s, d >= v * v / acc ? d / v + v / acc : 2 * std::sqrt(d / acc));
    char accel[32], vel[32];
    std::snprintf(accel, sizeof accel, "%.0f", std::ceil(acc));
    std::snprintf(vel, sizeof vel, "%.0f", std::ceil(v));
    Send(IndexerCommand::kAbsoluteMode, a.unit);
    Send(IndexerCommand::kAcceleration, a.unit, accel);
    Send(IndexerCommand::kVelocity, a.unit, vel);
    Send(IndexerCommand::kDistance, a.unit, std::to_string(goal[i]));
  }
  move_pending_ = true;
  for (const IndexerAxis& a : options_.axes) Send(IndexerCommand::kGo, a.unit);
  const auto deadline =
      Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(
                         2 * profile_s + options_.move_timeout_margin_s));
  for (bool moving = true; moving;) {
    std::this_thread::sleep_for(options_.poll_interval);
    moving = false;
    for (int i = 0; i < kNumAxes; ++i) {
      const std::string bits = Status(static_cast<Axis>(i));
      const std::string unit = "unit " + std::to_string(options_.axes[i].unit);
      if (bits[dialect_.fault_bit] == '1') Fail(unit + ": drive fault (status " + bits + ")");
      for (const int b : dialect_.limit_bits)
        if (bits[b] == '1') Fail(unit + ": limit hit (status " + bits + ")");
      moving |= bits[dialect_.moving_bit] == '1';
    }
    if (moving && Clock::now() > deadline)
      Fail("move did not finish within " +
           std::to_string(2 * profile_s + options_.move_timeout_margin_s) + " s");
  }
  move_pending_ = false;
  const auto reached = PositionSteps();
  for (int i = 0; i < kNumAxes; ++i)
    if (std::labs(reached[i] - goal[i]) > options_.position_tolerance_steps)
      Fail("unit " + std::to_string(options_.axes[i].unit) + ": position " +
           std::to_string(reached[i]) + " steps after the move, commanded " +
           std::to_string(goal[i]));
  MoveResult r;
  r.motion_time_s = std::chrono::duration<double>(Clock::now() - t0).count();
  std::array<double, kNumAxes> v{};
  for (int i = 0; i < kNumAxes; ++i) v[i] = FromSteps(static_cast<Axis>(i), reached[i]);
  r.reached = StageState::FromArray(v);
  return r;
}

}  // namespace rig
