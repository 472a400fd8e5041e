// Stereo calibration against chessboards the simulator renders at known
// poses: the recovered focal lengths and baseline against the true ones.
#include "experiments/calibration/calibration.h"

#include <unistd.h>

#include <catch2/catch.hpp>
#include <filesystem>

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
