// Writing results: every file and every output folder appears whole or not at
// all, and nothing the program did not make is deleted or overwritten.
#pragma once

#include <opencv2/core.hpp>
#include <stdexcept>
#include <string>

#include "experiments/usage_error.h"

namespace experiments {

/// What a command may do with an output target that already holds something.
enum class ExistingOutput {
  kRefuse,   ///< refuse it: UsageError naming it
  kReplace,  ///< --force: replace it, if it is a folder this program wrote (it holds kOutputMarker)
};

/// A file in every output folder the program writes: --force replaces only
/// folders that hold it, so it never deletes what a user put there.
inline constexpr char kOutputMarker[] = ".fovea-output";

/// `path` as the target it names: lexically normal, no trailing separator
/// ("out/run/" is "out/run"). Throws UsageError naming `flag` for an empty
/// path and for ".", ".." or "/", which cannot be replaced by a folder.
std::string NormalizeOutputPath(const std::string& path, const std::string& flag);

/// The output-folder policy, checked before any work: `target` (normalized)
/// may be absent or an empty folder; a symbolic link, a file or a non-empty
/// folder is refused (UsageError naming `flag` and the target) unless
/// `existing` is kReplace and the target is a folder holding kOutputMarker.
void CheckOutputTarget(const std::string& target, const std::string& flag, ExistingOutput existing);

/// The sibling `.NAME.partial-HOST-PID` a folder `target` is built under by
/// this process (HOST: this machine's name, so that processes sharing a file
/// system across machines never take each other's for stale).
std::string StagingPath(const std::string& target);

/// Removes the staging folders of `target` left by processes of this host
/// that are gone (a run killed part-way).
void RemoveStaleStaging(const std::string& target);

/// One output folder, built under StagingPath and renamed into place by
/// Commit(): the target holds a whole result or what it held before. The
/// constructor normalizes and checks the target (CheckOutputTarget) and
/// creates nothing; path() creates the staging folder (and any missing
/// parents) on first use, after removing stale staging folders of the same
/// target. Without Commit(), the destructor removes what it created.
class OutputFolder {
 public:
  OutputFolder(const std::string& out, const std::string& flag, ExistingOutput existing);
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;
  ~OutputFolder();
  /// Where to write now: the staging folder.
  const std::string& path();
  /// The folder the result will be.
  const std::string& target() const { return target_; }
  /// Writes kOutputMarker and renames the staging folder into place
  /// (replacing the old target when allowed). Throws std::runtime_error.
  void Commit();

 private:
  std::string flag_, target_, staging_;
  ExistingOutput existing_;
  std::string first_created_;  ///< the outermost parent folder this object created, if any
  bool committed_ = false;
};

/// The policy for a command whose output is one file: `path` may be absent;
/// an existing file is refused (UsageError naming `flag`) unless `force`; a
/// folder or a link is always refused. Returns the normalized path.
std::string CheckOutputFile(const std::string& path, const std::string& flag, bool force);

/// Creates `dir` (and parents) if needed; throws std::runtime_error naming it.
void EnsureDirectory(const std::string& dir);

/// Writes an image (format from the extension) to a temporary name in the same
/// folder, then renames it into place.
void WriteImageAtomic(const std::string& path, const cv::Mat& image);

/// Same for text.
void WriteTextAtomic(const std::string& path, const std::string& text);

/// The temporary name a file `path` is written under before the rename:
/// `.STEM.partial-HOST-PID.EXT` in the same folder.
std::string TempFileName(const std::string& path);

/// A whole file's bytes; "" when it cannot be read.
std::string ReadFile(const std::string& path);

/// Depth in metres (CV_32FC1, 0 = unknown) colour-mapped (turbo, near = red)
/// over [min_m, max_m]; unknown pixels black. min_m = max_m = 0 picks the
/// range of the known pixels.
cv::Mat ColorizeDepth(const cv::Mat& depth_m, double min_m = 0, double max_m = 0);

}  // namespace experiments
