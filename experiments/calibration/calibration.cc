#include "experiments/calibration/calibration.h"

#include <glob.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <random>
#include <sstream>

#include "board.h"
#include "experiments/config/config.h"
#include "experiments/output/output.h"
#include "scenes/catalog.h"

namespace experiments {
namespace fs = std::filesystem;

std::vector<std::string> Glob(const std::string& pattern) {
  glob_t g{};
  std::vector<std::string> files;
  if (::glob(pattern.c_str(), 0, nullptr, &g) == 0)
    for (size_t i = 0; i < g.gl_pathc; ++i) files.emplace_back(g.gl_pathv[i]);
  globfree(&g);
  if (files.empty()) throw UsageError("no files match '" + rig::ClipForMessage(pattern) + "'");
  std::sort(files.begin(), files.end());
  return files;
}

namespace board {

// An image of a calibration set, grey, of the set's size (the first
// image's); throws UsageError naming the file.
cv::Mat ReadBoardImage(const std::string& file, cv::Size* size) {
  rig::CheckInputFile(file, "calibrate: image");
  const cv::Mat img = cv::imread(file, cv::IMREAD_GRAYSCALE);
  if (img.empty())
    throw UsageError("calibrate: cannot read image '" + rig::ClipForMessage(file) + "'");
  if (size->empty()) *size = img.size();
  if (img.size() != *size)
    throw UsageError("calibrate: '" + rig::ClipForMessage(file) + "' is " +
                     std::to_string(img.cols) + "x" + std::to_string(img.rows) +
                     ", the first image is " + std::to_string(size->width) + "x" +
                     std::to_string(size->height));
  return img;
}

// The board's inner corners: the sector-based detector first (robust to
// noise, sub-pixel accurate), the classic one with sub-pixel refinement as a
// fallback.
namespace {

// Mean grey level in the 5x5 window around p; nullopt unless the window
// lies inside the image.
std::optional<double> MeanAround(const cv::Mat& img, const cv::Point2f& p) {
  const cv::Rect window(int(std::lround(p.x)) - 2, int(std::lround(p.y)) - 2, 5, 5);
  if ((window & cv::Rect(0, 0, img.cols, img.rows)) != window) return std::nullopt;
  return cv::mean(img(window))[0];
}

// The detectors may return a board's corners from either end (the grid is
// symmetric under a half turn): when one count is odd and the other even,
// the squares at the two ends of the diagonal differ in colour, and the
// corners are put in the order that starts at the dark one, so that every
// view numbers the same physical corner alike. Judged at whichever end
// shows both its end square and that square's neighbour; false (board not
// usable) when neither does.
bool StartAtDarkCorner(const cv::Mat& img, const cv::Size& pattern,
                       std::vector<cv::Point2f>* corners) {
  if ((pattern.width + pattern.height) % 2 == 0) return true;
  const std::vector<cv::Point2f>& c = *corners;
  const int n = static_cast<int>(c.size());
  // At the first corner (end = 0) or the last (end = 1, stepping backwards).
  for (int end = 0; end < 2; ++end) {
    const int i = end == 0 ? 0 : n - 1, sign = end == 0 ? 1 : -1;
    const cv::Point2f along = c[i + sign] - c[i], down = c[i + sign * pattern.width] - c[i];
    const std::optional<double> outer = MeanAround(img, c[i] - 0.5f * along - 0.5f * down);
    const std::optional<double> beside = MeanAround(img, c[i] + 0.5f * along - 0.5f * down);
    if (!outer || !beside) continue;
    const bool dark_here = *outer < *beside;
    if (dark_here != (end == 0)) std::reverse(corners->begin(), corners->end());
    return true;
  }
  return false;
}

}  // namespace

bool FindBoard(const cv::Mat& img, const cv::Size& pattern, std::vector<cv::Point2f>* corners) {
  if (!cv::findChessboardCornersSB(img, pattern, *corners, cv::CALIB_CB_ACCURACY) &&
      !cv::findChessboardCorners(img, pattern, *corners,
                                 cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE))
    return false;
  // Either detector's corners, refined where the image's gradients meet:
  // the sector detector's own positions are biased on slanted boards by
  // hundredths of a pixel, consistently, which a head calibration's chain
  // turns into millimetres of depth. The window reaches 0.4 of the nearest
  // neighbouring corner's distance (never another corner), at most 11 px.
  double spacing = std::numeric_limits<double>::infinity();
  for (int r = 0; r < pattern.height; ++r)
    for (int c = 0; c < pattern.width; ++c) {
      const cv::Point2f& p = (*corners)[r * pattern.width + c];
      if (c + 1 < pattern.width)
        spacing = std::min(spacing, cv::norm(p - (*corners)[r * pattern.width + c + 1]));
      if (r + 1 < pattern.height)
        spacing = std::min(spacing, cv::norm(p - (*corners)[(r + 1) * pattern.width + c]));
    }
  const int half = std::clamp(static_cast<int>(0.4 * spacing), 2, 11);
  cv::cornerSubPix(img, *corners, cv::Size(half, half), cv::Size(-1, -1),
                   cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 50, 1e-4));
  return StartAtDarkCorner(img, pattern, corners);
}

// A board with more corners than --board says holds sub-patterns of the
// stated size that the detectors find too (left and right may pick different
// ones): the sector detector, allowed a larger board, reports the size it
// sees. Throws UsageError naming the file.
void CheckBoardSize(const cv::Mat& img, const cv::Size& pattern, const std::string& file) {
  std::vector<cv::Point2f> all;
  cv::Mat meta;
  if (!cv::findChessboardCornersSB(img, pattern, all, cv::CALIB_CB_LARGER, meta) ||
      meta.total() <= static_cast<size_t>(pattern.area()))
    return;
  const bool same_way = (pattern.width >= pattern.height) == (meta.cols >= meta.rows);
  const int seen_cols = same_way ? meta.cols : meta.rows,
            seen_rows = same_way ? meta.rows : meta.cols;
  throw UsageError("calibrate: '" + rig::ClipForMessage(file) + "' shows a board of " +
                   std::to_string(seen_cols) + "x" + std::to_string(seen_rows) +
                   " inner corners, not the " + std::to_string(pattern.width) + "x" +
                   std::to_string(pattern.height) + " of --board: count the inner corners again");
}

rig::CameraIntrinsics IntrinsicsOf(const cv::Mat& k, const cv::Mat& dist, const cv::Size& size) {
  rig::CameraIntrinsics ki;
  ki.width_px = size.width;
  ki.height_px = size.height;
  ki.fx_px = k.at<double>(0, 0);
  ki.fy_px = k.at<double>(1, 1);
  ki.cx_px = k.at<double>(0, 2);
  ki.cy_px = k.at<double>(1, 2);
  ki.distortion.assign(dist.begin<double>(), dist.end<double>());
  return ki;
}

std::vector<cv::Point3f> Corners(const char* command, int cols, int rows, double square_m) {
  if (cols < 2 || rows < 2 || !(square_m > 0))
    throw UsageError(std::string(command) +
                     ": --board needs at least 2x2 inner corners and --square a positive size");
  std::vector<cv::Point3f> board;
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c)
      board.emplace_back(float(c * square_m), float(r * square_m), 0.f);
  return board;
}

