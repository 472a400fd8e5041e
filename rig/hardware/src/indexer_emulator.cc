#include "rig/hardware/indexer_emulator.h"

#include <poll.h>
#include <pty.h>
#include <termios.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace rig {
namespace {
using Clock = std::chrono::steady_clock;
}  // namespace

IndexerEmulator::IndexerEmulator(const std::vector<int>& units) {
  for (const int u : units) units_[u] = Unit{};
  termios raw{};
  cfmakeraw(&raw);
  char name[256];
  if (openpty(&master_, &slave_, name, &raw, nullptr) != 0)
    throw std::runtime_error("indexer emulator: openpty failed");
  path_ = name;
  thread_ = std::thread([this] { Serve(); });
}

IndexerEmulator::~IndexerEmulator() {
  stop_ = true;
  thread_.join();
  if (master_ >= 0) close(master_);
  if (slave_ >= 0) close(slave_);
}

void IndexerEmulator::SetFault(IndexerFault fault, std::chrono::milliseconds delay) {
  std::lock_guard<std::mutex> lock(mutex_);
  fault_ = fault;
  delay_ = delay;
}

int IndexerEmulator::Kills(int unit) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = units_.find(unit);
  return it == units_.end() ? 0 : it->second.kills;
}

long IndexerEmulator::Position(int unit) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = units_.find(unit);
  return it == units_.end() ? 0 : Now(it->second);
}

bool IndexerEmulator::Moving(int unit) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = units_.find(unit);
  if (it == units_.end() || !it->second.moving) return false;
  return std::chrono::duration<double>(Clock::now() - it->second.start).count() <
         it->second.duration_s;
}

std::vector<std::string> IndexerEmulator::Received() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return received_;
}

long IndexerEmulator::Now(const Unit& u) const {
  if (!u.moving) return u.position;
  const double t = std::chrono::duration<double>(Clock::now() - u.start).count();
  if (t >= u.duration_s) return u.target;
  // Trapezoid (or triangle): accelerate, cruise, decelerate.
  const double d = std::abs(double(u.target - u.position)), a = u.acceleration;
  const double v = std::min(u.velocity, std::sqrt(d * a));
  const double ta = v / a, tc = u.duration_s - 2 * ta;
  double s;
  if (t < ta)
    s = 0.5 * a * t * t;
  else if (t < ta + tc)
    s = 0.5 * a * ta * ta + v * (t - ta);
  else
    s = d - 0.5 * a * (u.duration_s - t) * (u.duration_s - t);
  const double sign = u.target >= u.position ? 1 : -1;
  return u.position + static_cast<long>(std::lround(sign * std::min(s, d)));
}

void IndexerEmulator::Settle(Unit& u) const {
  if (u.moving && std::chrono::duration<double>(Clock::now() - u.start).count() >= u.duration_s) {
    u.position = u.target;
    u.moving = false;
  }
}

std::string IndexerEmulator::Reply(const std::string& text, bool ok) {
  return text + (ok ? "\r\n> " : "\r\n? ");
}

