#include "experiments/calibration/head_calibration.h"

#include <yaml-cpp/yaml.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <optional>
#include <random>
#include <set>
#include <sstream>

#include "board.h"
#include "experiments/output/output.h"
#include "experiments/usage_error.h"
#include "fovea/geometry.h"
#include "fovea/stats.h"
#include "rig/input_file.h"
#include "scenes/catalog.h"
#include "sim/simulation.h"

namespace experiments {
namespace fs = std::filesystem;

namespace {

constexpr double kDeg = M_PI / 180;

Eigen::Matrix3d Exp(const Eigen::Vector3d& w) {
  const double a = w.norm();
  if (a < 1e-300) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(a, w / a).toRotationMatrix();
}

Eigen::Isometry3d FromRvecTvec(const cv::Mat& rvec, const cv::Mat& tvec) {
  cv::Mat r;
  cv::Rodrigues(rvec, r);
  Eigen::Matrix3d R;
  cv::cv2eigen(r, R);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R;
  T.translation() = Eigen::Vector3d(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2));
  return T;
}

// The tilt frame at the readings (what hand-eye calls the gripper): the
// rig's kinematics with a pan zero, no tilt zero (the mount carries it), the
// rail zero at the origin.
Eigen::Isometry3d WorldFromTilt(const rig::CameraStage& s, double pan_zero_rad) {
  rig::RigGeometry g;
  g.left.pan_zero_rad = pan_zero_rad;
  return g.WorldFromHead(rig::Side::kLeft, s);
}

// The joint model: per camera 16 parameters, per board placement 6.
constexpr int kPerCamera = 16;
constexpr int kPerBoard = 6;
enum CameraParam {
  kFx,
  kFy,
  kCx,
  kCy,
  kK1,
  kK2,
  kP1,
  kP2,
  kK3,
  kMountX,
  kMountY,
  kMountZ,
  kCentreX,
  kCentreY,
  kCentreZ,
  kPanZero
};
const char* const kParamName[kPerCamera] = {"fx",
                                            "fy",
                                            "cx",
                                            "cy",
                                            "k1",
                                            "k2",
                                            "p1",
                                            "p2",
                                            "k3",
                                            "mount rotation (x)",
                                            "mount rotation (y)",
                                            "mount rotation (z)",
                                            "optical centre (x)",
                                            "optical centre (y)",
                                            "optical centre (z)",
                                            "pan zero"};

struct Observation {
  int view, side;
  std::vector<cv::Point2f> corners;
};

struct Model {
  const std::vector<HeadView>* views;
  const std::vector<cv::Point3f>* board;
  std::vector<Observation> observations;
  std::array<Eigen::Matrix3d, 2> mount0;  // start rotations: head_R_camera = mount0 * Exp(w)
  std::vector<Eigen::Matrix3d> board0;    // start rotations of the placements
  int placements = 0;

  int Size() const { return 2 * kPerCamera + kPerBoard * placements; }
  int Residuals() const {
    int n = 0;
    for (const Observation& o : observations) n += 2 * static_cast<int>(o.corners.size());
    return n;
  }

  rig::CameraIntrinsics Intrinsics(const Eigen::VectorXd& x, int side) const {
    const double* c = x.data() + side * kPerCamera;
    rig::CameraIntrinsics k;
    k.fx_px = c[kFx];
    k.fy_px = c[kFy];
    k.cx_px = c[kCx];
    k.cy_px = c[kCy];
    k.distortion = {c[kK1], c[kK2], c[kP1], c[kP2], c[kK3]};
    return k;
  }
  Eigen::Isometry3d HeadFromCamera(const Eigen::VectorXd& x, int side) const {
    const double* c = x.data() + side * kPerCamera;
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = mount0[side] * Exp({c[kMountX], c[kMountY], c[kMountZ]});
    T.translation() = Eigen::Vector3d(c[kCentreX], c[kCentreY], c[kCentreZ]);
    return T;
  }
  Eigen::Isometry3d WorldFromBoard(const Eigen::VectorXd& x, int placement) const {
    const double* b = x.data() + 2 * kPerCamera + kPerBoard * placement;
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = board0[placement] * Exp({b[0], b[1], b[2]});
    T.translation() = Eigen::Vector3d(b[3], b[4], b[5]);
    return T;
  }

