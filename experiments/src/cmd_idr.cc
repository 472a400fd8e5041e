// fovea idr: initial depth recovery on a scene, with its figures and pictures.
#include <opencv2/imgproc.hpp>

#include "commands.h"
#include "idr_eval.h"
#include "output.h"
#include "run_output.h"
#include "scene_options.h"

namespace experiments {
namespace {

struct IdrArgs {
  SceneOptions scene;
  std::string out;
  fovea::IdrOptions idr;
};

int Idr(const IdrArgs& args) {
  args.idr.Check();
  auto sim = args.scene.Load();
  const fovea::IdrResult r = fovea::RunIdr(sim->rig(), args.idr);
  const IdrScore score = ScoreIdr(r, sim->truth());
  EnsureDirectory(args.out);

  const rig::CameraView& left = r.final_frame.left;
  const double b = (r.final_frame.right.world_T_camera.translation() - left.world_T_camera.translation()).norm();
  // Matched crossings' disparities over the dimmed left image.
  cv::Mat disparity;
  cv::cvtColor(left.gray / 2, disparity, cv::COLOR_GRAY2BGR);
  double d_lo = 1e9, d_hi = -1e9;
  for (const auto& m : r.final_samples) d_lo = std::min(d_lo, m.disparity_px), d_hi = std::max(d_hi, m.disparity_px);
  for (const auto& m : r.final_samples) {
    cv::Mat v(1, 1, CV_8U, cv::Scalar(255 * (m.disparity_px - d_lo) / std::max(1e-6, d_hi - d_lo)));
    cv::Mat c;
    cv::applyColorMap(v, c, cv::COLORMAP_TURBO);
    cv::circle(disparity, {int(m.x_px + 0.5), int(m.y_px)}, 1, cv::Scalar(c.at<cv::Vec3b>(0, 0)), cv::FILLED);
  }
  WriteImageAtomic(args.out + "/disparity.png", disparity);
  // Patch depth beside true depth, one colour scale.
  WriteImageAtomic(args.out + "/patch_depth_vs_true.png", PatchDepthBesideTruth(r.map, left, sim->truth()));

  nlohmann::json j = IdrJson(r, score);
  j["scene"] = sim->scene_path();
  j["final_baseline_m"] = b;
  WriteTextAtomic(args.out + "/idr.json", j.dump(2) + "\n");
  std::fprintf(stderr,
               "fovea idr: %zu stages, final baseline %.4f m (%s); %d patches, median error %.2f "
               "steps, %d of %d matches wrong -> %s\n",
               r.stages.size(), b, r.stop_reason.c_str(), score.patches, score.median_error_steps,
               score.wrong_matches, score.matches, args.out.c_str());
  return 0;
}

}  // namespace

void AddIdrCommand(CLI::App& app, std::function<int()>* run) {
  auto args = std::make_shared<IdrArgs>();
  CLI::App* cmd = app.add_subcommand("idr", "initial depth recovery: adaptive variable-baseline stereo");
  args->scene.Register(cmd, /*with_state=*/false);
  args->scene.noise_sigma_dn = 2.0;  // experiments run with noise on
  cmd->add_option("--out", args->out, "output folder")->required();
  cmd->add_option("--sigma", args->idr.zero_crossings.sigma_px, "LoG sigma, px")->capture_default_str();
  cmd->add_option("--unique-share", args->idr.unique_share, "share of unambiguous crossings at B0")->capture_default_str();
  cmd->add_option("--patch-size", args->idr.patch_size_px, "patch size, px")->capture_default_str();
  cmd->add_option("--initial-baseline", args->idr.fixed_initial_baseline_m,
                  "fixed initial baseline in metres instead of the period rule (0 = rule)")->capture_default_str();
  cmd->add_flag("--take-nearest", args->idr.matching.take_nearest_when_ambiguous,
                "resolve ambiguous matches by the smallest disparity instead of rejecting them");
  cmd->callback([args, run] { *run = [args] { return Idr(*args); }; });
}

}  // namespace experiments
