#include "experiments/output/output.h"

#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <system_error>

namespace experiments {
namespace fs = std::filesystem;

namespace {

// This process's tag in temporary names: host and pid.
std::string ProcessTag() {
  char host[256] = "";
  if (gethostname(host, sizeof host - 1) != 0 || !host[0]) std::snprintf(host, sizeof host, "host");
  std::string tag;
  for (const char* c = host; *c; ++c)
    tag += std::isalnum(static_cast<unsigned char>(*c)) ? *c : '_';
  return tag + "-" + std::to_string(getpid());
}

std::string Quoted(const std::string& path) { return "'" + rig::ClipForMessage(path) + "'"; }

void Commit(const std::string& tmp, const std::string& path) {
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw std::runtime_error("cannot write " + Quoted(path) + ": " + ec.message());
  }
}

bool IsEmptyFolder(const fs::path& p) {
  std::error_code ec;
  return fs::is_directory(fs::symlink_status(p, ec)) && fs::is_empty(p, ec) && !ec;
}

}  // namespace

std::string NormalizeOutputPath(const std::string& path, const std::string& flag) {
  if (path.empty()) throw UsageError(flag + ": the output path is empty");
  fs::path p = fs::path(path).lexically_normal();
  bool too_long = path.size() >= PATH_MAX;
  for (const fs::path& part : p) too_long |= part.string().size() > NAME_MAX;
  if (too_long) throw UsageError(flag + ": the output path is too long: " + Quoted(path));
  if (!p.has_filename()) p = p.parent_path();  // "out/run/" -> "out/run"
  const std::string last = p.filename().string();
  if (p.empty() || last.empty() || last == "." || last == ".." || p == p.root_path())
    throw UsageError(flag + ": " + Quoted(path) +
                     " names an existing folder above the output (., .. or /); name a new folder");
  return p.string();
}

void CheckOutputTarget(const std::string& target, const std::string& flag,
                       ExistingOutput existing) {
  std::error_code ec;
  const fs::file_status s = fs::symlink_status(target, ec);
  const std::string at = flag + ": " + Quoted(target);
  if (ec && ec != std::errc::no_such_file_or_directory)
    throw UsageError(at + " cannot be checked: " + ec.message());
  if (!fs::exists(s) || IsEmptyFolder(target)) return;
  if (fs::is_symlink(s)) throw UsageError(at + " is a symbolic link; name a new folder");
  if (!fs::is_directory(s)) throw UsageError(at + " exists and is not a folder; name a new folder");
  if (existing == ExistingOutput::kRefuse)
    throw UsageError(
        at + " exists and is not empty (pass --force to replace an earlier result of fovea)");
  if (!fs::exists(fs::path(target) / kOutputMarker))
    throw UsageError(at + " is not empty and was not written by fovea (it has no " + kOutputMarker +
                     "); --force replaces only fovea's own output folders");
}

std::string StagingPath(const std::string& target) {
  const fs::path p(target);
  return (p.parent_path() / ("." + p.filename().string() + ".partial-" + ProcessTag())).string();
}

void RemoveStaleStaging(const std::string& target) {
  const fs::path p(target);
  const fs::path parent = p.parent_path().empty() ? fs::path(".") : p.parent_path();
  const std::string tag = ProcessTag();
  const std::string prefix =
      "." + p.filename().string() + ".partial-" + tag.substr(0, tag.rfind('-') + 1);
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(parent, ec)) {
    const std::string name = e.path().filename().string();
    if (name.rfind(prefix, 0) != 0) continue;
    const std::string pid_text = name.substr(prefix.size());
    if (pid_text.empty() || pid_text.find_first_not_of("0123456789") != std::string::npos) continue;
    const long pid = std::stol(pid_text);
    if (pid == getpid() || kill(static_cast<pid_t>(pid), 0) == 0 || errno != ESRCH) continue;
    std::error_code rm;
    fs::remove_all(e.path(), rm);
  }
}

OutputFolder::OutputFolder(const std::string& out, const std::string& flag, ExistingOutput existing)
    : flag_(flag), target_(NormalizeOutputPath(out, flag)), existing_(existing) {
  CheckOutputTarget(target_, flag, existing_);
}

const std::string& OutputFolder::path() {
  if (!staging_.empty()) return staging_;
  const fs::path parent = fs::absolute(target_).parent_path();
  for (fs::path p = parent; !p.empty() && !fs::exists(p); p = p.parent_path()) {
    first_created_ = p.string();
    if (p == p.root_path()) break;
  }
  RemoveStaleStaging(target_);
  const std::string staging = StagingPath(target_);
  std::error_code ec;
  fs::remove_all(staging, ec);
  EnsureDirectory(staging);
  staging_ = staging;
  return staging_;
}

