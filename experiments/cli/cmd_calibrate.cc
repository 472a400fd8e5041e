// fovea calibrate: stereo calibration from chessboard image pairs, written as
// the calibration file a hardware rig reads; fovea chessboards: a synthetic
// set of such pairs rendered by the simulator, with the true values.
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <optional>

#include "commands.h"
#include "experiments/calibration/calibration.h"
#include "experiments/calibration/head_calibration.h"
#include "experiments/output/output.h"
#include "hardware_setup.h"
#include "scene_options.h"

namespace experiments {

namespace {

// --board WxH: inner corners, 2 to 100 each; UsageError otherwise.
cv::Size ParseBoard(const std::string& board) {
  const size_t x = board.find('x');
  const std::optional<double> cols = ParseNumber(board.substr(0, x)),
                              rows = x == std::string::npos ? std::nullopt
                                                            : ParseNumber(board.substr(x + 1));
  if (!cols || !rows || *cols != std::floor(*cols) || *rows != std::floor(*rows) || *cols < 2 ||
      *rows < 2 || *cols > 100 || *rows > 100)
    throw UsageError("--board expects WxH inner corners (2 to 100 each), e.g. 8x6, got '" +
                     rig::ClipForMessage(board) + "'");
  return {static_cast<int>(*cols), static_cast<int>(*rows)};
}

// Writes a calibration file through a temporary beside it, so that a
// failure leaves no half-written file.
void SaveCalibrationAtomic(const std::string& out, const rig::RigCalibration& calibration) {
  const std::string tmp = TempFileName(out);
  try {
    rig::SaveCalibration(tmp, calibration);
  } catch (...) {
    std::remove(tmp.c_str());
    throw;
  }
  if (std::rename(tmp.c_str(), out.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw std::runtime_error("cannot write '" + rig::ClipForMessage(out) + "'");
  }
}

void PrintHead(const char* side, const rig::CameraIntrinsics& k, const rig::HeadGeometry& h) {
  const double deg = 180 / M_PI;
  std::printf(
      "%-5s fx %.3f fy %.3f cx %.3f cy %.3f px, k1 %.4f k2 %.4f p1 %.5f p2 %.5f k3 %.4f\n"
      "      optical centre %.4f %.4f %.4f m, mount roll %.3f pitch %.3f yaw %.3f deg, pan zero "
      "%.4f deg\n",
      side, k.fx_px, k.fy_px, k.cx_px, k.cy_px, k.distortion[0], k.distortion[1], k.distortion[2],
      k.distortion[3], k.distortion[4], h.optical_centre_H.x(), h.optical_centre_H.y(),
      h.optical_centre_H.z(), h.mount_rpy_rad.x() * deg, h.mount_rpy_rad.y() * deg,
      h.mount_rpy_rad.z() * deg, h.pan_zero_rad * deg);
}

}  // namespace

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
      const cv::Size board = ParseBoard(a->board);
      const std::string out = CheckOutputFile(a->out, "--out", a->force);
      const CalibrationResult r = CalibrateStereo(Glob(a->left), Glob(a->right), board.width,
                                                  board.height, *ParseNumber(a->square));
      SaveCalibrationAtomic(out, r.calibration);
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

  struct HeadArgs {
    std::string views, board, out, square, truth;
    bool force = false;
  };
  auto h = std::make_shared<HeadArgs>();
  CLI::App* head = app.add_subcommand(
      "calibrate-head",
      "head calibration: intrinsics, each camera's pose on its head and the pan zeros, from "
      "chessboard views at many stage states");
  head->add_option("--views", h->views,
                   "views.yaml: image pairs and the stage readings they were taken at")
      ->required();
  head->add_option("--board", h->board, "inner corners WxH, e.g. 9x6")->required();
  head->add_option("--square", h->square, "square size, metres")
      ->required()
      ->check(NumberIn(1e-4, 10));
  head->add_option("--out", h->out, "calibration file to write (YAML, version 2)")->required();
  head->add_flag("--force", h->force, "replace an existing file at --out");
  head->add_option("--truth", h->truth,
                   "a rig's true calibration (fovea chessboards --head writes truth.yaml): also "
                   "print the depth error the recovered one makes at fixations");
  head->callback([h, run] {
    *run = [h] {
      const cv::Size board = ParseBoard(h->board);
      const std::string out = CheckOutputFile(h->out, "--out", h->force);
      const rig::RigCalibration truth =
          h->truth.empty() ? rig::RigCalibration{} : rig::LoadCalibration(h->truth);
      const HeadCalibrationResult r = CalibrateHead(LoadHeadViews(h->views), board.width,
                                                    board.height, *ParseNumber(h->square));
      SaveCalibrationAtomic(out, r.calibration);
      std::printf("views: left %d, right %d (skipped %zu), board placements %d\n", r.views[0],
                  r.views[1], r.skipped.size(), r.placements);
      PrintHead("left", r.calibration.left, r.calibration.left_head);
      PrintHead("right", r.calibration.right, r.calibration.right_head);
      std::printf(
          "one standard deviation: focal %.3f / %.3f px, mount %.4f / %.4f deg, optical centre "
          "%.5f / %.5f m, pan zero %.4f / %.4f deg\n"
          "the tilt zeros are folded into the mounts' pitch (no camera can tell them apart)\n"
          "reprojection RMS %.4f px (joint fit; each camera alone %.4f / %.4f px)\n-> %s\n",
          r.focal_sd_px[0], r.focal_sd_px[1], r.mount_sd_deg[0], r.mount_sd_deg[1],
          r.centre_sd_m[0], r.centre_sd_m[1], r.pan_zero_sd_deg[0], r.pan_zero_sd_deg[1], r.rms_px,
          r.rms_intrinsics_px[0], r.rms_intrinsics_px[1], out.c_str());
      if (!h->truth.empty()) {
        const CalibrationDepthError e = DepthErrorAgainst(truth, r.calibration);
        std::printf(
            "against %s: points near fixations 0.7-1.3 m ahead (0.06 m baseline) triangulate "
            "%.3f%% off (median), %.3f%% (p90), over %d points\n",
            h->truth.c_str(), 100 * e.median_rel, 100 * e.p90_rel, e.points);
      }
      return 0;
    };
  });