// One command line: "[unit_][!]COMMAND[value]".
std::string IndexerEmulator::Handle(const std::string& raw) {
  received_.push_back(raw);
  std::string line = raw;
  int address = 0;
  const size_t underscore = line.find('_');
  if (underscore == std::string::npos || underscore == 0) return Reply("NO UNIT ADDRESS", false);
  try {
    address = std::stoi(line.substr(0, underscore));
  } catch (...) {
    return Reply("BAD UNIT ADDRESS", false);
  }
  const auto it = units_.find(address);
  if (it == units_.end()) return "";  // nobody at that address: silence, as on a real chain
  Unit& u = it->second;
  Settle(u);
  line = line.substr(underscore + 1);
  if (!line.empty() && line[0] == '!') line = line.substr(1);
  auto number = [&](size_t from, double* v) {
    const std::string s = line.substr(from);
    char* end = nullptr;
    *v = std::strtod(s.c_str(), &end);
    return !s.empty() && end && *end == '\0';
  };
  double v = 0;
  if (line == "K") {
    u.position = Now(u);
    u.target = u.position;
    u.moving = false;
    ++u.kills;
    return Reply("", true);
  }
  if (line == "S") {
    u.position = Now(u);
    u.target = u.position;
    u.moving = false;
    return Reply("", true);
  }
  if (line == "TPC") {
    char buf[48];
    std::snprintf(buf, sizeof buf, "*TPC%+ld", Now(u));
    return Reply(buf, true);
  }
  if (line == "TAS") {
    std::string bits(32, '0');
    bits[0] = u.moving ? '1' : '0';
    if (fault_ == IndexerFault::kFaultStatus) bits[13] = '1';
    std::string grouped = "*TAS";
    for (int i = 0; i < 32; ++i) grouped += (i && i % 4 == 0 ? "_" : "") + std::string(1, bits[i]);
    return Reply(grouped, true);
  }
  if (line == "MA1" || line == "MA0") {
    u.absolute = line == "MA1";
    return Reply("", true);
  }
  if (line == "GO1") {
    if (u.moving) return Reply("MOTION IN PROGRESS", false);
    if (fault_ == IndexerFault::kFaultStatus)
      return Reply("", true);  // a faulted drive does not move
    u.target = u.absolute ? u.distance : u.position + u.distance;
    const double d = std::abs(double(u.target - u.position));
    const double a = u.acceleration, vmax = u.velocity;
    u.duration_s = d >= vmax * vmax / a ? d / vmax + vmax / a : 2 * std::sqrt(d / a);
    u.start = Clock::now();
    u.moving = d > 0;
    return Reply("", true);
  }
  if (line.rfind("A", 0) == 0 && number(1, &v) && v > 0) return u.acceleration = v, Reply("", true);
  if (line.rfind("V", 0) == 0 && number(1, &v) && v > 0) return u.velocity = v, Reply("", true);
  if (line.rfind("D", 0) == 0 && number(1, &v) && v == std::floor(v))
    return u.distance = static_cast<long>(v), Reply("", true);
  return Reply("INVALID COMMAND OR VALUE '" + line + "'", false);
}

void IndexerEmulator::Serve() {
  std::string buffer;
  // Slow replies: the command takes effect at once, its answer goes out late.
  std::vector<std::pair<Clock::time_point, std::string>> late;
  while (!stop_) {
    for (auto it = late.begin(); it != late.end();)
      if (Clock::now() >= it->first && master_ >= 0) {
        ssize_t w = ::write(master_, it->second.data(), it->second.size());
        (void)w;
        it = late.erase(it);
      } else {
        ++it;
      }
    pollfd p{master_, POLLIN, 0};
    if (master_ < 0 || ::poll(&p, 1, 10) <= 0) {
      if (master_ < 0) std::this_thread::sleep_for(std::chrono::milliseconds(10));
      continue;
    }
    char buf[256];
    const ssize_t n = ::read(master_, buf, sizeof buf);
    if (n <= 0) continue;
    buffer.append(buf, static_cast<size_t>(n));
    for (size_t end; (end = buffer.find_first_of("\r\n")) != std::string::npos;) {
      const std::string line = buffer.substr(0, end);
      buffer.erase(0, end + 1);
      if (line.empty()) continue;
      std::string reply;
      IndexerFault fault;
      std::chrono::milliseconds delay;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        reply = Handle(line);
        fault = fault_;
        delay = delay_;
      }
      switch (fault) {
        case IndexerFault::kNoReply:
          reply.clear();
          break;
        case IndexerFault::kGarbled:
          reply = "\x9f\xa3\xff\x01#\r\n> ";
          break;
        case IndexerFault::kPartialLine:
          reply = reply.substr(0, reply.size() / 2 > 4 ? 4 : reply.size() / 2);
          break;
        case IndexerFault::kDropConnection:
          close(master_);
          close(slave_);
          master_ = slave_ = -1;
          reply.clear();
          break;
        case IndexerFault::kSlowReply:
          late.emplace_back(Clock::now() + delay, reply);
          reply.clear();
          break;
        default:
          break;
      }
      if (master_ < 0) break;
      if (!reply.empty()) {
        ssize_t w = ::write(master_, reply.data(), reply.size());
        (void)w;
      }
    }
  }
}

}  // namespace rig