  // Reprojection residuals (predicted - measured), px.
  Eigen::VectorXd Evaluate(const Eigen::VectorXd& x) const {
    Eigen::VectorXd r(Residuals());
    int i = 0;
    const std::array<rig::CameraIntrinsics, 2> k = {Intrinsics(x, 0), Intrinsics(x, 1)};
    const std::array<Eigen::Isometry3d, 2> head_T_camera = {HeadFromCamera(x, 0),
                                                            HeadFromCamera(x, 1)};
    for (const Observation& o : observations) {
      const HeadView& v = (*views)[o.view];
      const double pan_zero = x[o.side * kPerCamera + kPanZero];
      const Eigen::Isometry3d camera_T_board =
          (WorldFromTilt(v.state[static_cast<rig::Side>(o.side)], pan_zero) * head_T_camera[o.side])
              .inverse() *
          WorldFromBoard(x, v.placement);
      for (size_t j = 0; j < o.corners.size(); ++j) {
        const cv::Point3f& X = (*board)[j];
        const Eigen::Vector3d p_C = camera_T_board * Eigen::Vector3d(X.x, X.y, X.z);
        const Eigen::Vector2d uv =
            p_C.z() > 1e-6 ? k[o.side].Project(p_C) : Eigen::Vector2d(1e6, 1e6);
        r[i++] = uv.x() - o.corners[j].x;
        r[i++] = uv.y() - o.corners[j].y;
      }
    }
    return r;
  }

  // Central differences, each parameter at its own scale; the columns of
  // the parameters in `free` (all when empty), in their order.
  Eigen::MatrixXd Jacobian(const Eigen::VectorXd& x, const std::vector<int>& free = {}) const {
    std::vector<int> params = free;
    if (params.empty())
      for (int p = 0; p < Size(); ++p) params.push_back(p);
    Eigen::MatrixXd J(Residuals(), params.size());
    for (size_t col = 0; col < params.size(); ++col) {
      const int p = params[col];
      const int c = p < 2 * kPerCamera ? p % kPerCamera : -1;
      const double h = c >= 0 && c <= kCy ? 1e-4 : 1e-7;
      Eigen::VectorXd plus = x, minus = x;
      plus[p] += h;
      minus[p] -= h;
      J.col(col) = (Evaluate(plus) - Evaluate(minus)) / (2 * h);
    }
    return J;
  }
};

// Levenberg-Marquardt (Marquardt's diagonal scaling) over the parameters in
// `free`, the others held; returns the solution.
Eigen::VectorXd Refine(const Model& model, Eigen::VectorXd x, const std::vector<int>& free) {
  Eigen::VectorXd r = model.Evaluate(x);
  double cost = r.squaredNorm();
  double lambda = 1e-3;
  for (int it = 0; it < 100; ++it) {
    const Eigen::MatrixXd J = model.Jacobian(x, free);
    const Eigen::MatrixXd JtJ = J.transpose() * J;
    const Eigen::VectorXd g = J.transpose() * r;
    bool improved = false;
    for (int tries = 0; tries < 12 && !improved; ++tries) {
      Eigen::MatrixXd A = JtJ;
      A.diagonal() += lambda * JtJ.diagonal().cwiseMax(1e-12);
      const Eigen::VectorXd step = A.ldlt().solve(-g);
      Eigen::VectorXd trial = x;
      for (size_t i = 0; i < free.size(); ++i) trial[free[i]] += step[i];
      const Eigen::VectorXd r_trial = model.Evaluate(trial);
      const double c = r_trial.squaredNorm();
      if (std::isfinite(c) && c < cost) {
        const double gain = (cost - c) / cost;
        x = trial;
        r = r_trial;
        cost = c;
        lambda = std::max(lambda / 3, 1e-12);
        improved = true;
        if (gain < 1e-12) return x;
      } else {
        lambda *= 8;
      }
    }
    if (!improved) break;
  }
  return x;
}

std::string Short(double v) {
  char t[32];
  std::snprintf(t, sizeof t, "%.3g", v);
  return t;
}

std::string Degrees(double rad) { return Short(rad / kDeg); }

}  // namespace

