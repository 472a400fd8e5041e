// fovea fixate: IDR, then one fixation with foveated vergent stereo.
#include <opencv2/imgproc.hpp>

#include "commands.h"
#include "experiments/output/output.h"
#include "experiments/output/run_output.h"
#include "experiments/scoring/foveal_eval.h"
#include "fovea/ddr.h"
#include "fovea/sgbm.h"
#include "scene_options.h"

namespace experiments {
namespace {

struct FixateArgs {
  SceneOptions scene;
  std::vector<std::string> point;
  std::string out, matcher, baseline;
  bool force = false;
};

int Fixate(const FixateArgs& args) {
  RunConfig config;  // the run's defaults: noise on
  args.scene.ApplyTo(&config);
  if (!args.baseline.empty())
    SetParamFromFlag(&config, "--baseline", "foveal.baseline_m", args.baseline);
  if (!args.matcher.empty()) SetParamFromFlag(&config, "--matcher", "matcher", args.matcher);
  config.Check();
  const Eigen::Vector3d p(*ParseNumber(args.point[0]), *ParseNumber(args.point[1]),
                          *ParseNumber(args.point[2]));
  OutputFolder folder(args.out, "--out", ExistingPolicy(args.force));
  auto sim = LoadSceneOf(config);
  rig::Rig& rig = sim->rig();
  const fovea::IdrResult idr = fovea::RunIdr(rig, config.fovea.idr);
  const std::unique_ptr<fovea::StereoMatcher> matcher =
      fovea::MakeMatcher(config.matcher, config.fovea);
  const fovea::FixationResult r =
      fovea::Fixate(rig, idr.map, p, *matcher, fovea::ResolvedFixationOptions(config.fovea));
  if (!r.ok) {
    char at[96];
    std::snprintf(at, sizeof at, "(%.3f, %.3f, %.3f)", p.x(), p.y(), p.z());
    throw std::runtime_error(std::string("cannot fixate ") + at + ": " + r.why);
  }
  const FovealScore score = ScoreFoveal(r, sim->truth());
  const std::string dir = folder.path();

  const rig::CameraView& left = r.servo.frame.left;
  const fovea::Tessellation& t = r.foveal.tessellation;
  // Tessellation overlay: level rectangles, masked pixels tinted red.
  cv::Mat overlay;
  cv::cvtColor(left.gray, overlay, cv::COLOR_GRAY2BGR);
  overlay.setTo(cv::Scalar(60, 60, 200), t.mask == 0);
  const cv::Scalar colours[] = {{0, 255, 0},   {0, 200, 255},   {255, 160, 0},
                                {255, 0, 255}, {255, 255, 255}, {128, 128, 128}};
  for (size_t k = 0; k < t.rects.size(); ++k) cv::rectangle(overlay, t.rects[k], colours[k % 6], 2);
  cv::drawMarker(overlay, {int(left.intrinsics.cx_px), int(left.intrinsics.cy_px)}, {0, 0, 255},
                 cv::MARKER_CROSS, 20, 2);
  WriteImageAtomic(dir + "/tessellation.png", overlay);
  // Per-level disparity, colour-mapped, upsampled to full size.
  for (size_t k = 0; k < r.foveal.disparity_px.size(); ++k) {
    const cv::Mat& d = r.foveal.disparity_px[k];
    const cv::Mat valid = d == d;  // not NaN
    double lo = 0, hi = 0;
    if (cv::countNonZero(valid)) cv::minMaxLoc(d, &lo, &hi, nullptr, nullptr, valid);
    cv::Mat scaled, colour;
    d.convertTo(scaled, CV_8U, 255.0 / std::max(1e-6, hi - lo),
                -255.0 * lo / std::max(1e-6, hi - lo));
    cv::applyColorMap(scaled, colour, cv::COLORMAP_TURBO);
    colour.setTo(cv::Scalar(0, 0, 0), ~valid);
    cv::resize(colour, colour, left.gray.size(), 0, 0, cv::INTER_NEAREST);
    WriteImageAtomic(dir + "/disparity_level" + std::to_string(k) + ".png", colour);
  }
  // This fixation's patches beside the true depth, from the left camera.
  WriteImageAtomic(dir + "/patch_depth_vs_true.png",
                   PatchDepthBesideTruth(r.foveal.patches, left, sim->truth()));

  nlohmann::json j = FixationJson(r, score);
  j["scene"] = sim->scene_path();
  j["point_W"] = {p.x(), p.y(), p.z()};
  j["matcher"] = matcher->Name();
  WriteTextAtomic(dir + "/fixate.json", j.dump(2) + "\n");
  folder.Commit();
  std::fprintf(stderr,
               "fovea fixate: fovea %dx%d, %zu levels, %zu patches, foveal error %.3f steps, "
               "coverage %.3f -> %s\n",
               t.rects[0].width, t.rects[0].height, t.rects.size(), r.foveal.patches.size(),
               score.levels.empty() ? 0.0 : score.levels[0].median_error_steps,
               score.fovea_coverage, folder.target().c_str());
  return 0;
}

}  // namespace

void AddFixateCommand(CLI::App& app, std::function<int()>* run) {
  auto args = std::make_shared<FixateArgs>();
  CLI::App* cmd =
      app.add_subcommand("fixate", "IDR, then verge on a point and recover its foveated depth map");
  args->scene.Register(cmd, /*with_state=*/false);
  cmd->add_option("--point", args->point, "fixation point X Y Z in the world, metres")
      ->required()
      ->expected(3)
      ->check(NumberIn(-100, 100));
  cmd->add_option("--out", args->out, "output folder (new, or empty)")->required();
  AddForceFlag(cmd, &args->force);
  cmd->add_option("--baseline", args->baseline, "vergent baseline, metres (foveal.baseline_m)");
  cmd->add_option("--matcher", args->matcher,
                  "per-level matcher: nl1 (the paper's cost) or sgbm (matcher)");
  cmd->callback([args, run] { *run = [args] { return Fixate(*args); }; });
}

}  // namespace experiments
