// The chessboard both calibrations use: finding it in an image, checking
// its size, and the simulator scene that shows it (internal to calibration/).
#pragma once

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "rig/types.h"

namespace experiments::board {

/// Squares of the rendered board (9 x 6 inner corners).
inline constexpr int kSquaresX = 10, kSquaresY = 7;

/// An image of a calibration set, grey, of the set's size (the first
/// image's, stored in *size when empty); throws UsageError naming the file.
cv::Mat ReadBoardImage(const std::string& file, cv::Size* size);
/// The board's inner corners, sub-pixel; false if not found.
bool FindBoard(const cv::Mat& img, const cv::Size& pattern, std::vector<cv::Point2f>* corners);
/// Throws UsageError naming the file if it shows a larger board than `pattern`.
void CheckBoardSize(const cv::Mat& img, const cv::Size& pattern, const std::string& file);
rig::CameraIntrinsics IntrinsicsOf(const cv::Mat& k, const cv::Mat& dist, const cv::Size& size);
/// Board coordinates of the inner corners, row by row, metres (z = 0).
/// Throws UsageError, prefixed by `command`, unless the board has at least
/// 2x2 inner corners and a positive square.
std::vector<cv::Point3f> Corners(const char* command, int cols, int rows, double square_m);
/// Creates `dir` and a scene folder inside it holding the board's texture
/// (chessboard.png, for SceneXml); returns the scene folder's path, which
/// the caller removes when done.
std::string PrepareSceneFolder(const std::string& dir);
/// MJCF of a scene with the rig and the board (texture "chessboard.png"
/// beside it) on a body with `body_pose` (MJCF attributes); the board faces
/// -y of that body's frame... its front face looks along the body's -y.
std::string SceneXml(const std::string& body_pose, double square_m);

}  // namespace experiments::board