std::vector<HeadView> LoadHeadViews(const std::string& path, bool images) {
  const std::string text = rig::ReadInputFile(path, "views file");
  const fs::path folder = fs::path(path).parent_path();
  auto fail = [&](const std::string& what) {
    throw UsageError("views file '" + rig::ClipForMessage(path) + "': " + what);
  };
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    fail("not YAML (" + std::string(e.what()) + ")");
  }
  if (!root.IsMap() || !root["views"] || !root["views"].IsSequence()) fail("needs a list 'views'");
  std::vector<HeadView> views;
  for (size_t i = 0; i < root["views"].size(); ++i) {
    const YAML::Node n = root["views"][i];
    const std::string where = "view " + std::to_string(i) + ": ";
    if (!n.IsMap()) fail(where + "is not a map");
    HeadView v;
    try {
      for (const char* key : {"left", "right", "state"})
        if (!n[key] && (images || std::string(key) == "state")) fail(where + "lacks '" + key + "'");
      if (n["left"]) v.left = (folder / n["left"].as<std::string>()).string();
      if (n["right"]) v.right = (folder / n["right"].as<std::string>()).string();
      v.placement = n["placement"] ? n["placement"].as<int>() : 0;
      const std::vector<double> s = n["state"].as<std::vector<double>>();
      if (s.size() != rig::kNumAxes) fail(where + "'state' needs 6 numbers");
      std::array<double, rig::kNumAxes> a{};
      for (int k = 0; k < rig::kNumAxes; ++k) {
        if (!std::isfinite(s[k])) fail(where + "'state' holds a non-finite number");
        a[k] = s[k];
      }
      v.state = rig::StageState::FromArray(a);
    } catch (const YAML::Exception& e) {
      fail(where + "bad entry (" + std::string(e.what()) + ")");
    }
    if (v.placement < 0 || v.placement > 99) fail(where + "'placement' must be 0 to 99");
    views.push_back(v);
  }
  if (views.empty()) fail("lists no views");
  return views;
}

void SaveHeadViews(const std::string& path, const std::vector<HeadView>& views) {
  YAML::Emitter out;
  out << YAML::Comment(
      "fovea head-calibration views: stage readings (metres, radians: left carriage, pan, tilt, "
      "right carriage, pan, tilt) per image pair");
  out << YAML::BeginMap << YAML::Key << "views" << YAML::Value << YAML::BeginSeq;
  for (const HeadView& v : views) {
    out << YAML::BeginMap << YAML::Key << "left" << YAML::Value << v.left << YAML::Key << "right"
        << YAML::Value << v.right << YAML::Key << "placement" << YAML::Value << v.placement;
    out << YAML::Key << "state" << YAML::Value << YAML::Flow << YAML::BeginSeq;
    for (const double a : v.state.ToArray()) out << a;
    out << YAML::EndSeq << YAML::EndMap;
  }
  out << YAML::EndSeq << YAML::EndMap;
  WriteTextAtomic(path, std::string(out.c_str()) + "\n");
}

namespace {

// Throws UsageError unless side `s`'s stage readings over `used` views can
// determine the head model: 6 distinct states, pan and tilt spanning 5 deg,
// the carriage 0.05 m.
void CheckStageSpread(const std::vector<HeadView>& views, const std::vector<int>& used, int s) {
  const std::string side = s == 0 ? "left" : "right";
  double pan_lo = 1e9, pan_hi = -1e9, tilt_lo = 1e9, tilt_hi = -1e9, car_lo = 1e9, car_hi = -1e9;
  std::set<std::array<long long, 3>> states;
  for (const int v : used) {
    const rig::CameraStage& st = views[v].state[static_cast<rig::Side>(s)];
    pan_lo = std::min(pan_lo, st.pan_rad), pan_hi = std::max(pan_hi, st.pan_rad);
    tilt_lo = std::min(tilt_lo, st.tilt_rad), tilt_hi = std::max(tilt_hi, st.tilt_rad);
    car_lo = std::min(car_lo, st.carriage_m), car_hi = std::max(car_hi, st.carriage_m);
    states.insert({std::llround(st.carriage_m * 1e5), std::llround(st.pan_rad * 1e5),
                   std::llround(st.tilt_rad * 1e5)});
  }
  if (states.size() < 6)
    throw UsageError("calibrate-head: the " + side + " head was seen at only " +
                     std::to_string(states.size()) +
                     " distinct stage states (the head model needs 6 or more)");
  if (pan_hi - pan_lo < 5 * kDeg || tilt_hi - tilt_lo < 5 * kDeg)
    throw UsageError("calibrate-head: cannot determine the " + side +
                     " camera's mount: its pan readings span " + Degrees(pan_hi - pan_lo) +
                     " deg and its tilt readings " + Degrees(tilt_hi - tilt_lo) +
                     " deg; both must span 5 deg or more");
  if (car_hi - car_lo < 0.05)
    throw UsageError("calibrate-head: cannot determine the " + side +
                     " pan zero: its carriage readings span " + Short(car_hi - car_lo) +
                     " m; vary the carriages by 0.05 m or more");
}

}  // namespace

