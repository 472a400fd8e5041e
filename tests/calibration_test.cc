// Stereo calibration against chessboards the simulator renders at known
// poses: the recovered focal lengths and baseline against the true ones.
#include "experiments/calibration/calibration.h"

#include <unistd.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>

#include "experiments/calibration/head_calibration.h"

TEST_CASE("calibration on simulator-rendered chessboards recovers focal length and baseline",
          "[calibration]") {
  const std::string dir =
      (std::filesystem::temp_directory_path() / ("fovea_chessboards_" + std::to_string(getpid())))
          .string();
  const experiments::SyntheticTruth truth = experiments::RenderChessboardViews(dir, 12, 0.025, 1);
  const experiments::CalibrationResult r = experiments::CalibrateStereo(
      experiments::Glob(dir + "/left_*.png"), experiments::Glob(dir + "/right_*.png"), 9, 6, 0.025);
  INFO("fx left " << r.calibration.left.fx_px << ", right " << r.calibration.right.fx_px
                  << ", true " << truth.fx_px << "; baseline " << r.baseline_m << " (true "
                  << truth.baseline_m << "); RMS " << r.rms_left_px << " / " << r.rms_right_px
                  << " / " << r.rms_stereo_px << " px");
  CHECK(r.views == 12);
  for (const rig::CameraIntrinsics* k : {&r.calibration.left, &r.calibration.right}) {
    CHECK(std::abs(k->fx_px - truth.fx_px) < 0.005 * truth.fx_px);
    CHECK(std::abs(k->fy_px - truth.fy_px) < 0.005 * truth.fy_px);
    CHECK(std::abs(k->cx_px - truth.cx_px) < 5);
    CHECK(std::abs(k->cy_px - truth.cy_px) < 5);
  }
  CHECK(std::abs(r.baseline_m - truth.baseline_m) < 0.001);
  CHECK(r.rms_stereo_px < 0.5);

  // The file the hardware rig reads says the same.
  rig::SaveCalibration(dir + "/calibration.yaml", r.calibration);
  const rig::RigCalibration back = rig::LoadCalibration(dir + "/calibration.yaml");
  CHECK(back.left.fx_px == Approx(r.calibration.left.fx_px));
  CHECK(back.right.cy_px == Approx(r.calibration.right.cy_px));
  CHECK(back.left.distortion.size() == 5);
  CHECK(back.left.width_px == 640);
  std::filesystem::remove_all(dir);
}

namespace {

// The simulated rig of issue 22: every imperfection at a value a real head has.
sim::SimRigConfig ImperfectRig() {
  sim::SimRigConfig c;
  c.noise.read_noise_sigma_dn = 1.0;
  c.optical_centre_offset_m = {0.02, 0.08, 0.02};
  sim::Imperfections& im = c.imperfections;
  im.k1 = -0.2;
  im.left.mount_rpy_deg = {1.5, 1.5, 1.5};
  im.right.mount_rpy_deg = {-1.5, 1.5, -1.5};
  im.left.pan_zero_deg = 0.1;
  im.left.tilt_zero_deg = 0.1;
  im.right.pan_zero_deg = -0.1;
  im.right.tilt_zero_deg = 0.1;
  im.right.gain = 1.1;
  return c;
}

double AngleDeg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(a.transpose() * b).angle() * 180 / M_PI;
}

}  // namespace

TEST_CASE("head calibration recovers a known imperfect rig", "[calibration][head]") {
  const std::string dir =
      (std::filesystem::temp_directory_path() / ("fovea_head_" + std::to_string(getpid())))
          .string();
  const rig::RigCalibration truth =
      experiments::RenderHeadChessboards(dir, ImperfectRig(), 3, 10, 0.02, 7);
  const std::vector<experiments::HeadView> views = experiments::LoadHeadViews(dir + "/views.yaml");
  REQUIRE(views.size() == 30);
  const experiments::HeadCalibrationResult r = experiments::CalibrateHead(views, 9, 6, 0.02);
  INFO("reprojection RMS " << r.rms_px << " px over " << r.views[0] << " + " << r.views[1]
                           << " views");
  CHECK(r.rms_px < 0.2);
  for (const rig::Side s : {rig::Side::kLeft, rig::Side::kRight}) {
    const rig::CameraIntrinsics& k = r.calibration.Intrinsics(s);
    const rig::CameraIntrinsics& kt = truth.Intrinsics(s);
    const rig::HeadGeometry& h = r.calibration.Head(s);
    // The tilt zero is the mount's to any camera: compare the folded truth.
    const rig::HeadGeometry ht = truth.Head(s).FoldTiltZero();
    INFO(rig::SideName(s) << ": fx " << k.fx_px << " (true " << kt.fx_px << "), fy " << k.fy_px
                          << ", k1 " << k.distortion[0] << "; mount rpy deg "
                          << (h.mount_rpy_rad * 180 / M_PI).transpose() << " (true "
                          << (ht.mount_rpy_rad * 180 / M_PI).transpose() << "); centre "
                          << h.optical_centre_H.transpose() << " (true "
                          << ht.optical_centre_H.transpose() << "); pan zero deg "
                          << h.pan_zero_rad * 180 / M_PI << " (true "
                          << ht.pan_zero_rad * 180 / M_PI << "); sd: pan zero "
                          << r.pan_zero_sd_deg[int(s)] << " deg, mount " << r.mount_sd_deg[int(s)]
                          << " deg, centre " << r.centre_sd_m[int(s)] << " m");
    CHECK(std::abs(k.fx_px / kt.fx_px - 1) < 0.003);
    CHECK(std::abs(k.fy_px / kt.fy_px - 1) < 0.003);
    CHECK(std::abs(k.distortion[0] - kt.distortion[0]) < 0.02);
    CHECK(AngleDeg(h.MountRotation(), ht.MountRotation()) < 0.1);
    CHECK((h.optical_centre_H - ht.optical_centre_H).norm() < 0.002);
    CHECK(std::abs(h.pan_zero_rad - ht.pan_zero_rad) * 180 / M_PI < 0.02);
  }
  // What matters to a fixating pair: its depth. The ideal rig's own stereo
  // error is about 0.06% of the depth; a calibration must add well under it.
  const experiments::CalibrationDepthError e = experiments::DepthErrorAgainst(truth, r.calibration);
  INFO("depth error at fixations: median " << 100 * e.median_rel << "%, p90 " << 100 * e.p90_rel
                                           << "% over " << e.points << " points");
  CHECK(e.points > 1000);
  CHECK(e.median_rel < 0.0003);
  std::filesystem::remove_all(dir);
}

