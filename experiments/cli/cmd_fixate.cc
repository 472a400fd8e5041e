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
  std::vector<std::string> set;
  bool force = false;
};

const cv::Scalar kLevelColours[] = {{0, 255, 0},   {0, 200, 255},   {255, 160, 0},
                                    {255, 0, 255}, {255, 255, 255}, {128, 128, 128}};

// A view with the tessellation's level rectangles: drawn as they are in the
// frame matched in (H = identity), or mapped back through H^-1 onto the
// original image (quadrilaterals); masked pixels tinted red when given.
cv::Mat DrawLevels(const rig::CameraView& view, const fovea::Tessellation& t, const cv::Matx33d& H,
                   const cv::Mat& mask, const std::string& title) {
  const rig::CameraIntrinsics& k = view.intrinsics;
  const cv::Mat& gray = view.gray;
  cv::Mat out;
  cv::cvtColor(gray, out, cv::COLOR_GRAY2BGR);
  if (!mask.empty()) out.setTo(cv::Scalar(60, 60, 200), mask == 0);
  const cv::Matx33d back = H.inv();
  for (size_t k = 0; k < t.rects.size(); ++k) {
    const cv::Rect& r = t.rects[k];
    const std::vector<cv::Point2d> corners =
        fovea::MapPixels(back, {{r.x - 0.5, r.y - 0.5},
                                {r.x + r.width - 0.5, r.y - 0.5},
                                {r.x + r.width - 0.5, r.y + r.height - 0.5},
                                {r.x - 0.5, r.y + r.height - 0.5}});
    std::vector<cv::Point> poly;
    for (const cv::Point2d& c : corners) poly.emplace_back(cvRound(c.x), cvRound(c.y));
    cv::polylines(out, poly, true, kLevelColours[k % 6], 2);
  }
  // The principal point: a roll about it leaves it in place.
  cv::drawMarker(out, {cvRound(k.cx_px), cvRound(k.cy_px)}, {0, 0, 255}, cv::MARKER_CROSS, 20, 2);
  cv::putText(out, title, {8, 22}, cv::FONT_HERSHEY_SIMPLEX, 0.6, {0, 255, 255}, 2);
  return out;
}

// Left and right side by side.
cv::Mat SideBySide(const cv::Mat& a, const cv::Mat& b) {
  cv::Mat out;
  cv::hconcat(a, b, out);
  return out;
}

// The fixation's pictures in `dir`: the levels on both views, as matched
// and mapped back onto the original images; disparities per level; the
// patches' depth beside the truth.
void WritePictures(const fovea::FixationResult& r, const sim::GroundTruth& truth,
                   const std::string& dir) {
  // Everything the fovea computed is in the frame it matched in.
  const fovea::FixationFrame& matched = r.foveal.frame;
  const rig::CameraView& left = matched.views.left;
  const fovea::Tessellation& t = r.foveal.tessellation;
  // Level rectangles on both views: as matched, and mapped back onto the
  // original images; masked pixels tinted red.
  const cv::Matx33d I = cv::Matx33d::eye();
  const std::string frame_name = matched.resampled ? "fixation frame" : "original frame";
  const cv::Mat left_matched = DrawLevels(left, t, I, t.mask, "left, " + frame_name);
  WriteImageAtomic(dir + "/tessellation.png", left_matched);
  WriteImageAtomic(dir + "/fovea_matched.png",
                   SideBySide(left_matched, DrawLevels(matched.views.right, t, I, cv::Mat(),
                                                       "right, " + frame_name)));
  WriteImageAtomic(
      dir + "/fovea_original.png",
      SideBySide(
          DrawLevels(r.servo.frame.left, t, matched.left_H, cv::Mat(), "left, original"),
          DrawLevels(r.servo.frame.right, t, matched.right_H, cv::Mat(), "right, original")));
  // Per-level disparity, colour-mapped, upsampled to full size (and the
  // outermost level's in the rectified pair, foveal.rectified_periphery).
  std::vector<std::pair<std::string, cv::Mat>> disparities;
  for (size_t k = 0; k < r.foveal.disparity_px.size(); ++k)
    disparities.emplace_back("disparity_level" + std::to_string(k), r.foveal.disparity_px[k]);
  if (!r.foveal.rectified_periphery_px.empty())
    disparities.emplace_back("disparity_rectified_periphery", r.foveal.rectified_periphery_px);
  for (const auto& [name, d] : disparities) {
    const cv::Mat valid = d == d;  // not NaN
    double lo = 0, hi = 0;
    if (cv::countNonZero(valid)) cv::minMaxLoc(d, &lo, &hi, nullptr, nullptr, valid);
    cv::Mat scaled, colour;
    d.convertTo(scaled, CV_8U, 255.0 / std::max(1e-6, hi - lo),
                -255.0 * lo / std::max(1e-6, hi - lo));
    cv::applyColorMap(scaled, colour, cv::COLORMAP_TURBO);
    colour.setTo(cv::Scalar(0, 0, 0), ~valid);
    cv::resize(colour, colour, left.gray.size(), 0, 0, cv::INTER_NEAREST);
    WriteImageAtomic(dir + "/" + name + ".png", colour);
  }
  // This fixation's patches beside the true depth, from the left camera.
  WriteImageAtomic(dir + "/patch_depth_vs_true.png",
                   PatchDepthBesideTruth(r.foveal.patches, left, truth));
}

