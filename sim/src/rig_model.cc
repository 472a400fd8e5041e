// The MJCF model of the TAVT, generated from the configuration so that the
// model and the kinematics the algorithms use can never disagree.
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <sstream>
#include <utility>

#include "sim/simulation.h"

namespace sim {

void NoiseConfig::Check() const {
  rig::CheckParam(params::kNoiseSigmaDn, read_noise_sigma_dn);
  rig::CheckParam(params::kBlurSigmaPx, blur_sigma_px);
}

void SimRigConfig::Check() const {
  rig::CheckParam(params::kWidthPx, width_px);
  rig::CheckParam(params::kHeightPx, height_px);
  rig::CheckParam(params::kHorizontalFovDeg, horizontal_fov_deg);
  rig::CheckParam(params::kOpticalCentreXM, optical_centre_offset_m.x());
  rig::CheckParam(params::kOpticalCentreYM, optical_centre_offset_m.y());
  rig::CheckParam(params::kOpticalCentreZM, optical_centre_offset_m.z());
  rig::CheckParam(params::kCarriageMinM, carriage_min_m);
  rig::CheckParam(params::kCarriageMaxM, carriage_max_m);
  rig::CheckParam(params::kHomeBaselineM, home_baseline_m);
  rig::CheckParam(params::kPanLimitDeg, pan_limit_deg);
  rig::CheckParam(params::kTiltLimitDeg, tilt_limit_deg);
  rig::CheckParam(params::kBaselineStepsPerMm, baseline_steps_per_mm);
  rig::CheckParam(params::kPanTiltStepsPerDeg, pan_tilt_steps_per_deg);
  rig::CheckParam(params::kSettleToleranceSteps, settle_tolerance_steps);
  rig::CheckParam(params::kMoveTimeoutS, move_timeout_s);
  noise.Check();
  const Imperfections& im = imperfections;
  for (const auto& [spec, value] : std::initializer_list<std::pair<const rig::ParamSpec*, double>>{
           {&params::kLeftMountRollDeg, im.left.mount_rpy_deg.x()},
           {&params::kLeftMountPitchDeg, im.left.mount_rpy_deg.y()},
           {&params::kLeftMountYawDeg, im.left.mount_rpy_deg.z()},
           {&params::kRightMountRollDeg, im.right.mount_rpy_deg.x()},
           {&params::kRightMountPitchDeg, im.right.mount_rpy_deg.y()},
           {&params::kRightMountYawDeg, im.right.mount_rpy_deg.z()},
           {&params::kLeftPanZeroDeg, im.left.pan_zero_deg},
           {&params::kLeftTiltZeroDeg, im.left.tilt_zero_deg},
           {&params::kRightPanZeroDeg, im.right.pan_zero_deg},
           {&params::kRightTiltZeroDeg, im.right.tilt_zero_deg},
           {&params::kLeftGain, im.left.gain},
           {&params::kRightGain, im.right.gain},
           {&params::kLeftOffsetDn, im.left.offset_dn},
           {&params::kRightOffsetDn, im.right.offset_dn},
           {&params::kDistortionK1, im.k1},
           {&params::kDistortionK2, im.k2},
           {&params::kDistortionP1, im.p1},
           {&params::kDistortionP2, im.p2},
           {&params::kVignetting, im.vignetting},
           {&params::kPositionErrorSteps, im.position_error_steps}})
    rig::CheckParam(*spec, value);
  // What single ranges cannot say: the parts against each other.
  const std::string widest = rig::FormatParamNumber(2 * carriage_max_m);
  if (!(carriage_max_m > carriage_min_m))
    throw rig::InputError("key 'rig.carriage_max_m': must exceed rig.carriage_min_m");
  if (home_baseline_m < 2 * carriage_min_m || home_baseline_m > 2 * carriage_max_m)
    throw rig::InputError("key 'rig.home_baseline_m': " + rig::FormatParamNumber(home_baseline_m) +
                          " is not within the carriages' travel (2 x rig.carriage_min_m to 2 x "
                          "rig.carriage_max_m = " +
                          widest + ")");
}

rig::HeadGeometry TrueHead(const SimRigConfig& c, rig::Side side) {
  constexpr double kDeg = M_PI / 180;
  const CameraImperfections& im = c.imperfections[side];
  rig::HeadGeometry head;
  head.optical_centre_H = c.optical_centre_offset_m;
  head.mount_rpy_rad = im.mount_rpy_deg * kDeg;
  head.pan_zero_rad = im.pan_zero_deg * kDeg;
  head.tilt_zero_rad = im.tilt_zero_deg * kDeg;
  return head;
}

rig::CameraIntrinsics TrueIntrinsics(const SimRigConfig& c) {
  rig::CameraIntrinsics k = rig::CameraIntrinsics::FromHorizontalFov(
      c.width_px, c.height_px, c.horizontal_fov_deg * M_PI / 180);
  const Imperfections& im = c.imperfections;
  if (im.Distorted()) k.distortion = {im.k1, im.k2, im.p1, im.p2};
  return k;
}

cv::Size RenderSize(const SimRigConfig& c) {
  const rig::CameraIntrinsics k = TrueIntrinsics(c);
  if (k.distortion.empty()) return {c.width_px, c.height_px};
  // The undistorted positions of the image's border pixels bound the
  // undistorted image (OpenCV's distortion models are monotone over a
  // sensible image): a centred window around them, 2 px of margin.
  std::vector<cv::Point2f> border, ideal;
  for (int u = 0; u < c.width_px; ++u) {
    border.emplace_back(float(u), 0.f);
    border.emplace_back(float(u), float(c.height_px - 1));
  }
  for (int v = 0; v < c.height_px; ++v) {
    border.emplace_back(0.f, float(v));
    border.emplace_back(float(c.width_px - 1), float(v));
  }
  cv::undistortPoints(border, ideal, cv::Mat(k.K()), k.distortion, cv::noArray(), cv::Mat(k.K()));
  double half_w = 0, half_h = 0;
  for (const cv::Point2f& p : ideal) {
    half_w = std::max(half_w, std::abs(p.x - k.cx_px));
    half_h = std::max(half_h, std::abs(p.y - k.cy_px));
  }
  return {std::max(c.width_px, 2 * static_cast<int>(std::ceil(half_w)) + 5),
          std::max(c.height_px, 2 * static_cast<int>(std::ceil(half_h)) + 5)};
}

std::string RigMjcf(const SimRigConfig& c) {
  const double f_px = 0.5 * c.width_px / std::tan(0.5 * c.horizontal_fov_deg * M_PI / 180);
  const cv::Size render = RenderSize(c);
  // The truth camera draws at most the images' size; the rig's cameras at
  // their render size (wider than the image for a distorted lens).
  const double fovy_deg = 2 * std::atan(0.5 * c.height_px / f_px) * 180 / M_PI;
  const double render_fovy_deg = 2 * std::atan(0.5 * render.height / f_px) * 180 / M_PI;
  const Eigen::Vector3d& o = c.optical_centre_offset_m;
  std::ostringstream x;
  x.precision(12);
  // Ranges and near/far planes are set on the compiled model (in SI units),
  // so a scene's <compiler angle=...> cannot change them.
  x << R"(<mujoco model="tavt">
  <option timestep="0.001" gravity="0 0 0"/>
  <visual>
    <global offwidth=")"
    << render.width << R"(" offheight=")" << render.height << R"("/>
    <quality offsamples="4"/>
    <headlight ambient="0.25 0.25 0.25" diffuse="0 0 0" specular="0 0 0"/>
  </visual>
  <default>
    <default class="tavt">
      <geom group="4" contype="0" conaffinity="0" rgba="0.25 0.25 0.28 1"/>
    </default>
  </default>
  <worldbody>
    <camera name="tavt_truth" pos="0 0 0" xyaxes="1 0 0 0 0 1" fovy=")"
    << fovy_deg << R"("/>
    <body name="tavt_rail" childclass="tavt">
      <geom name="tavt_rail" type="box" size=")"
    << c.carriage_max_m + 0.05 << R"( 0.03 0.01" pos="0 0 -0.08"/>
)";
  for (const rig::Side s : {rig::Side::kLeft, rig::Side::kRight}) {
    const char* side = s == rig::Side::kLeft ? "left" : "right";
    // Imperfections as fixed rotations (quaternions and axes, which a
    // scene's <compiler angle=...> cannot reinterpret): the encoders' zeros
    // turn the pan and tilt bodies, the mount turns the camera.
    const rig::HeadGeometry head = TrueHead(c, s);
    const Eigen::Quaterniond pan_q(Eigen::AngleAxisd(head.pan_zero_rad, Eigen::Vector3d::UnitZ()));
    const Eigen::Quaterniond tilt_q(
        Eigen::AngleAxisd(head.tilt_zero_rad, Eigen::Vector3d::UnitX()));
    const Eigen::Matrix3d mount = head.MountRotation();
    const Eigen::Vector3d cam_x = mount.col(0), cam_y = mount.col(2);  // MuJoCo: x right, y up
    // Carriage: slide along X. Head: pan about Z, tilt about the panned X.
    // Inertias: carriage 2 kg plus 3 kg reflected screw inertia; pan and tilt
    // heads with reflected rotor inertia (armature) dominating, as on
    // geared microstepping stages. Damping makes each servo about critical.
    x << R"(      <body name="tavt_)" << side << R"(_carriage" pos="0 0 0">
        <inertial pos="0 0 0" mass="2" diaginertia="0.01 0.01 0.01"/>
        <joint name="tavt_)"
      << side << R"(_baseline" type="slide" axis="1 0 0" armature="3" damping="170"/>
        <geom type="box" size="0.04 0.05 0.01" pos="0 0 -0.065"/>
        <body name="tavt_)"
      << side << R"(_pan" pos="0 0 0" quat=")" << pan_q.w() << " " << pan_q.x() << " " << pan_q.y()
      << " " << pan_q.z() << R"(">
          <inertial pos="0 0 0" mass="0.5" diaginertia="0.002 0.002 0.002"/>
          <joint name="tavt_)"
      << side << R"(_pan" type="hinge" axis="0 0 1" armature="0.02" damping="1.2"/>
          <geom type="cylinder" size="0.02 0.02" pos="0 0 -0.04"/>
          <body name="tavt_)"
      << side << R"(_tilt" pos="0 0 0" quat=")" << tilt_q.w() << " " << tilt_q.x() << " "
      << tilt_q.y() << " " << tilt_q.z() << R"(">
            <inertial pos="0 0 0" mass="0.4" diaginertia="0.001 0.001 0.001"/>
            <joint name="tavt_)"
      << side << R"(_tilt" type="hinge" axis="1 0 0" armature="0.01" damping="0.62"/>
            <geom type="box" size="0.02 0.035 0.02" pos=")"
      << o.x() << " " << o.y() - 0.035 << " " << o.z() << R"("/>
            <camera name="tavt_)"
      << side << R"(" pos=")" << o.x() << " " << o.y() << " " << o.z() << R"(" xyaxes=")"
      << cam_x.x() << " " << cam_x.y() << " " << cam_x.z() << " " << cam_y.x() << " " << cam_y.y()
      << " " << cam_y.z() << R"(" fovy=")" << render_fovy_deg << R"("/>
          </body>
        </body>
      </body>
)";
  }
  x << R"(    </body>
  </worldbody>
  <actuator>
)";
  for (const char* side : {"left", "right"}) {
    x << "    <position name=\"tavt_" << side << "_baseline\" joint=\"tavt_" << side
      << "_baseline\" kp=\"1500\" forcelimited=\"true\" forcerange=\"-40 40\"/>\n"
      << "    <position name=\"tavt_" << side << "_pan\" joint=\"tavt_" << side
      << "_pan\" kp=\"15\" forcelimited=\"true\" forcerange=\"-1.5 1.5\"/>\n"
      << "    <position name=\"tavt_" << side << "_tilt\" joint=\"tavt_" << side
      << "_tilt\" kp=\"8\" forcelimited=\"true\" forcerange=\"-0.8 0.8\"/>\n";
  }
  x << "  </actuator>\n</mujoco>\n";
  return x.str();
}

}  // namespace sim