TEST_CASE("the depth error a calibration makes follows the baseline and vergence it gets wrong",
          "[calibration]") {
  rig::RigCalibration truth;
  truth.left = truth.right = rig::CameraIntrinsics::FromHorizontalFov(640, 480, 30 * M_PI / 180);
  truth.left.distortion = truth.right.distortion = {-0.2, 0, 0, 0, 0};
  truth.left_head.optical_centre_H = truth.right_head.optical_centre_H = {0.02, 0.08, 0.02};
  truth.left_head.mount_rpy_rad = {0.02, 0.03, -0.01};
  const experiments::CalibrationDepthError exact = experiments::DepthErrorAgainst(truth, truth);
  CHECK(exact.points > 1000);
  CHECK(exact.median_rel < 1e-9);
  // Depth is baseline over vergence: 0.1 mm more believed baseline (of
  // 0.06 m) is about 0.17% more depth everywhere; the right camera believed
  // turned 0.01 degrees inward costs about depth x angle / baseline, 0.29%
  // at 1 m (0.20% at 0.7 m, 0.38% at 1.3 m).
  rig::RigCalibration wider = truth;
  wider.right_head.optical_centre_H.x() += 1e-4;
  const experiments::CalibrationDepthError b = experiments::DepthErrorAgainst(truth, wider);
  CHECK(b.median_rel == Approx(1e-4 / 0.06).epsilon(0.2));
  CHECK(b.p90_rel < 1.3 * b.median_rel);
  rig::RigCalibration turned = truth;
  turned.right_head.mount_rpy_rad.z() += 0.01 * M_PI / 180;
  const experiments::CalibrationDepthError v = experiments::DepthErrorAgainst(truth, turned);
  CHECK(v.median_rel == Approx(1.0 * 0.01 * M_PI / 180 / 0.06).epsilon(0.2));
  CHECK(v.p90_rel > 1.2 * v.median_rel);
}

TEST_CASE("calibration files keep the head model (version 2) and still read version 1",
          "[calibration]") {
  const std::string dir =
      (std::filesystem::temp_directory_path() / ("fovea_calfile_" + std::to_string(getpid())))
          .string();
  std::filesystem::create_directories(dir);
  rig::RigCalibration c;
  c.left = c.right = rig::CameraIntrinsics::FromHorizontalFov(640, 480, 0.5);
  c.left.distortion = {-0.2, 0.01, 0.001, -0.002, 0};
  c.left_head.optical_centre_H = {0.02, 0.08, 0.02};
  c.left_head.mount_rpy_rad = {0.026, -0.01, 0.02};
  c.left_head.pan_zero_rad = 0.0017;
  c.right_head.tilt_zero_rad = -0.003;
  rig::SaveCalibration(dir + "/v2.yaml", c);
  const rig::RigCalibration back = rig::LoadCalibration(dir + "/v2.yaml");
  CHECK(back.version == rig::kCalibrationVersion);
  CHECK((back.left_head.mount_rpy_rad - c.left_head.mount_rpy_rad).norm() < 1e-12);
  CHECK((back.left_head.optical_centre_H - c.left_head.optical_centre_H).norm() < 1e-12);
  CHECK(back.left_head.pan_zero_rad == Approx(0.0017).margin(1e-15));
  CHECK(back.right_head.tilt_zero_rad == Approx(-0.003).margin(1e-15));
  CHECK(back.left.distortion == c.left.distortion);
  // Version 1 (no version key, no head model but the offset): zeros.
  std::ofstream(dir + "/v1.yaml")
      << "%YAML:1.0\n---\nleft: {width_px: 640, height_px: 480, fx_px: 1194., fy_px: 1194., "
         "cx_px: 319.5, cy_px: 239.5, optical_centre_H_m: [0, 0.03, 0.01]}\nright: {width_px: "
         "640, height_px: 480, fx_px: 1194., fy_px: 1194., cx_px: 319.5, cy_px: 239.5}\n";
  const rig::RigCalibration v1 = rig::LoadCalibration(dir + "/v1.yaml");
  CHECK(v1.version == 1);
  CHECK(v1.left_head.optical_centre_H.y() == Approx(0.03));
  CHECK(v1.left_head.mount_rpy_rad.isZero());
  CHECK(v1.right_head.pan_zero_rad == 0);
  std::filesystem::remove_all(dir);
}
