// fovea idr: initial depth recovery on a scene, with its figures and pictures.
#include <opencv2/imgproc.hpp>

#include "commands.h"
#include "experiments/output/output.h"
#include "experiments/output/run_output.h"
#include "experiments/scoring/idr_eval.h"
#include "scene_options.h"

namespace experiments {
namespace {

struct IdrArgs {
  SceneOptions scene;
  std::string out, sigma, unique_share, patch_size, initial_baseline;
  bool take_nearest = false, force = false;
};

int Idr(const IdrArgs& args) {
  RunConfig config;  // the run's defaults: noise on
  args.scene.ApplyTo(&config);
  if (!args.sigma.empty()) SetParamFromFlag(&config, "--sigma", "idr.log_sigma_px", args.sigma);
  if (!args.unique_share.empty())
    SetParamFromFlag(&config, "--unique-share", "idr.unique_share", args.unique_share);
  if (!args.patch_size.empty())
    SetParamFromFlag(&config, "--patch-size", "idr.patch_size_px", args.patch_size);
  config.Check();
  fovea::IdrOptions idr = config.fovea.idr;
  if (!args.initial_baseline.empty())
    idr.fixed_initial_baseline_m = *ParseNumber(args.initial_baseline);
  idr.matching.take_nearest_when_ambiguous = args.take_nearest;
  OutputFolder folder(args.out, "--out", ExistingPolicy(args.force));
  auto sim = LoadSceneOf(config);
  const fovea::IdrResult r = fovea::RunIdr(sim->rig(), idr);
  const IdrScore score = ScoreIdr(r, sim->truth());
  const std::string dir = folder.path();

  const rig::CameraView& left = r.final_frame.left;
  const double b =
      (r.final_frame.right.world_T_camera.translation() - left.world_T_camera.translation()).norm();
  // Matched crossings' disparities over the dimmed left image.
  cv::Mat disparity;
  cv::cvtColor(left.gray / 2, disparity, cv::COLOR_GRAY2BGR);
  double d_lo = 1e9, d_hi = -1e9;
  for (const auto& m : r.final_samples)
    d_lo = std::min(d_lo, m.disparity_px), d_hi = std::max(d_hi, m.disparity_px);
  for (const auto& m : r.final_samples) {
    cv::Mat v(1, 1, CV_8U, cv::Scalar(255 * (m.disparity_px - d_lo) / std::max(1e-6, d_hi - d_lo)));
    cv::Mat c;
    cv::applyColorMap(v, c, cv::COLORMAP_TURBO);
    cv::circle(disparity, {int(m.x_px + 0.5), int(m.y_px)}, 1, cv::Scalar(c.at<cv::Vec3b>(0, 0)),
               cv::FILLED);
  }
  WriteImageAtomic(dir + "/disparity.png", disparity);
  // Patch depth beside true depth, one colour scale.
  WriteImageAtomic(dir + "/patch_depth_vs_true.png",
                   PatchDepthBesideTruth(r.map, left, sim->truth()));

  nlohmann::json j = IdrJson(r, score);
  j["scene"] = sim->scene_path();
  j["final_baseline_m"] = b;
  WriteTextAtomic(dir + "/idr.json", j.dump(2) + "\n");
  folder.Commit();
  std::fprintf(stderr,
               "fovea idr: %zu stages, final baseline %.4f m (%s); %d patches, median error %.2f "
               "steps, %d of %d matches wrong -> %s\n",
               r.stages.size(), b, r.stop_reason.c_str(), score.patches, score.median_error_steps,
               score.wrong_matches, score.matches, folder.target().c_str());
  return 0;
}

}  // namespace

void AddIdrCommand(CLI::App& app, std::function<int()>* run) {
  auto args = std::make_shared<IdrArgs>();
  CLI::App* cmd =
      app.add_subcommand("idr", "initial depth recovery: adaptive variable-baseline stereo");
  args->scene.Register(cmd, /*with_state=*/false);
  cmd->add_option("--out", args->out, "output folder (new, or empty)")->required();
  AddForceFlag(cmd, &args->force);
  cmd->add_option("--sigma", args->sigma, "LoG sigma, px (idr.log_sigma_px)");
  cmd->add_option("--unique-share", args->unique_share,
                  "share of unambiguous crossings at B0 (idr.unique_share)");
  cmd->add_option("--patch-size", args->patch_size, "patch size, px (idr.patch_size_px)");
  cmd->add_option("--initial-baseline", args->initial_baseline,
                  "fixed initial baseline in metres instead of the period rule (0 = rule)")
      ->check(NumberIn(0, 1));
  cmd->add_flag("--take-nearest", args->take_nearest,
                "resolve ambiguous matches by the smallest disparity instead of rejecting them");
  cmd->callback([args, run] { *run = [args] { return Idr(*args); }; });
}

}  // namespace experiments
