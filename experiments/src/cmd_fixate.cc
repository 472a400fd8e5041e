// fovea fixate: IDR, then one fixation with foveated vergent stereo.
#include <opencv2/imgproc.hpp>

#include "commands.h"
#include "foveal_eval.h"
#include "fovea/idr.h"
#include "fovea/sgbm.h"
#include "output.h"
#include "run_output.h"
#include "scene_options.h"

namespace experiments {
namespace {

struct FixateArgs {
  SceneOptions scene;
  std::vector<double> point;
  std::string out;
  std::string matcher = "nl1";
  fovea::FixationOptions fixation;
};

int Fixate(const FixateArgs& args) {
  args.fixation.Check();
  auto sim = args.scene.Load();
  rig::Rig& rig = sim->rig();
  const fovea::IdrResult idr = fovea::RunIdr(rig, {});
  const Eigen::Vector3d p(args.point[0], args.point[1], args.point[2]);
  std::unique_ptr<fovea::StereoMatcher> matcher;
  if (args.matcher == "sgbm") matcher = std::make_unique<fovea::SgbmMatcher>();
  else matcher = std::make_unique<fovea::Nl1Matcher>();
  const fovea::FixationResult r = fovea::Fixate(rig, idr.map, p, *matcher, args.fixation);
  if (!r.ok) throw std::runtime_error("cannot fixate (" + std::to_string(p.x()) + ", " + std::to_string(p.y()) + ", " + std::to_string(p.z()) + "): " + r.why);
  const FovealScore score = ScoreFoveal(r, sim->truth());
  EnsureDirectory(args.out);

  const rig::CameraView& left = r.servo.frame.left;
  const fovea::Tessellation& t = r.foveal.tessellation;
  // Tessellation overlay: level rectangles, masked pixels tinted red.
  cv::Mat overlay;
  cv::cvtColor(left.gray, overlay, cv::COLOR_GRAY2BGR);
  overlay.setTo(cv::Scalar(60, 60, 200), t.mask == 0);
  const cv::Scalar colours[] = {{0, 255, 0}, {0, 200, 255}, {255, 160, 0}, {255, 0, 255}, {255, 255, 255}, {128, 128, 128}};
  for (size_t k = 0; k < t.rects.size(); ++k) cv::rectangle(overlay, t.rects[k], colours[k % 6], 2);
  cv::drawMarker(overlay, {int(left.intrinsics.cx_px), int(left.intrinsics.cy_px)}, {0, 0, 255}, cv::MARKER_CROSS, 20, 2);
  WriteImageAtomic(args.out + "/tessellation.png", overlay);
  // Per-level disparity, colour-mapped, upsampled to full size.
  for (size_t k = 0; k < r.foveal.disparity_px.size(); ++k) {
    const cv::Mat& d = r.foveal.disparity_px[k];
    const cv::Mat valid = d == d;  // not NaN
    double lo = 0, hi = 0;
    if (cv::countNonZero(valid)) cv::minMaxLoc(d, &lo, &hi, nullptr, nullptr, valid);
    cv::Mat scaled, colour;
    d.convertTo(scaled, CV_8U, 255.0 / std::max(1e-6, hi - lo), -255.0 * lo / std::max(1e-6, hi - lo));
    cv::applyColorMap(scaled, colour, cv::COLORMAP_TURBO);
    colour.setTo(cv::Scalar(0, 0, 0), ~valid);
    cv::resize(colour, colour, left.gray.size(), 0, 0, cv::INTER_NEAREST);
    WriteImageAtomic(args.out + "/disparity_level" + std::to_string(k) + ".png", colour);
  }
  // This fixation's patches beside the true depth, from the left camera.
  WriteImageAtomic(args.out + "/patch_depth_vs_true.png", PatchDepthBesideTruth(r.foveal.patches, left, sim->truth()));

  nlohmann::json j = FixationJson(r, score);
  j["scene"] = sim->scene_path();
  j["point_W"] = args.point;
  j["matcher"] = matcher->Name();
  WriteTextAtomic(args.out + "/fixate.json", j.dump(2) + "\n");
  std::fprintf(stderr, "fovea fixate: fovea %dx%d, %zu levels, %zu patches, foveal error %.3f steps, coverage %.3f -> %s\n",
               t.rects[0].width, t.rects[0].height, t.rects.size(), r.foveal.patches.size(),
               score.levels.empty() ? 0.0 : score.levels[0].median_error_steps, score.fovea_coverage, args.out.c_str());
  return 0;
}

}  // namespace

void AddFixateCommand(CLI::App& app, std::function<int()>* run) {
  auto args = std::make_shared<FixateArgs>();
  CLI::App* cmd = app.add_subcommand("fixate", "IDR, then verge on a point and recover its foveated depth map");
  args->scene.Register(cmd, /*with_state=*/false);
  args->scene.noise_sigma_dn = 2.0;
  cmd->add_option("--point", args->point, "fixation point X Y Z in the world, metres")->required()->expected(3);
  cmd->add_option("--out", args->out, "output folder")->required();
  cmd->add_option("--baseline", args->fixation.baseline_m, "vergent baseline, metres")->capture_default_str();
  cmd->add_option("--matcher", args->matcher, "per-level matcher: nl1 (the paper's cost) or sgbm")
      ->check(CLI::IsMember({"nl1", "sgbm"}))->capture_default_str();
  cmd->callback([args, run] { *run = [args] { return Fixate(*args); }; });
}

}  // namespace experiments