HeadCalibrationResult CalibrateHead(const std::vector<HeadView>& views, int cols, int rows,
                                    double square_m) {
  const std::vector<cv::Point3f> board = board::Corners("calibrate-head", cols, rows, square_m);
  const cv::Size pattern(cols, rows);
  HeadCalibrationResult result;
  Model model;
  model.views = &views;
  model.board = &board;
  // Readings that cannot determine the model fail before any image is read
  // (finding the boards is the slow part); the same check runs again below
  // on the views whose boards were found. Too few views are said as too few
  // boards found, below.
  constexpr size_t kMinViews = 8;
  std::vector<int> all(views.size());
  std::iota(all.begin(), all.end(), 0);
  if (views.size() >= kMinViews)
    for (int s = 0; s < 2; ++s) CheckStageSpread(views, all, s);
  cv::Size size;
  std::set<int> placements;
  for (size_t i = 0; i < views.size(); ++i) {
    for (int s = 0; s < 2; ++s) {
      const std::string& file = s == 0 ? views[i].left : views[i].right;
      const cv::Mat img = board::ReadBoardImage(file, &size);
      Observation o{static_cast<int>(i), s, {}};
      if (!board::FindBoard(img, pattern, &o.corners)) {
        result.skipped.push_back(file);
        continue;
      }
      board::CheckBoardSize(img, pattern, file);
      model.observations.push_back(std::move(o));
      ++result.views[s];
      placements.insert(views[i].placement);
    }
  }

  // What the head model needs of the data, said before any fitting.
  for (int s = 0; s < 2; ++s) {
    if (result.views[s] < static_cast<int>(kMinViews))
      throw UsageError("calibrate-head: the " + std::to_string(cols) + "x" + std::to_string(rows) +
                       " board was found in only " + std::to_string(result.views[s]) + " " +
                       (s == 0 ? "left" : "right") + " images (need " + std::to_string(kMinViews) +
                       " or more)");
    std::vector<int> seen;  // the views whose image of side s showed the board
    for (const Observation& o : model.observations)
      if (o.side == s) seen.push_back(o.view);
    CheckStageSpread(views, seen, s);
  }
  model.placements = *placements.rbegin() + 1;
  result.placements = static_cast<int>(placements.size());
  if (result.placements != model.placements)
    throw UsageError("calibrate-head: board placements must be numbered 0 to " +
                     std::to_string(result.placements - 1) + " with each seen");

  // Start: each camera alone (OpenCV), then hand-eye on the placement seen
  // most, then the placements' poses from the left camera's first view.
  Eigen::VectorXd x = Eigen::VectorXd::Zero(model.Size());
  std::array<std::vector<Eigen::Isometry3d>, 2> camera_T_board;  // per observation of the side
  std::array<std::vector<int>, 2> observation_of;
  for (int s = 0; s < 2; ++s) {
    std::vector<std::vector<cv::Point3f>> object;
    std::vector<std::vector<cv::Point2f>> image;
    for (size_t i = 0; i < model.observations.size(); ++i)
      if (model.observations[i].side == s) {
        object.push_back(board);
        image.push_back(model.observations[i].corners);
        observation_of[s].push_back(static_cast<int>(i));
      }
    cv::Mat K, dist;
    std::vector<cv::Mat> rvecs, tvecs;
    // k3 held at 0: a 30-degree lens needs k1 and k2, and boards that stay
    // clear of the image's corners cannot tell k3 from the focal length.
    result.rms_intrinsics_px[s] =
        cv::calibrateCamera(object, image, size, K, dist, rvecs, tvecs, cv::CALIB_FIX_K3);
    double* c = x.data() + s * kPerCamera;
    c[kFx] = K.at<double>(0, 0), c[kFy] = K.at<double>(1, 1);
    c[kCx] = K.at<double>(0, 2), c[kCy] = K.at<double>(1, 2);
    for (int d = 0; d < 5; ++d) c[kK1 + d] = dist.at<double>(d);
    for (size_t i = 0; i < rvecs.size(); ++i)
      camera_T_board[s].push_back(FromRvecTvec(rvecs[i], tvecs[i]));
  }
  std::map<int, int> seen;
  for (const Observation& o : model.observations) ++seen[views[o.view].placement];
  const int main_placement = std::max_element(seen.begin(), seen.end(), [](auto& a, auto& b) {
                               return a.second < b.second;
                             })->first;
  std::array<Eigen::Isometry3d, 2> head_T_camera;
  for (int s = 0; s < 2; ++s) {
    std::vector<cv::Mat> R_g2b, t_g2b, R_t2c, t_t2c;
    for (size_t i = 0; i < observation_of[s].size(); ++i) {
      const Observation& o = model.observations[observation_of[s][i]];
      if (views[o.view].placement != main_placement) continue;
      const Eigen::Isometry3d g = WorldFromTilt(views[o.view].state[static_cast<rig::Side>(s)], 0);
      // Four matrices of their own: cv::Mat copies share their pixels.
      cv::Mat Rg, tg, Rt, tt;
      cv::eigen2cv(Eigen::Matrix3d(g.linear()), Rg);
      cv::eigen2cv(Eigen::Vector3d(g.translation()), tg);
      cv::eigen2cv(Eigen::Matrix3d(camera_T_board[s][i].linear()), Rt);
      cv::eigen2cv(Eigen::Vector3d(camera_T_board[s][i].translation()), tt);
      R_g2b.push_back(Rg);
      t_g2b.push_back(tg);
      R_t2c.push_back(Rt);
      t_t2c.push_back(tt);
    }
    if (R_g2b.size() < 3)
      throw UsageError("calibrate-head: the " + std::string(s == 0 ? "left" : "right") +
                       " camera saw board placement " + std::to_string(main_placement) +
                       " in fewer than 3 views (hand-eye needs 3 or more)");
    cv::Mat R_c2g, t_c2g;
    cv::calibrateHandEye(R_g2b, t_g2b, R_t2c, t_t2c, R_c2g, t_c2g, cv::CALIB_HAND_EYE_TSAI);
    Eigen::Matrix3d R;
    Eigen::Vector3d t;
    cv::cv2eigen(R_c2g, R);
    cv::cv2eigen(t_c2g, t);
    head_T_camera[s].setIdentity();
    head_T_camera[s].linear() = R;
    head_T_camera[s].translation() = t;
    model.mount0[s] = R;
    x.segment<3>(s * kPerCamera + kCentreX) = t;
  }
  model.board0.resize(model.placements);
  for (int p = 0; p < model.placements; ++p) {
    for (int s = 0; s < 2; ++s) {
      auto it = std::find_if(observation_of[s].begin(), observation_of[s].end(), [&](int i) {
        return views[model.observations[i].view].placement == p;
      });
      if (it == observation_of[s].end()) continue;
      const Observation& o = model.observations[*it];
      const Eigen::Isometry3d w_T_b =
          WorldFromTilt(views[o.view].state[static_cast<rig::Side>(s)], 0) * head_T_camera[s] *
          camera_T_board[s][it - observation_of[s].begin()];
      model.board0[p] = w_T_b.linear();
      x.segment<3>(2 * kPerCamera + kPerBoard * p + 3) = w_T_b.translation();
      break;
    }
  }

  // Extrinsics first (the camera's own intrinsics are good to start from
  // and a far-off chain would bend them), then the pan zeros, then all.
  std::vector<int> free;
  for (int p = 2 * kPerCamera; p < model.Size(); ++p) free.push_back(p);
  for (int s = 0; s < 2; ++s)
    for (int p = kMountX; p <= kCentreZ; ++p) free.push_back(s * kPerCamera + p);
  x = Refine(model, x, free);
  for (int s = 0; s < 2; ++s) free.push_back(s * kPerCamera + kPanZero);
  x = Refine(model, x, free);
  free.clear();
  for (int p = 0; p < model.Size(); ++p)
    if (p >= 2 * kPerCamera || p % kPerCamera != kK3) free.push_back(p);
  x = Refine(model, x, free);
  const Eigen::VectorXd r = model.Evaluate(x);
  result.rms_px = std::sqrt(r.squaredNorm() / (r.size() / 2));
  // Spread of each estimate: sigma^2 (J^T J)^-1. A parameter the views do
  // not pin down has a spread no calibration could use.
  const Eigen::MatrixXd J = model.Jacobian(x, free);
  const double sigma2 = r.squaredNorm() / std::max<double>(1, r.size() - free.size());
  const Eigen::MatrixXd cov =
      sigma2 * (J.transpose() * J).completeOrthogonalDecomposition().pseudoInverse();
  auto sd = [&](int s, int p) {
    const int col =
        static_cast<int>(std::find(free.begin(), free.end(), s * kPerCamera + p) - free.begin());
    return std::sqrt(std::max(0.0, cov(col, col)));
  };
  for (int s = 0; s < 2; ++s) {
    result.focal_sd_px[s] = std::max(sd(s, kFx), sd(s, kFy));
    result.mount_sd_deg[s] = std::max({sd(s, kMountX), sd(s, kMountY), sd(s, kMountZ)}) / kDeg;
    result.centre_sd_m[s] = std::max({sd(s, kCentreX), sd(s, kCentreY), sd(s, kCentreZ)});
    result.pan_zero_sd_deg[s] = sd(s, kPanZero) / kDeg;
    const char* side = s == 0 ? "left" : "right";
    struct Limit {
      int param;
      double max;
      const char* unit;
      double scale;
      const char* vary;
    };
    for (const Limit& l :
         {Limit{kFx, 0.002 * x[s * kPerCamera + kFx], "px", 1,
                "show the board across more of the image"},
          Limit{kMountX, 0.1 * kDeg, "deg", 1 / kDeg, "vary pan and tilt more"},
          Limit{kMountY, 0.1 * kDeg, "deg", 1 / kDeg, "vary pan and tilt more"},
          Limit{kMountZ, 0.1 * kDeg, "deg", 1 / kDeg, "vary pan and tilt more"},
          Limit{kCentreX, 0.003, "m", 1, "vary pan and tilt more"},
          Limit{kCentreY, 0.003, "m", 1, "vary pan and tilt more"},
          Limit{kCentreZ, 0.003, "m", 1, "vary pan and tilt more"},
          Limit{kPanZero, 0.05 * kDeg, "deg", 1 / kDeg, "vary the carriages and tilts more"}}) {
      const double spread = sd(s, l.param);
      if (!(spread <= l.max)) {
        char text[64];
        std::snprintf(text, sizeof text, "%.3g", spread * l.scale);
        throw UsageError(std::string("calibrate-head: the views cannot determine the ") + side +
                         " camera's " + kParamName[l.param] + " (one standard deviation " + text +
                         " " + l.unit + ", reprojection RMS " + Short(result.rms_px) +
                         " px): " + l.vary);
      }
    }
  }

  // The calibration: the tilt zero folded into the mount (it is 0 here).
  result.calibration = {};
  for (int s = 0; s < 2; ++s) {
    rig::CameraIntrinsics k = model.Intrinsics(x, s);
    k.width_px = size.width;
    k.height_px = size.height;
    rig::HeadGeometry head;
    const Eigen::Isometry3d h = model.HeadFromCamera(x, s);
    head.optical_centre_H = h.translation();
    head.mount_rpy_rad =
        rig::MountRpyFromRotation(h.linear() * rig::HeadFromCameraRotation().transpose());
    head.pan_zero_rad = x[s * kPerCamera + kPanZero];
    (s == 0 ? result.calibration.left : result.calibration.right) = k;
    (s == 0 ? result.calibration.left_head : result.calibration.right_head) = head;
  }
  return result;
}

