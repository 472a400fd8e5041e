// fovea calibrate: stereo calibration from chessboard image pairs, written as
// the calibration file a hardware rig reads; fovea chessboards: a synthetic
// set of such pairs rendered by the simulator, with the true values.
#include <cstdio>

#include "calibration.h"
#include "commands.h"
#include "output.h"

namespace experiments {

void AddCalibrateCommands(CLI::App& app, std::function<int()>* run) {
  struct Args {
    std::string left, right, board, out;
    double square_m = 0;
  };
  auto a = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand("calibrate", "stereo calibration from chessboard image pairs");
  cmd->add_option("--left", a->left, "left images (a shell pattern, quoted)")->required();
  cmd->add_option("--right", a->right, "right images, same count and order")->required();
  cmd->add_option("--board", a->board, "inner corners WxH, e.g. 8x6")->required();
  cmd->add_option("--square", a->square_m, "square size, metres")->required()->check(CLI::PositiveNumber);
  cmd->add_option("--out", a->out, "calibration file to write (YAML)")->required();
  cmd->callback([a, run] {
    *run = [a] {
      int cols = 0, rows = 0;
      char extra;
      if (std::sscanf(a->board.c_str(), "%dx%d%c", &cols, &rows, &extra) != 2)
        throw UsageError("--board expects WxH inner corners, e.g. 8x6, got '" + a->board + "'");
      const CalibrationResult r = CalibrateStereo(Glob(a->left), Glob(a->right), cols, rows, a->square_m);
      const std::string tmp = a->out + ".partial";
      rig::SaveCalibration(tmp, r.calibration);
      std::rename(tmp.c_str(), a->out.c_str());
      const rig::CameraIntrinsics& l = r.calibration.left;
      const rig::CameraIntrinsics& rr = r.calibration.right;
      std::printf("views %d (skipped %zu)\nleft  fx %.3f fy %.3f cx %.3f cy %.3f px, reprojection RMS %.4f px\n"
                  "right fx %.3f fy %.3f cx %.3f cy %.3f px, reprojection RMS %.4f px\n"
                  "stereo reprojection RMS %.4f px, baseline %.5f m\n-> %s\n",
                  r.views, r.skipped.size(), l.fx_px, l.fy_px, l.cx_px, l.cy_px, r.rms_left_px, rr.fx_px, rr.fy_px,
                  rr.cx_px, rr.cy_px, r.rms_right_px, r.rms_stereo_px, r.baseline_m, a->out.c_str());
      return 0;
    };
  });

  auto dir = std::make_shared<std::string>();
  auto views = std::make_shared<int>(12);
  auto square = std::make_shared<double>(0.025);
  CLI::App* gen = app.add_subcommand("chessboards", "render chessboard pairs at known poses for fovea calibrate");
  gen->add_option("--out", *dir, "folder for left_NN.png, right_NN.png")->required();
  gen->add_option("--views", *views, "pairs to render")->check(CLI::Range(3, 100));
  gen->add_option("--square", *square, "square size, metres")->check(CLI::Range(0.005, 0.1));
  gen->callback([dir, views, square, run] {
    *run = [dir, views, square] {
      const SyntheticTruth t = RenderChessboardViews(*dir, *views, *square, 1);
      std::printf("true: fx %.3f fy %.3f cx %.3f cy %.3f px, baseline %.5f m (board 9x6 inner corners, square %g m)\n",
                  t.fx_px, t.fy_px, t.cx_px, t.cy_px, t.baseline_m, *square);
      return 0;
    };
  });
}

}  // namespace experiments