OutputFolder::~OutputFolder() {
  if (committed_) return;
  std::error_code ec;
  if (!staging_.empty()) fs::remove_all(staging_, ec);
  if (first_created_.empty()) return;
  // Parent folders this object made, innermost first, while they are empty.
  for (fs::path p = fs::absolute(target_).parent_path(); !p.empty(); p = p.parent_path()) {
    if (!fs::remove(p, ec) || p == fs::path(first_created_)) break;
  }
}

void OutputFolder::Commit() {
  const std::string dir = path();
  WriteTextAtomic(dir + "/" + kOutputMarker, "written by fovea; --force may replace this folder\n");
  std::error_code ec;
  std::string old;
  if (fs::exists(fs::symlink_status(target_, ec)) && !IsEmptyFolder(target_)) {
    CheckOutputTarget(target_, flag_, existing_);  // it may have changed while we worked
    old = (fs::path(target_).parent_path() /
           ("." + fs::path(target_).filename().string() + ".replaced-" + ProcessTag()))
              .string();
    fs::rename(target_, old, ec);
    if (ec) throw std::runtime_error("cannot replace " + Quoted(target_) + ": " + ec.message());
  }
  fs::rename(staging_, target_, ec);
  if (ec) {
    std::error_code back;
    if (!old.empty()) fs::rename(old, target_, back);
    throw std::runtime_error("cannot write " + Quoted(target_) + ": " + ec.message());
  }
  committed_ = true;
  if (!old.empty()) fs::remove_all(old, ec);
}

std::string CheckOutputFile(const std::string& path, const std::string& flag, bool force) {
  const std::string p = NormalizeOutputPath(path, flag);
  std::error_code ec;
  const fs::file_status s = fs::symlink_status(p, ec);
  if (ec || !fs::exists(s)) return p;
  if (fs::is_symlink(s)) throw UsageError(flag + ": " + Quoted(p) + " is a symbolic link");
  if (!fs::is_regular_file(s))
    throw UsageError(flag + ": " + Quoted(p) + " exists and is not a file");
  if (!force) throw UsageError(flag + ": " + Quoted(p) + " exists (pass --force to replace it)");
  return p;
}

void EnsureDirectory(const std::string& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir))
    throw std::runtime_error("cannot create output folder " + Quoted(dir) + ": " +
                             (ec ? ec.message() : "not a folder"));
}

std::string TempFileName(const std::string& path) {
  const fs::path p(path);
  return (p.parent_path() /
          ("." + p.stem().string() + ".partial-" + ProcessTag() + p.extension().string()))
      .string();
}

void WriteImageAtomic(const std::string& path, const cv::Mat& image) {
  const std::string tmp = TempFileName(path);
  bool ok = false;
  try {
    ok = cv::imwrite(tmp, image);
  } catch (const cv::Exception&) {
    ok = false;
  }
  if (!ok) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw std::runtime_error("cannot write image " + Quoted(path));
  }
  Commit(tmp, path);
}

void WriteTextAtomic(const std::string& path, const std::string& text) {
  const std::string tmp = TempFileName(path);
  {
    std::ofstream out(tmp, std::ios::binary);
    out << text;
    out.flush();
    if (!out) {
      std::error_code ec;
      fs::remove(tmp, ec);
      throw std::runtime_error("cannot write " + Quoted(path));
    }
  }
  Commit(tmp, path);
}

cv::Mat ColorizeDepth(const cv::Mat& depth_m, double min_m, double max_m) {
  const cv::Mat known = depth_m > 0;
  if (min_m == 0 && max_m == 0 && cv::countNonZero(known) > 0)
    cv::minMaxLoc(depth_m, &min_m, &max_m, nullptr, nullptr, known);
  if (max_m <= min_m) max_m = min_m + 1e-3;
  cv::Mat scaled;
  // Near is hot (255), far is cold (0).
  depth_m.convertTo(scaled, CV_8U, -255.0 / (max_m - min_m), 255.0 * max_m / (max_m - min_m));
  cv::Mat color;
  cv::applyColorMap(scaled, color, cv::COLORMAP_TURBO);
  color.setTo(cv::Scalar(0, 0, 0), ~known);
  return color;
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace experiments