  auto dir = std::make_shared<std::string>();
  auto views = std::make_shared<int>(12);
  auto square = std::make_shared<double>(0.025);
  auto force = std::make_shared<bool>(false);
  struct HeadSet {
    bool head = false;
    int placements = 3;
    std::string config_path;
    std::vector<std::string> set;
    std::string seed;
    std::string states;
    bool no_wait = false;
  };
  auto hs = std::make_shared<HeadSet>();
  CLI::App* gen = app.add_subcommand("chessboards",
                                     "render chessboard pairs at known poses for fovea calibrate");
  gen->add_option("--out", *dir, "folder for left_NN.png, right_NN.png (new, or empty)")
      ->required();
  AddForceFlag(gen, force.get());
  gen->add_option("--views", *views, "pairs to render (with --head: per board placement)")
      ->check(CLI::Range(3, 100));
  gen->add_option("--square", *square, "square size, metres")->check(NumberIn(0.005, 0.1));
  gen->add_flag("--head", hs->head,
                "a head-calibration set: the board stays put while the rig moves through stage "
                "states (views.yaml), for fovea calibrate-head");
  gen->add_option("--placements", hs->placements, "with --head: board placements")
      ->check(CLI::Range(1, 20));
  gen->add_option("--config", hs->config_path,
                  "with --head: YAML configuration of the rig (its imperfections: rig.*)");
  gen->add_option("--set", hs->set, "with --head: KEY=VALUE, one rig parameter (repeatable)");
  gen->add_option("--seed", hs->seed, "with --head: seed of the stage states and sensor noise");
  gen->add_option("--states", hs->states,
                  "with --head: capture with the config's rig (rig.type hardware, or its simulated "
                  "scene) at the stage states this views.yaml lists, instead of rendering boards");
  gen->add_flag("--no-wait", hs->no_wait,
                "with --states: do not wait for Enter before each board placement");
  gen->callback([dir, views, square, force, hs, run] {
    *run = [dir, views, square, force, hs] {
      if (!hs->head && (!hs->config_path.empty() || !hs->set.empty() || !hs->seed.empty() ||
                        !hs->states.empty()))
        throw UsageError("--config, --set, --seed and --states go with --head");
      // The rig's configuration (--head): the file, then --set, then --seed.
      RunConfig c;
      if (hs->head) {
        if (!hs->config_path.empty()) c = LoadConfig(hs->config_path);
        SetParams(&c, hs->set);
        if (!hs->seed.empty()) SetParamFromFlag(&c, "--seed", "seed", hs->seed);
        c.Check();
      }
      if (hs->head && !hs->states.empty()) {
        const std::vector<HeadView> plan = LoadHeadViews(hs->states, /*images=*/false);
        std::unique_ptr<rig::IndexerEmulator> emulator;
        std::unique_ptr<rig::HardwareRig> hardware;
        std::unique_ptr<sim::Simulation> sim;
        if (c.hardware.type == "hardware")
          hardware = MakeHardwareRig(c, &emulator);
        else
          sim = LoadSceneOf(c);
        rig::Rig& rig = hardware ? static_cast<rig::Rig&>(*hardware) : sim->rig();
        const bool wait = !hs->no_wait && isatty(STDIN_FILENO);
        OutputFolder folder(*dir, "--out", ExistingPolicy(*force));
        CaptureHeadViews(rig, plan, folder.path(), [wait](int placement) {
          if (!wait) return;
          std::printf("place the board at placement %d, then press Enter: ", placement);
          std::fflush(stdout);
          std::string line;
          std::getline(std::cin, line);
        });
        folder.Commit();
        std::printf("%zu views captured -> %s/views.yaml\n", plan.size(), dir->c_str());
        return 0;
      }
      if (hs->head) {
        OutputFolder folder(*dir, "--out", ExistingPolicy(*force));
        const rig::RigCalibration truth =
            RenderHeadChessboards(folder.path(), c.rig, hs->placements, *views, *square, c.seed);
        // The truth beside the views, to compare a calibration with.
        rig::RigCalibration folded = truth;
        folded.left_head = truth.left_head.FoldTiltZero();
        folded.right_head = truth.right_head.FoldTiltZero();
        for (rig::CameraIntrinsics* k : {&folded.left, &folded.right}) k->distortion.resize(5, 0.0);
        SaveCalibrationAtomic(folder.path() + "/truth.yaml", folded);
        folder.Commit();
        std::printf("%d views of %d board placements (9x6 inner corners, square %g m)\n",
                    hs->placements * *views, hs->placements, *square);
        PrintHead("true left", folded.left, folded.left_head);
        PrintHead("true right", folded.right, folded.right_head);
        std::printf("(true tilt zeros folded into the mounts' pitch) -> %s/views.yaml\n",
                    dir->c_str());
        return 0;
      }
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
