#include "rig/calibration.h"

#include <cmath>
#include <opencv2/core.hpp>

#include "rig/input_file.h"

namespace rig {

namespace {

void WriteCamera(cv::FileStorage& fs, const char* name, const CameraIntrinsics& k,
                 const Eigen::Vector3d& offset) {
  fs << name << "{";
  fs << "width_px" << k.width_px << "height_px" << k.height_px;
  fs << "fx_px" << k.fx_px << "fy_px" << k.fy_px << "cx_px" << k.cx_px << "cy_px" << k.cy_px;
  fs << "distortion" << k.distortion;
  fs << "optical_centre_H_m" << std::vector<double>{offset.x(), offset.y(), offset.z()};
  fs << "}";
}

void ReadCamera(const cv::FileStorage& fs, const std::string& path, const char* name,
                CameraIntrinsics* k, Eigen::Vector3d* offset) {
  const cv::FileNode n = fs[name];
  auto fail = [&](const std::string& what) {
    throw InputError("calibration " + ClipForMessage(path) + ": " + name + ": " + what);
  };
  if (n.empty() || !n.isMap()) fail("missing");
  for (const char* key : {"width_px", "height_px", "fx_px", "fy_px", "cx_px", "cy_px"})
    if (n[key].empty() || (!n[key].isReal() && !n[key].isInt()))
      fail(std::string("missing number '") + key + "'");
  k->width_px = static_cast<int>(n["width_px"]);
  k->height_px = static_cast<int>(n["height_px"]);
  k->fx_px = static_cast<double>(n["fx_px"]);
  k->fy_px = static_cast<double>(n["fy_px"]);
  k->cx_px = static_cast<double>(n["cx_px"]);
  k->cy_px = static_cast<double>(n["cy_px"]);
  k->distortion.clear();
  if (!n["distortion"].empty()) n["distortion"] >> k->distortion;
  std::vector<double> o;
  if (!n["optical_centre_H_m"].empty()) n["optical_centre_H_m"] >> o;
  if (!o.empty() && o.size() != 3) fail("optical_centre_H_m needs 3 numbers");
  *offset = o.empty() ? Eigen::Vector3d::Zero() : Eigen::Vector3d(o[0], o[1], o[2]);
  if (!offset->allFinite()) fail("optical_centre_H_m holds a non-finite number");
  for (const double d : k->distortion)
    if (!std::isfinite(d)) fail("distortion holds a non-finite number");
  try {
    k->Check();
  } catch (const RigError& e) {
    fail(e.what());
  }
}

}  // namespace

RigCalibration LoadCalibration(const std::string& path) {
  const std::string text = ReadInputFile(path, "calibration");
  cv::FileStorage fs;
  try {
    fs.open(text, cv::FileStorage::READ | cv::FileStorage::MEMORY);
  } catch (const cv::Exception&) {
  }
  if (!fs.isOpened())
    throw InputError("calibration '" + ClipForMessage(path) + "' cannot be read (not OpenCV YAML)");
  RigCalibration c;
  ReadCamera(fs, path, "left", &c.left, &c.left_optical_centre_H);
  ReadCamera(fs, path, "right", &c.right, &c.right_optical_centre_H);
  return c;
}

void SaveCalibration(const std::string& path, const RigCalibration& c) {
  cv::FileStorage fs(path, cv::FileStorage::WRITE | cv::FileStorage::FORMAT_YAML);
  if (!fs.isOpened()) throw RigError("calibration " + path + ": cannot be written");
  WriteCamera(fs, "left", c.left, c.left_optical_centre_H);
  WriteCamera(fs, "right", c.right, c.right_optical_centre_H);
}

}  // namespace rig