std::string PrepareSceneFolder(const std::string& dir) {
  EnsureDirectory(dir);
  const std::string scene_dir = (fs::path(dir) / ".scenes").string();
  EnsureDirectory(scene_dir);
  // The board image: 10 x 7 squares (9 x 6 inner corners: one count even,
  // one odd, so that its orientation is unambiguous) with a one-square
  // white margin, 64 px a square; mapped once onto the board's front face.
  const int px = 64;
  cv::Mat board((kSquaresY + 2) * px, (kSquaresX + 2) * px, CV_8UC3, cv::Scalar(255, 255, 255));
  for (int r = 0; r < kSquaresY; ++r)
    for (int c = 0; c < kSquaresX; ++c)
      if ((r + c) % 2 == 0)
        cv::rectangle(board, cv::Rect((c + 1) * px, (r + 1) * px, px, px), cv::Scalar(0, 0, 0),
                      cv::FILLED);
  WriteImageAtomic((fs::path(scene_dir) / "chessboard.png").string(), board);
  return scene_dir;
}

std::string SceneXml(const std::string& body_pose, double square_m) {
  const double half_w = 0.5 * (kSquaresX + 2) * square_m, half_h = 0.5 * (kSquaresY + 2) * square_m;
  std::ostringstream x;
  x << "<mujoco>\n  <include file=\"tavt.xml\"/>\n  <asset>\n"
    << "    <texture name=\"board\" type=\"2d\" file=\"chessboard.png\"/>\n"
    << "    <material name=\"board\" texture=\"board\" specular=\"0\" shininess=\"0\"/>\n"
    << "  </asset>\n  <worldbody>\n"
    << "    <light directional=\"true\" pos=\"0 0 3\" dir=\"0 1 -0.3\" diffuse=\"0.9 0.9 0.9\" "
       "specular=\"0 0 0\" castshadow=\"false\"/>\n"
    << "    <body " << body_pose << ">\n      <geom name=\"board\" type=\"box\" size=\"" << half_w
    << " " << half_h << " 0.002\" zaxis=\"0 -1 0\" material=\"board\"/>\n    </body>\n"
    << "  </worldbody>\n</mujoco>\n";
  return x.str();
}

}  // namespace board