int Fixate(const FixateArgs& args) {
  RunConfig config;  // the run's defaults: noise on
  SetParams(&config, args.set);
  args.scene.ApplyTo(&config);
  // The point fixated is the one asked for: --baseline is its baseline,
  // whether the IDR map holds it or not.
  if (!args.baseline.empty()) {
    SetParamFromFlag(&config, "--baseline", "foveal.baseline_m", args.baseline);
    SetParamFromFlag(&config, "--baseline", "foveal.mapped_baseline_m", args.baseline);
  }
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
  WritePictures(r, sim->truth(), dir);
  // The paper's tessellation of the original pair, for comparison.
  const fovea::Tessellation unrolled =
      fovea::Tessellate(r.servo.frame.left, r.servo.frame.right, r.fixation_W, idr.map,
                        config.fovea.fixation.foveal.tessellation);
  nlohmann::json j = FixationJson(r, score);
  j["scene"] = sim->scene_path();
  j["point_W"] = {p.x(), p.y(), p.z()};
  j["matcher"] = matcher->Name();
  j["fovea_unrectified"] = {{"width_px", unrolled.rects[0].width},
                            {"height_px", unrolled.rects[0].height}};
  WriteTextAtomic(dir + "/fixate.json", j.dump(2) + "\n");
  folder.Commit();
  const fovea::Tessellation& t = r.foveal.tessellation;
  const std::string frame_name = r.foveal.frame.resampled ? "fixation frame" : "original frame";
  std::fprintf(stderr,
               "fovea fixate: fovea %dx%d in the %s (unrectified tessellation: %dx%d), %zu "
               "levels, %zu patches, foveal error %.3f steps, coverage %.3f -> %s\n",
               t.rects[0].width, t.rects[0].height, frame_name.c_str(), unrolled.rects[0].width,
               unrolled.rects[0].height, t.rects.size(), r.foveal.patches.size(),
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
  cmd->add_option("--baseline", args->baseline,
                  "vergent baseline, metres (foveal.baseline_m and foveal.mapped_baseline_m)");
  cmd->add_option("--set", args->set, "KEY=VALUE: set one parameter (repeatable)");
  cmd->add_option("--matcher", args->matcher,
                  "per-level matcher: nl1 (the paper's cost) or sgbm (matcher)");
  cmd->callback([args, run] { *run = [args] { return Fixate(*args); }; });
}

}  // namespace experiments
