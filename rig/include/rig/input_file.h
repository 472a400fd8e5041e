// Reading the files a user gives the testbed (configs, sweeps, scenes,
// calibrations): bounded, and refused with one line naming the file when they
// are not what they should be.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>

namespace rig {

/// Thrown for a file or a value the user gave that cannot be used; the
/// message names it. The command line turns it into exit code 2.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The largest text file the testbed reads (YAML, MJCF, JSON): far above any
/// real config or scene, far below what would exhaust memory.
constexpr std::uintmax_t kMaxInputFileBytes = std::uintmax_t{64} << 20;

/// The longest piece of user input a message echoes (ClipForMessage).
constexpr std::size_t kMaxEchoChars = 200;

/// The whole of `path`, after checking that it is a regular file (not a
/// folder, a device or a pipe) of at most `max_bytes`. Throws InputError
/// "<what> '<path>': <problem>".
std::string ReadInputFile(const std::string& path, const std::string& what,
                          std::uintmax_t max_bytes = kMaxInputFileBytes);

/// Throws InputError like ReadInputFile unless `path` is a regular file of
/// at most `max_bytes` (for files another library opens itself).
void CheckInputFile(const std::string& path, const std::string& what,
                    std::uintmax_t max_bytes = kMaxInputFileBytes);

/// `text` as a message may echo it: at most `max_chars` characters (then
/// "...", and how long it was), control characters shown as '?'.
std::string ClipForMessage(const std::string& text, std::size_t max_chars = kMaxEchoChars);

}  // namespace rig
