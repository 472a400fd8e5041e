#include "experiments/calibration/calibration.h"

#include <glob.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

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

CalibrationResult CalibrateStereo(const std::vector<std::string>& left_files,
                                  const std::vector<std::string>& right_files, int cols, int rows,
                                  double square_m) {
  if (left_files.size() != right_files.size())
    throw UsageError("calibrate: " + std::to_string(left_files.size()) + " left images but " +
                     std::to_string(right_files.size()) + " right ones");
  if (cols < 2 || rows < 2 || !(square_m > 0))
    throw UsageError(
        "calibrate: --board needs at least 2x2 inner corners and --square a positive size");
  const cv::Size pattern(cols, rows);
  std::vector<cv::Point3f> board;
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c)
      board.emplace_back(float(c * square_m), float(r * square_m), 0.f);
  CalibrationResult result;
  std::vector<std::vector<cv::Point3f>> object;
  std::vector<std::vector<cv::Point2f>> left_points, right_points;
  cv::Size size;
  for (size_t i = 0; i < left_files.size(); ++i) {
    std::vector<cv::Point2f> corners[2];
    cv::Mat img[2];
    bool found = true;
    for (int s = 0; s < 2; ++s) {
      const std::string& file = s == 0 ? left_files[i] : right_files[i];
      rig::CheckInputFile(file, "calibrate: image");
      img[s] = cv::imread(file, cv::IMREAD_GRAYSCALE);
      if (img[s].empty())
        throw UsageError("calibrate: cannot read image '" + rig::ClipForMessage(file) + "'");
      if (size.empty()) size = img[s].size();
      if (img[s].size() != size)
        throw UsageError("calibrate: '" + rig::ClipForMessage(file) + "' is " +
                         std::to_string(img[s].cols) + "x" + std::to_string(img[s].rows) +
                         ", the first image is " + std::to_string(size.width) + "x" +
                         std::to_string(size.height));
      // The sector-based detector first (robust to noise, sub-pixel
      // accurate), the classic one with sub-pixel refinement as a fallback.
      if (!found) continue;
      if (!cv::findChessboardCornersSB(img[s], pattern, corners[s], cv::CALIB_CB_ACCURACY)) {
        found =
            cv::findChessboardCorners(img[s], pattern, corners[s],
                                      cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE);
        if (found)
          cv::cornerSubPix(
              img[s], corners[s], cv::Size(5, 5), cv::Size(-1, -1),
              cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 50, 1e-4));
      }
    }
    if (!found) {
      result.skipped.push_back(left_files[i]);
      continue;
    }
    // A board with more corners than --board says holds sub-patterns of the
    // stated size that the detectors find too (left and right may pick
    // different ones): the sector detector, allowed a larger board, reports
    // the size it sees.
    for (int s = 0; s < 2; ++s) {
      std::vector<cv::Point2f> all;
      cv::Mat meta;
      if (cv::findChessboardCornersSB(img[s], pattern, all, cv::CALIB_CB_LARGER, meta) &&
          meta.total() > static_cast<size_t>(cols) * rows) {
        const bool same_way = (cols >= rows) == (meta.cols >= meta.rows);
        const int seen_cols = same_way ? meta.cols : meta.rows,
                  seen_rows = same_way ? meta.rows : meta.cols;
        throw UsageError(
            "calibrate: '" + rig::ClipForMessage(s == 0 ? left_files[i] : right_files[i]) +
            "' shows a board of " + std::to_string(seen_cols) + "x" + std::to_string(seen_rows) +
            " inner corners, not the " + std::to_string(cols) + "x" + std::to_string(rows) +
            " of --board: count the inner corners again");
      }
    }
    object.push_back(board);
    left_points.push_back(corners[0]);
    right_points.push_back(corners[1]);
  }
  result.views = static_cast<int>(object.size());
  if (result.views < 3)
    throw UsageError("calibrate: the " + std::to_string(cols) + "x" + std::to_string(rows) +
                     " board was found in only " + std::to_string(result.views) +
                     " image pairs (need 3 or more)");
  cv::Mat k[2], dist[2];
  std::vector<cv::Mat> rvecs, tvecs;
  result.rms_left_px = cv::calibrateCamera(object, left_points, size, k[0], dist[0], rvecs, tvecs);
  result.rms_right_px =
      cv::calibrateCamera(object, right_points, size, k[1], dist[1], rvecs, tvecs);
  cv::Mat e, f;
  result.rms_stereo_px =
      cv::stereoCalibrate(object, left_points, right_points, k[0], dist[0], k[1], dist[1], size,
                          result.r_right_left, result.t_right_left, e, f, cv::CALIB_FIX_INTRINSIC);
  result.baseline_m = cv::norm(result.t_right_left);
  for (int s = 0; s < 2; ++s) {
    rig::CameraIntrinsics& ki = s == 0 ? result.calibration.left : result.calibration.right;
    ki.width_px = size.width;
    ki.height_px = size.height;
    ki.fx_px = k[s].at<double>(0, 0);
    ki.fy_px = k[s].at<double>(1, 1);
    ki.cx_px = k[s].at<double>(0, 2);
    ki.cy_px = k[s].at<double>(1, 2);
    ki.distortion.assign(dist[s].begin<double>(), dist[s].end<double>());
  }
  return result;
}