CalibrationDepthError DepthErrorAgainst(const rig::RigCalibration& truth,
                                        const rig::RigCalibration& belief) {
  const rig::RigGeometry true_geometry = truth.Geometry(), believed_geometry = belief.Geometry();
  constexpr double kHalfBaseline = 0.03;
  std::vector<double> errors, misses;
  for (const double distance : {0.7, 1.0, 1.3})
    for (const double azimuth : {-15 * kDeg, 0.0, 15 * kDeg})
      for (const double elevation : {-8 * kDeg, 0.0, 8 * kDeg}) {
        const Eigen::Vector3d p(distance * std::sin(azimuth) * std::cos(elevation),
                                distance * std::cos(azimuth) * std::cos(elevation),
                                distance * std::sin(elevation));
        std::array<Eigen::Isometry3d, 2> true_pose, believed_pose;
        for (const rig::Side s : {rig::Side::kLeft, rig::Side::kRight}) {
          const double carriage = (s == rig::Side::kLeft ? -1 : 1) * kHalfBaseline;
          const rig::CameraStage stage = believed_geometry.FacingStage(s, carriage, p);
          true_pose[static_cast<int>(s)] = true_geometry.WorldFromCamera(s, stage);
          believed_pose[static_cast<int>(s)] = believed_geometry.WorldFromCamera(s, stage);
        }
        // A camera's ray to q as the belief has it: the true lens's pixel,
        // undistorted with the believed one; none where the true camera
        // does not image q.
        auto believed_ray = [&](int s, const Eigen::Vector3d& q) -> std::optional<fovea::Ray> {
          const rig::CameraIntrinsics& t = s == 0 ? truth.left : truth.right;
          const rig::CameraIntrinsics& b = s == 0 ? belief.left : belief.right;
          const Eigen::Vector3d q_C = true_pose[s].inverse() * q;
          if (q_C.z() <= 0) return std::nullopt;
          std::vector<cv::Point2d> raw, delivered;
          cv::projectPoints(std::vector<cv::Point3d>{{q_C.x(), q_C.y(), q_C.z()}},
                            cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cv::Mat(t.K()), t.distortion,
                            raw);
          if (raw[0].x < 0 || raw[0].y < 0 || raw[0].x >= t.width_px || raw[0].y >= t.height_px)
            return std::nullopt;
          cv::undistortPoints(raw, delivered, cv::Mat(b.K()), b.distortion);
          return fovea::Ray{believed_pose[s].translation(),
                            believed_pose[s].linear() *
                                Eigen::Vector3d(delivered[0].x, delivered[0].y, 1).normalized()};
        };
        for (int i = -2; i <= 2; ++i)
          for (int j = -2; j <= 2; ++j)
            for (int k = -1; k <= 1; ++k) {
              const Eigen::Vector3d q = p + Eigen::Vector3d(0.025 * i, 0.03 * k, 0.025 * j);
              const std::optional<fovea::Ray> left = believed_ray(0, q), right = believed_ray(1, q);
              if (!left || !right) continue;
              const std::optional<fovea::Triangulation> t =
                  fovea::TriangulateMidpoint(*left, *right);
              if (!t) continue;
              errors.push_back((t->p_W - q).norm() / (q - true_pose[0].translation()).norm());
              // How far the rays miss each other, as pixels at the point:
              // what a rectified pair shows as vertical disparity.
              misses.push_back(t->miss_distance_m / (t->p_W - left->origin_W).norm() *
                               belief.left.fx_px);
            }
      }
  CalibrationDepthError e;
  e.points = static_cast<int>(errors.size());
  e.median_rel = fovea::Quantile(errors, 0.5);
  e.p90_rel = fovea::Quantile(errors, 0.9);
  e.median_miss_px = fovea::Quantile(misses, 0.5);
  e.p90_miss_px = fovea::Quantile(misses, 0.9);
  return e;
}

