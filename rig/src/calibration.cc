#include "rig/calibration.h"

#include <cmath>
#include <functional>
#include <opencv2/core.hpp>

#include "rig/input_file.h"

namespace rig {

namespace {

constexpr double kDeg = M_PI / 180;

void WriteCamera(cv::FileStorage& fs, const char* name, const CameraIntrinsics& k,
                 const HeadGeometry& head) {
  const Eigen::Vector3d& o = head.optical_centre_H;
  const Eigen::Vector3d rpy = head.mount_rpy_rad / kDeg;
  fs << name << "{";
  fs << "width_px" << k.width_px << "height_px" << k.height_px;
  fs << "fx_px" << k.fx_px << "fy_px" << k.fy_px << "cx_px" << k.cx_px << "cy_px" << k.cy_px;
  fs << "distortion" << k.distortion;
  fs << "optical_centre_H_m" << std::vector<double>{o.x(), o.y(), o.z()};
  fs << "mount_rpy_deg" << std::vector<double>{rpy.x(), rpy.y(), rpy.z()};
  fs << "pan_zero_deg" << head.pan_zero_rad / kDeg;
  fs << "tilt_zero_deg" << head.tilt_zero_rad / kDeg;
  fs << "}";
}

// A list of 3 finite numbers under `key`, or zeros if absent.
Eigen::Vector3d ReadVector3(const cv::FileNode& n, const char* key,
                            const std::function<void(const std::string&)>& fail) {
  if (n[key].empty()) return Eigen::Vector3d::Zero();
  std::vector<double> v;
  if (!n[key].isSeq()) fail(std::string(key) + " needs 3 numbers");
  n[key] >> v;
  if (v.size() != 3) fail(std::string(key) + " needs 3 numbers");
  const Eigen::Vector3d out(v[0], v[1], v[2]);
  if (!out.allFinite()) fail(std::string(key) + " holds a non-finite number");
  return out;
}

// A finite number under `key` (within +-limit), or 0 if absent.
double ReadAngle(const cv::FileNode& n, const char* key, double limit,
                 const std::function<void(const std::string&)>& fail) {
  if (n[key].empty()) return 0;
  if (!n[key].isReal() && !n[key].isInt()) fail(std::string("'") + key + "' is not a number");
  const double v = static_cast<double>(n[key]);
  if (!std::isfinite(v) || std::abs(v) > limit)
    fail(std::string("'") + key + "' must be within +-" + std::to_string(int(limit)) + " degrees");
  return v;
}

void ReadCamera(const cv::FileStorage& fs, const std::string& path, const char* name,
                CameraIntrinsics* k, HeadGeometry* head) {
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
  head->optical_centre_H = ReadVector3(n, "optical_centre_H_m", fail);
  const Eigen::Vector3d rpy = ReadVector3(n, "mount_rpy_deg", fail);
  if (rpy.cwiseAbs().maxCoeff() > 45) fail("mount_rpy_deg must be within +-45 degrees");
  head->mount_rpy_rad = rpy * kDeg;
  head->pan_zero_rad = ReadAngle(n, "pan_zero_deg", 45, fail) * kDeg;
  head->tilt_zero_rad = ReadAngle(n, "tilt_zero_deg", 45, fail) * kDeg;
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
  c.version = 1;
  if (!fs["version"].empty()) {
    if (!fs["version"].isInt())
      throw InputError("calibration " + ClipForMessage(path) + ": 'version' is not a whole number");
    c.version = static_cast<int>(fs["version"]);
    if (c.version < 1 || c.version > kCalibrationVersion)
      throw InputError("calibration " + ClipForMessage(path) + ": version " +
                       std::to_string(c.version) + " is not one this program reads (1 to " +
                       std::to_string(kCalibrationVersion) + ")");
  }
  ReadCamera(fs, path, "left", &c.left, &c.left_head);
  ReadCamera(fs, path, "right", &c.right, &c.right_head);
  return c;
}

RigGeometry RigCalibration::Geometry() const {
  RigGeometry g;
  g.left = left_head;
  g.right = right_head;
  g.left.rail_zero_W = g.right.rail_zero_W = Eigen::Vector3d::Zero();
  return g;
}

void CheckCalibrationSize(const RigCalibration& c, const std::string& path, int width_px,
                          int height_px) {
  for (const CameraIntrinsics* k : {&c.left, &c.right})
    if (k->width_px != width_px || k->height_px != height_px)
      throw InputError("calibration " + ClipForMessage(path) + " is for " +
                       std::to_string(k->width_px) + "x" + std::to_string(k->height_px) +
                       " images, rig.width_px x rig.height_px is " + std::to_string(width_px) +
                       "x" + std::to_string(height_px));
}

void SaveCalibration(const std::string& path, const RigCalibration& c) {
  cv::FileStorage fs(path, cv::FileStorage::WRITE | cv::FileStorage::FORMAT_YAML);
  if (!fs.isOpened()) throw RigError("calibration " + path + ": cannot be written");
  fs << "version" << kCalibrationVersion;
  WriteCamera(fs, "left", c.left, c.left_head);
  WriteCamera(fs, "right", c.right, c.right_head);
}

}  // namespace rig
