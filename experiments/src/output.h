// Writing results: every file appears whole or not at all.
#pragma once

#include <opencv2/core.hpp>
#include <stdexcept>
#include <string>

namespace experiments {

/// Thrown for bad command-line input; the CLI prints it and exits with 2.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Creates `dir` (and parents) if needed; throws std::runtime_error naming it.
void EnsureDirectory(const std::string& dir);

/// Writes an image (format from the extension) to a temporary name in the same
/// folder, then renames it into place.
void WriteImageAtomic(const std::string& path, const cv::Mat& image);

/// Same for text.
void WriteTextAtomic(const std::string& path, const std::string& text);

/// A whole file's bytes; "" when it cannot be read.
std::string ReadFile(const std::string& path);

/// Depth in metres (CV_32FC1, 0 = unknown) colour-mapped (turbo, near = red)
/// over [min_m, max_m]; unknown pixels black. min_m = max_m = 0 picks the
/// range of the known pixels.
cv::Mat ColorizeDepth(const cv::Mat& depth_m, double min_m = 0, double max_m = 0);

}  // namespace experiments