void CaptureHeadViews(rig::Rig& rig, const std::vector<HeadView>& plan, const std::string& dir,
                      const std::function<void(int placement)>& before_placement) {
  std::vector<HeadView> views;
  for (size_t i = 0; i < plan.size(); ++i) {
    if (i == 0 || plan[i].placement != plan[i - 1].placement) before_placement(plan[i].placement);
    rig.MoveTo(plan[i].state);
    rig::CaptureOptions raw;
    raw.raw = true;
    const rig::StereoFrame frame = rig.Capture(raw);
    char name[2][64];
    std::snprintf(name[0], sizeof name[0], "left_%02zu.png", i);
    std::snprintf(name[1], sizeof name[1], "right_%02zu.png", i);
    WriteImageAtomic((fs::path(dir) / name[0]).string(), frame.left.gray);
    WriteImageAtomic((fs::path(dir) / name[1]).string(), frame.right.gray);
    views.push_back({rig.State(), name[0], name[1], plan[i].placement});
  }
  SaveHeadViews((fs::path(dir) / "views.yaml").string(), views);
}

rig::RigCalibration RenderHeadChessboards(const std::string& dir, const sim::SimRigConfig& config,
                                          int placements, int views_per_placement, double square_m,
                                          uint64_t seed) {
  const fs::path scene_dir = board::PrepareSceneFolder(dir);
  std::mt19937_64 rng(seed);
  auto uniform = [&](double a, double b) {
    return std::uniform_real_distribution<double>(a, b)(rng);
  };
  // Placements: ahead, then alternately high and low, each slanted well
  // away from facing the rig (a board seen square-on cannot tell the focal
  // length from its distance); degrees in MJCF's default.
  std::vector<HeadView> views;
  rig::RigCalibration truth;
  for (int p = 0; p < placements; ++p) {
    const double up = p == 0 ? 0 : (p % 2 == 1 ? 1 : -1) * (0.12 + 0.04 * ((p - 1) / 2));
    const Eigen::Vector3d centre(uniform(-0.08, 0.08), uniform(0.7, 0.85), up);
    const double yaw = (p % 2 == 0 ? 1 : -1) * uniform(25, 35);
    const double pitch = std::atan2(up, centre.y()) / kDeg + (p % 3 - 1) * uniform(10, 20);
    char pose[160];
    std::snprintf(pose, sizeof pose, "pos=\"%.4f %.4f %.4f\" euler=\"%.2f %.2f %.2f\"", centre.x(),
                  centre.y(), centre.z(), pitch, uniform(-10, 10), yaw);
    const fs::path scene = scene_dir / ("placement_" + std::to_string(p) + ".xml");
    std::ofstream(scene) << board::SceneXml(pose, square_m);
    sim::SimRigConfig c = config;
    c.seed = seed + p;
    auto sim = scenes::LoadScene(scene.string(), c);
    rig::Rig& rig = sim->rig();
    const rig::RigGeometry& g = rig.Geometry();  // the belief: the design
    for (int v = 0; v < views_per_placement; ++v) {
      rig::StageState target;
      for (const rig::Side s : {rig::Side::kLeft, rig::Side::kRight}) {
        const double carriage = (s == rig::Side::kLeft ? -1 : 1) * uniform(0.02, 0.26);
        const Eigen::Vector3d aim =
            centre + Eigen::Vector3d(uniform(-0.06, 0.06), 0, uniform(-0.04, 0.04));
        target[s] = g.FacingStage(s, carriage, aim);
      }
      rig.MoveTo(target);
      rig::CaptureOptions raw;
      raw.raw = true;
      const rig::StereoFrame frame = rig.Capture(raw);
      char name[2][64];
      const int n = static_cast<int>(views.size());
      std::snprintf(name[0], sizeof name[0], "left_%02d.png", n);
      std::snprintf(name[1], sizeof name[1], "right_%02d.png", n);
      WriteImageAtomic((fs::path(dir) / name[0]).string(), frame.left.gray);
      WriteImageAtomic((fs::path(dir) / name[1]).string(), frame.right.gray);
      views.push_back({frame.state, name[0], name[1], p});
    }
  }
  SaveHeadViews((fs::path(dir) / "views.yaml").string(), views);
  fs::remove_all(scene_dir);
  for (const rig::Side s : {rig::Side::kLeft, rig::Side::kRight}) {
    (s == rig::Side::kLeft ? truth.left : truth.right) = sim::TrueIntrinsics(config);
    (s == rig::Side::kLeft ? truth.left_head : truth.right_head) = sim::TrueHead(config, s);
  }
  return truth;
}

}  // namespace experiments