SyntheticTruth RenderChessboardViews(const std::string& dir, int views, double square_m,
                                     uint64_t seed) {
  EnsureDirectory(dir);
  // The board image: 10 x 7 squares (9 x 6 inner corners: one count even,
  // one odd, so that its orientation is unambiguous) with a one-square
  // white margin, 64 px a square; mapped once onto the board's front face.
  const int px = 64, squares_x = 10, squares_y = 7;
  cv::Mat board((squares_y + 2) * px, (squares_x + 2) * px, CV_8UC3, cv::Scalar(255, 255, 255));
  for (int r = 0; r < squares_y; ++r)
    for (int c = 0; c < squares_x; ++c)
      if ((r + c) % 2 == 0)
        cv::rectangle(board, cv::Rect((c + 1) * px, (r + 1) * px, px, px), cv::Scalar(0, 0, 0),
                      cv::FILLED);
  const fs::path scene_dir = fs::path(dir) / ".scenes";
  EnsureDirectory(scene_dir.string());
  cv::imwrite((scene_dir / "chessboard.png").string(), board);
  const double half_w = 0.5 * (squares_x + 2) * square_m, half_h = 0.5 * (squares_y + 2) * square_m;
  std::mt19937_64 rng(seed);
  auto uniform = [&](double a, double b) {
    return std::uniform_real_distribution<double>(a, b)(rng);
  };
  SyntheticTruth truth;
  sim::SimRigConfig config;
  config.noise.read_noise_sigma_dn = 2;  // as the experiments' cameras
  config.seed = seed;
  for (int v = 0; v < views; ++v) {
    char pose[256];
    std::snprintf(pose, sizeof pose, "pos=\"%.4f %.4f %.4f\" euler=\"%.2f %.2f %.2f\"",
                  uniform(-0.03, 0.03), uniform(0.85, 1.0), uniform(-0.02, 0.02), uniform(-25, 25),
                  uniform(-10, 10), uniform(-25, 25));
    const fs::path scene = scene_dir / ("view_" + std::to_string(v) + ".xml");
    std::ofstream(scene)
        << "<mujoco>\n  <include file=\"tavt.xml\"/>\n  <asset>\n"
        << "    <texture name=\"board\" type=\"2d\" file=\"chessboard.png\"/>\n"
        << "    <material name=\"board\" texture=\"board\" specular=\"0\" shininess=\"0\"/>\n"
        << "  </asset>\n  <worldbody>\n"
        << "    <light directional=\"true\" pos=\"0 0 3\" dir=\"0 1 -0.3\" diffuse=\"0.9 0.9 0.9\" "
           "specular=\"0 0 0\" castshadow=\"false\"/>\n"
        << "    <body " << pose << ">\n      <geom name=\"board\" type=\"box\" size=\"" << half_w
        << " " << half_h << " 0.002\" zaxis=\"0 -1 0\" material=\"board\"/>\n    </body>\n"
        << "  </worldbody>\n</mujoco>\n";
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