using board::CheckBoardSize;
using board::FindBoard;
using board::IntrinsicsOf;
using board::ReadBoardImage;

CalibrationResult CalibrateStereo(const std::vector<std::string>& left_files,
                                  const std::vector<std::string>& right_files, int cols, int rows,
                                  double square_m) {
  if (left_files.size() != right_files.size())
    throw UsageError("calibrate: " + std::to_string(left_files.size()) + " left images but " +
                     std::to_string(right_files.size()) + " right ones");
  const std::vector<cv::Point3f> board = board::Corners("calibrate", cols, rows, square_m);
  const cv::Size pattern(cols, rows);
  CalibrationResult result;
  std::vector<std::vector<cv::Point3f>> object;
  std::vector<std::vector<cv::Point2f>> points[2];
  cv::Size size;
  for (size_t i = 0; i < left_files.size(); ++i) {
    const std::string* files[2] = {&left_files[i], &right_files[i]};
    std::vector<cv::Point2f> corners[2];
    cv::Mat img[2];
    bool found = true;
    for (int s = 0; s < 2; ++s) {
      img[s] = ReadBoardImage(*files[s], &size);
      found = found && FindBoard(img[s], pattern, &corners[s]);
    }
    if (!found) {
      result.skipped.push_back(left_files[i]);
      continue;
    }
    for (int s = 0; s < 2; ++s) CheckBoardSize(img[s], pattern, *files[s]);
    object.push_back(board);
    for (int s = 0; s < 2; ++s) points[s].push_back(corners[s]);
  }
  result.views = static_cast<int>(object.size());
  if (result.views < 3)
    throw UsageError("calibrate: the " + std::to_string(cols) + "x" + std::to_string(rows) +
                     " board was found in only " + std::to_string(result.views) +
                     " image pairs (need 3 or more)");
  cv::Mat k[2], dist[2];
  std::vector<cv::Mat> rvecs, tvecs;
  result.rms_left_px = cv::calibrateCamera(object, points[0], size, k[0], dist[0], rvecs, tvecs);
  result.rms_right_px = cv::calibrateCamera(object, points[1], size, k[1], dist[1], rvecs, tvecs);
  cv::Mat e, f;
  result.rms_stereo_px =
      cv::stereoCalibrate(object, points[0], points[1], k[0], dist[0], k[1], dist[1], size,
                          result.r_right_left, result.t_right_left, e, f, cv::CALIB_FIX_INTRINSIC);
  result.baseline_m = cv::norm(result.t_right_left);
  result.calibration.left = IntrinsicsOf(k[0], dist[0], size);
  result.calibration.right = IntrinsicsOf(k[1], dist[1], size);
  return result;
}

SyntheticTruth RenderChessboardViews(const std::string& dir, int views, double square_m,
                                     uint64_t seed) {
  const fs::path scene_dir = board::PrepareSceneFolder(dir);
  std::mt19937_64 rng(seed);
  auto uniform = [&](double a, double b) {
    return std::uniform_real_distribution<double>(a, b)(rng);
  };
  SyntheticTruth truth;
  sim::SimRigConfig config;
  config.noise.read_noise_sigma_dn = kExperimentNoiseSigmaDn;
  config.seed = seed;
  for (int v = 0; v < views; ++v) {
    char pose[256];
    std::snprintf(pose, sizeof pose, "pos=\"%.4f %.4f %.4f\" euler=\"%.2f %.2f %.2f\"",
                  uniform(-0.03, 0.03), uniform(0.85, 1.0), uniform(-0.02, 0.02), uniform(-25, 25),
                  uniform(-10, 10), uniform(-25, 25));
    const fs::path scene = scene_dir / ("view_" + std::to_string(v) + ".xml");
    std::ofstream(scene) << board::SceneXml(pose, square_m);
    auto sim = scenes::LoadScene(scene.string(), config);
    rig::Rig& rig = sim->rig();
    const rig::StereoFrame frame = rig.Capture();
    char name[64];
    std::snprintf(name, sizeof name, "/left_%02d.png", v);
    WriteImageAtomic(dir + name, frame.left.gray);
    std::snprintf(name, sizeof name, "/right_%02d.png", v);
    WriteImageAtomic(dir + name, frame.right.gray);
    if (v == 0) {
      const rig::CameraIntrinsics& k = frame.left.intrinsics;
      truth = {k.fx_px, k.fy_px, k.cx_px, k.cy_px,
               (frame.right.world_T_camera.translation() - frame.left.world_T_camera.translation())
                   .norm()};
    }
  }
  fs::remove_all(scene_dir);
  return truth;
}

}  // namespace experiments
