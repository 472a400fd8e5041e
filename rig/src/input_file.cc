#include "rig/input_file.h"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace rig {
namespace fs = std::filesystem;

void CheckInputFile(const std::string& path, const std::string& what, std::uintmax_t max_bytes) {
  const std::string name = what + " '" + ClipForMessage(path) + "'";
  if (path.empty()) throw InputError(what + ": no file name given");
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (ec || !fs::exists(status)) throw InputError(name + " cannot be read: no such file");
  if (fs::is_directory(status)) throw InputError(name + " is a folder, not a file");
  if (!fs::is_regular_file(status))
    throw InputError(name + " is not a regular file (a device, pipe or socket)");
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec) throw InputError(name + " cannot be read: " + ec.message());
  if (size > max_bytes)
    throw InputError(name + " is " + std::to_string(size) + " bytes, over the limit of " +
                     std::to_string(max_bytes >> 20) + " MiB");
}

std::string ReadInputFile(const std::string& path, const std::string& what,
                          std::uintmax_t max_bytes) {
  CheckInputFile(path, what, max_bytes);
  std::ifstream in(path, std::ios::binary);
  if (!in)
    throw InputError(what + " '" + ClipForMessage(path) +
                     "' cannot be read: " + std::strerror(errno));
  // At most max_bytes + 1: the file may have grown since it was checked.
  std::string all;
  char buf[1 << 16];
  while (in && all.size() <= max_bytes) {
    in.read(buf, sizeof buf);
    all.append(buf, static_cast<size_t>(in.gcount()));
  }
  if (all.size() > max_bytes)
    throw InputError(what + " '" + ClipForMessage(path) + "' is over the limit of " +
                     std::to_string(max_bytes >> 20) + " MiB");
  if (in.bad())
    throw InputError(what + " '" + ClipForMessage(path) + "' cannot be read: read error");
  return all;
}

std::string ClipForMessage(const std::string& text, std::size_t max_chars) {
  std::string s = text.size() > max_chars ? text.substr(0, max_chars) : text;
  for (char& c : s)
    if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) c = '?';
  if (text.size() > max_chars) s += "... (" + std::to_string(text.size()) + " characters)";
  return s;
}

}  // namespace rig
