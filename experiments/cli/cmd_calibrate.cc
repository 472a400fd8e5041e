// fovea calibrate: stereo calibration from chessboard image pairs, written as
// the calibration file a hardware rig reads; fovea chessboards: a synthetic
// set of such pairs rendered by the simulator, with the true values.
#include <cmath>
#include <cstdio>

#include "commands.h"
#include "experiments/calibration/calibration.h"
#include "experiments/output/output.h"
#include "scene_options.h"

namespace experiments {

void AddCalibrateCommands(CLI::App& app, std::function<int()>* run) {
  struct Args {
    std::string left, right, board, out, square;
    bool force = false;
  };
  auto a = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand("calibrate", "stereo calibration from chessboard image pairs");
  cmd->add_option("--left", a->left, "left images (a shell pattern, quoted)")->required();
  cmd->add_option("--right", a->right, "right images, same count and order")->required();
  cmd->add_option("--board", a->board, "inner corners WxH, e.g. 8x6")->required();
  cmd->add_option("--square", a->square, "square size, metres")
      ->required()
      ->check(NumberIn(1e-4, 10));
  cmd->add_option("--out", a->out, "calibration file to write (YAML)")->required();
  cmd->add_flag("--force", a->force, "replace an existing file at --out");
  cmd->callback([a, run] {
    *run = [a] {
      const size_t x = a->board.find('x');
      const std::optional<double> cols = ParseNumber(a->board.substr(0, x)),
                                  rows = x == std::string::npos
                                             ? std::nullopt
                                             : ParseNumber(a->board.substr(x + 1));
      if (!cols || !rows || *cols != std::floor(*cols) || *rows != std::floor(*rows) || *cols < 2 ||
          *rows < 2 || *cols > 100 || *rows > 100)
        throw UsageError("--board expects WxH inner corners (2 to 100 each), e.g. 8x6, got '" +
                         rig::ClipForMessage(a->board) + "'");
      const std::string out = CheckOutputFile(a->out, "--out", a->force);
      const CalibrationResult r =
          CalibrateStereo(Glob(a->left), Glob(a->right), static_cast<int>(*cols),
                          static_cast<int>(*rows), *ParseNumber(a->square));
      const std::string tmp = TempFileName(out);
      try {
        rig::SaveCalibration(tmp, r.calibration);
      } catch (...) {
        std::remove(tmp.c_str());
        throw;
      }
      if (std::rename(tmp.c_str(), out.c_str()) != 0) {
        std::remove(tmp.c_str());
        throw std::runtime_error("cannot write '" + rig::ClipForMessage(out) + "'");
      }
      const rig::CameraIntrinsics& l = r.calibration.left;
      const rig::CameraIntrinsics& rr = r.calibration.right;
      std::printf(
          "views %d (skipped %zu)\nleft  fx %.3f fy %.3f cx %.3f cy %.3f px, reprojection RMS %.4f "
          "px\n"
          "right fx %.3f fy %.3f cx %.3f cy %.3f px, reprojection RMS %.4f px\n"
          "stereo reprojection RMS %.4f px, baseline %.5f m\n-> %s\n",
          r.views, r.skipped.size(), l.fx_px, l.fy_px, l.cx_px, l.cy_px, r.rms_left_px, rr.fx_px,
          rr.fy_px, rr.cx_px, rr.cy_px, r.rms_right_px, r.rms_stereo_px, r.baseline_m, out.c_str());
      return 0;
    };
  });

  auto dir = std::make_shared<std::string>();
  auto views = std::make_shared<int>(12);
  auto square = std::make_shared<double>(0.025);
  auto force = std::make_shared<bool>(false);
  CLI::App* gen = app.add_subcommand("chessboards",
                                     "render chessboard pairs at known poses for fovea calibrate");
  gen->add_option("--out", *dir, "folder for left_NN.png, right_NN.png (new, or empty)")
      ->required();
  AddForceFlag(gen, force.get());
  gen->add_option("--views", *views, "pairs to render")->check(CLI::Range(3, 100));
  gen->add_option("--square", *square, "square size, metres")->check(NumberIn(0.005, 0.1));
  gen->callback([dir, views, square, force, run] {
    *run = [dir, views, square, force] {
      OutputFolder folder(*dir, "--out", ExistingPolicy(*force));
      const SyntheticTruth t = RenderChessboardViews(folder.path(), *views, *square, 1);
      folder.Commit();
      std::printf(
          "true: fx %.3f fy %.3f cx %.3f cy %.3f px, baseline %.5f m (board 9x6 inner corners, "
          "square %g m)\n",
          t.fx_px, t.fy_px, t.cx_px, t.cy_px, t.baseline_m, *square);
      return 0;
    };
  });
}

}  // namespace experiments
