#include "output.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <system_error>
#include <unistd.h>

namespace experiments {
namespace fs = std::filesystem;

namespace {
std::string TempName(const std::string& path) {
  const fs::path p(path);
  return (p.parent_path() / ("." + p.stem().string() + ".partial-" + std::to_string(getpid()) +
                             p.extension().string()))
      .string();
}
void Commit(const std::string& tmp, const std::string& path) {
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw std::runtime_error("cannot write '" + path + "': " + ec.message());
  }
}
}  // namespace

void EnsureDirectory(const std::string& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir))
    throw std::runtime_error("cannot create output folder '" + dir + "': " +
                             (ec ? ec.message() : "not a folder"));
}

void WriteImageAtomic(const std::string& path, const cv::Mat& image) {
  const std::string tmp = TempName(path);
  bool ok = false;
  try {
    ok = cv::imwrite(tmp, image);
  } catch (const cv::Exception& e) {
    ok = false;
  }
  if (!ok) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw std::runtime_error("cannot write image '" + path + "'");
  }
  Commit(tmp, path);
}

void WriteTextAtomic(const std::string& path, const std::string& text) {
  const std::string tmp = TempName(path);
  {
    std::ofstream out(tmp, std::ios::binary);
    out << text;
    out.flush();
    if (!out) {
      std::error_code ec;
      fs::remove(tmp, ec);
      throw std::runtime_error("cannot write '" + path + "'");
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
