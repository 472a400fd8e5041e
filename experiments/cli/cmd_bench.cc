// fovea bench: speed figures printed by the program, never asserted in tests.
#include <algorithm>
#include <chrono>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "experiments/output/output.h"
#include "fovea/geometry.h"
#include "fovea/stats.h"
#include "scene_options.h"

namespace experiments {
void AddBenchFixationCommand(CLI::App& bench, std::function<int()>* run);
namespace {

struct BenchRenderArgs {
  SceneOptions scene;
  int frames = 20;
  bool json = false;
};

int BenchRender(const BenchRenderArgs& args) {
  using Clock = std::chrono::steady_clock;
  RunConfig config;
  config.rig.noise.read_noise_sigma_dn = 0;  // rendering speed alone, unless --noise
  args.scene.ApplyTo(&config);
  auto sim = LoadSceneOf(config);
  rig::Rig& rig = sim->rig();
  rig.Capture();  // warm-up: texture upload, JIT of the software rasterizer
  auto seconds = [](Clock::time_point t0) {
    return std::chrono::duration<double>(Clock::now() - t0).count();
  };
  auto t0 = Clock::now();
  for (int i = 0; i < args.frames; ++i) rig.Capture();
  const double stereo_gray_s = seconds(t0);
  t0 = Clock::now();
  for (int i = 0; i < args.frames; ++i) rig.Capture({/*color=*/true});
  const double stereo_color_s = seconds(t0);
  const rig::StereoFrame frame = rig.Capture();
  t0 = Clock::now();
  for (int i = 0; i < args.frames; ++i)
    sim->truth().Render(frame.left.world_T_camera, frame.left.intrinsics);
  const double depth_s = seconds(t0);
  // The reference view's ground truth as a run computes it (depth and
  // surface labels), against exact ray casting of every pixel.
  t0 = Clock::now();
  int truth_ray_cast = 0;
  for (int i = 0; i < args.frames; ++i)
    truth_ray_cast =
        sim->truth().RenderLabels(frame.left.world_T_camera, frame.left.intrinsics).ray_cast;
  const double labels_s = seconds(t0) / args.frames;
  t0 = Clock::now();
  sim->truth().RayCastDepth(frame.left.world_T_camera, frame.left.intrinsics);
  const double raycast_s = seconds(t0);

  const auto& k = frame.left.intrinsics;
  nlohmann::json j = {
      {"scene", sim->scene_path()},
      {"width_px", k.width_px},
      {"height_px", k.height_px},
      {"frames", args.frames},
      {"camera_images_per_s", 2 * args.frames / stereo_gray_s},
      {"stereo_pairs_per_s", args.frames / stereo_gray_s},
      {"stereo_pairs_color_per_s", args.frames / stereo_color_s},
      {"true_depth_images_per_s", args.frames / depth_s},
      {"raycast_depth_image_s", raycast_s},
      {"truth_labels_s", labels_s},
      {"truth_labels_ray_cast_px", truth_ray_cast},
      {"truth_labels_over_stereo_pair", labels_s / (stereo_gray_s / args.frames)},
  };
  if (args.json) {
    std::printf("%s\n", j.dump().c_str());
  } else {
    std::printf("render benchmark, %s, %dx%d, %d frames\n", sim->scene_path().c_str(), k.width_px,
                k.height_px, args.frames);
    std::printf("  camera images (gray, noise model)   %7.1f frames/s\n",
                j["camera_images_per_s"].get<double>());
    std::printf("  stereo pairs (gray)                 %7.1f pairs/s\n",
                j["stereo_pairs_per_s"].get<double>());
    std::printf("  stereo pairs (gray + colour)        %7.1f pairs/s\n",
                j["stereo_pairs_color_per_s"].get<double>());
    std::printf("  true depth (OpenGL depth buffer)    %7.1f images/s\n",
                j["true_depth_images_per_s"].get<double>());
    std::printf("  true depth (exact ray casting)      %7.3f s per image\n", raycast_s);
    std::printf(
        "  true depth and labels (rendered)    %7.3f s per image (%.2f stereo pairs; %d pixels "
        "ray cast)\n",
        labels_s, j["truth_labels_over_stereo_pair"].get<double>(), truth_ray_cast);
  }
  return 0;
}

}  // namespace

void AddBenchCommand(CLI::App& app, std::function<int()>* run) {
  CLI::App* bench = app.add_subcommand("bench", "speed benchmarks (figures for the README)");
  bench->require_subcommand(1);
  auto args = std::make_shared<BenchRenderArgs>();
  CLI::App* render = bench->add_subcommand("render", "offscreen rendering speed");
  args->scene.Register(render, /*with_state=*/false);
  render->add_option("--frames", args->frames, "frames per measurement")
      ->check(CLI::Range(1, 10000));
  render->add_flag("--json", args->json, "one JSON object on stdout");
  render->callback([args, run] { *run = [args] { return BenchRender(*args); }; });
  AddBenchFixationCommand(*bench, run);
}

}  // namespace experiments

// fovea bench fixation: the foveated process against full-resolution NL1
// and against StereoSGBM on the rectified full frame, one run, one machine.
#include <opencv2/imgproc.hpp>

#include "experiments/scoring/foveal_eval.h"
#include "fovea/idr.h"
#include "fovea/sgbm.h"

namespace experiments {
namespace {

struct BenchFixationArgs {
  SceneOptions scene;
  std::vector<std::string> point{"0", "0.89", "0"};
  int repeat = 5;
  bool json = false;
  std::vector<std::string> set;  ///< KEY=VALUE parameters
};

// The whole-frame matchers against the fovea's, on one fixation's frame over
// the depths the fovea searches (Z_T about the fixation depth), with their
// disparity errors on the foveal pixels (level 0, unmasked, with truth).
struct WholeFrame {
  double full_ms = 0, sgbm_ms = 0;
  std::vector<double> full_err, sgbm_err;
  int fovea_pixels = 0;
  double d_lo = 0, d_hi = 0;
};

WholeFrame MatchWholeFrame(const fovea::FixationResult& r, const fovea::Nl1Matcher& nl1,
                           const sim::GroundTruth& truth, int repeat) {
  using Clock = std::chrono::steady_clock;
  auto ms = [](Clock::time_point t0) {
    return 1e3 * std::chrono::duration<double>(Clock::now() - t0).count();
  };
  // The frame the fovea matched in: the whole-frame matchers see the same images.
  const rig::StereoFrame& frame = r.foveal.frame.views;
  const rig::CameraView& left = frame.left;
  const rig::CameraIntrinsics& k = left.intrinsics;
  const fovea::Tessellation& t = r.foveal.tessellation;
  const Eigen::Isometry3d right_T_left = frame.right.world_T_camera.inverse() * left.world_T_camera;
  auto disparity_at = [&](double u, double v, double z) {
    return fovea::DisparityAtDepth(left, frame.right, right_T_left, u, v, z);
  };
  WholeFrame w;
  const double z_near = t.fixation_depth_m - t.z_t_near_m, z_far = t.fixation_depth_m + t.z_t_far_m;
  w.d_lo = std::min(disparity_at(k.cx_px, k.cy_px, z_far), disparity_at(k.cx_px, k.cy_px, z_near));
  w.d_hi = std::max(disparity_at(k.cx_px, k.cy_px, z_far), disparity_at(k.cx_px, k.cy_px, z_near));
  // Each timed `repeat` times; the median.
  std::vector<double> full_ms, sgbm_ms;
  fovea::DisparityMap full;
  cv::Mat sgbm_depth;
  for (int i = 0; i < repeat; ++i) {
    auto t0 = Clock::now();
    full = nl1.Match(left.gray, frame.right.gray,
                     cv::Mat(left.gray.size(), CV_32F, cv::Scalar(w.d_lo - 1)),
                     cv::Mat(left.gray.size(), CV_32F, cv::Scalar(w.d_hi + 1)));
    full_ms.push_back(ms(t0));
    t0 = Clock::now();
    sgbm_depth = fovea::RectifiedSgbmDepth(left, frame.right, z_near, z_far);
    sgbm_ms.push_back(ms(t0));
  }
  w.full_ms = fovea::Quantile(full_ms, 0.5, 0.0);
  w.sgbm_ms = fovea::Quantile(sgbm_ms, 0.5, 0.0);
  const cv::Mat true_depth = truth.RenderLabels(left.world_T_camera, k).depth_m;
  const cv::Rect& fovea = t.rects[0];
  for (int v = fovea.y; v < fovea.y + fovea.height; ++v)
    for (int u = fovea.x; u < fovea.x + fovea.width; ++u) {
      const float zt = true_depth.at<float>(v, u);
      if (zt <= 0 || !t.mask.at<uchar>(v, u)) continue;
      ++w.fovea_pixels;
      const double dt = disparity_at(u, v, zt);
      const float df = full.disparity_px.at<float>(v, u);
      if (std::isfinite(df)) w.full_err.push_back(std::abs(df - dt));
      const float zs = sgbm_depth.at<float>(v, u);
      if (zs > 0) w.sgbm_err.push_back(std::abs(disparity_at(u, v, zs) - dt));
    }
  return w;
}

int BenchFixation(const BenchFixationArgs& args) {
  RunConfig config;  // the run's defaults: noise on
  SetParams(&config, args.set);
  args.scene.ApplyTo(&config);
  config.Check();
  const Eigen::Vector3d p(*ParseNumber(args.point[0]), *ParseNumber(args.point[1]),
                          *ParseNumber(args.point[2]));
  auto sim = LoadSceneOf(config);
  rig::Rig& rig = sim->rig();
  const fovea::IdrResult idr = fovea::RunIdr(rig, config.fovea.idr);
  const fovea::Nl1Matcher nl1(config.fovea.nl1);
  const fovea::FixationResult r =
      fovea::Fixate(rig, idr.map, p, nl1, fovea::ResolvedFixationOptions(config.fovea));
  if (!r.ok) throw std::runtime_error("cannot fixate the benchmark point: " + r.why);
  const FovealScore score = ScoreFoveal(r, sim->truth());
  // The foveated matching (every level's, and the wide search for silent
  // pixels) of the same fixation, `repeat` times: the median.
  auto matching_ms = [](const fovea::FovealResult& f) {
    double ms = 1e3 * f.silent_check_time_s;
    for (const auto& level : f.levels) ms += 1e3 * level.match_time_s;
    return ms;
  };
  // Where the median repeat's time went: the wide search, and each level's
  // search ranges and matching (finest first), with the pixels each level
  // searched.
  struct Breakdown {
    double total_ms = 0, silent_ms = 0;
    std::vector<double> level_ms;
  };
  std::vector<Breakdown> repeats;
  for (int i = 0; i < args.repeat; ++i) {
    const fovea::FovealResult f =
        i == 0 ? r.foveal
               : fovea::FovealStereo(r.servo.measured, r.fixation_W, idr.map, nl1,
                                     fovea::ResolvedFixationOptions(config.fovea).foveal);
    Breakdown b{matching_ms(f), 1e3 * f.silent_check_time_s, {}};
    for (const auto& level : f.levels) b.level_ms.push_back(1e3 * level.match_time_s);
    repeats.push_back(b);
  }
  std::sort(repeats.begin(), repeats.end(),
            [](const Breakdown& a, const Breakdown& b) { return a.total_ms < b.total_ms; });
  const Breakdown& median_repeat = repeats[repeats.size() / 2];
  const double foveated_ms = median_repeat.total_ms;
  nlohmann::json levels_ms = median_repeat.level_ms, searched = nlohmann::json::array();
  for (const auto& level : r.foveal.levels) searched.push_back(level.searched);
  const WholeFrame w = MatchWholeFrame(r, nl1, sim->truth(), args.repeat);
  const fovea::Tessellation& t = r.foveal.tessellation;
  const cv::Rect& fovea = t.rects[0];
  auto median = [](const std::vector<double>& e) { return fovea::Quantile(e, 0.5, std::nan("")); };
  auto share = [&](const std::vector<double>& e) {
    return w.fovea_pixels ? double(e.size()) / w.fovea_pixels : 0.0;
  };
  const nlohmann::json j = {{"scene", sim->scene_path()},
                            {"fovea_px", {fovea.width, fovea.height}},
                            {"levels", t.rects.size()},
                            {"repeat", args.repeat},
                            {"foveated_ms", foveated_ms},
                            {"full_res_ms", w.full_ms},
                            {"sgbm_ms", w.sgbm_ms},
                            {"foveal_error_px", score.levels[0].median_disparity_error_px},
                            {"full_res_error_px", median(w.full_err)},
                            {"sgbm_error_px", median(w.sgbm_err)},
                            {"full_res_fovea_coverage", share(w.full_err)},
                            {"sgbm_fovea_coverage", share(w.sgbm_err)},
                            {"foveal_coverage", score.fovea_coverage},
                            {"disparity_range_px", {w.d_lo, w.d_hi}},
                            {"full_res_over_foveated", w.full_ms / foveated_ms},
                            {"sgbm_over_foveated", w.sgbm_ms / foveated_ms},
                            {"silent_check_ms", median_repeat.silent_ms},
                            {"level_ms", levels_ms},
                            {"level_searched_px", searched}};
  if (args.json) {
    std::printf("%s\n", j.dump().c_str());
    return 0;
  }
  std::printf("fixation benchmark, %s, fovea %dx%d, %zu levels, median of %d\n",
              sim->scene_path().c_str(), fovea.width, fovea.height, t.rects.size(), args.repeat);
  std::printf("  foveated NL1 (all levels)   %8.1f ms   foveal error %.3f px\n", foveated_ms,
              j["foveal_error_px"].get<double>());
  std::printf("    wide search of silent pixels %6.1f ms\n", j["silent_check_ms"].get<double>());
  for (size_t l = 0; l < levels_ms.size(); ++l)
    std::printf("    level %zu (ranges, matching) %6.1f ms, %d pixels searched\n", l,
                levels_ms[l].get<double>(), searched[l].get<int>());
  std::printf("  full-resolution NL1         %8.1f ms   foveal error %.3f px  (%.1fx the time)\n",
              w.full_ms, j["full_res_error_px"].get<double>(), w.full_ms / foveated_ms);
  std::printf("  StereoSGBM, rectified frame %8.1f ms   foveal error %.3f px  (%.1fx the time)\n",
              w.sgbm_ms, j["sgbm_error_px"].get<double>(), w.sgbm_ms / foveated_ms);
  return 0;
}

}  // namespace

void AddBenchFixationCommand(CLI::App& bench, std::function<int()>* run) {
  auto args = std::make_shared<BenchFixationArgs>();
  args->scene.scene = "cylinder_planes";
  CLI::App* cmd =
      bench.add_subcommand("fixation", "foveated matching vs full-resolution NL1 vs StereoSGBM");
  args->scene.Register(cmd, /*with_state=*/false);
  cmd->add_option("--point", args->point, "fixation point X Y Z, metres")
      ->expected(3)
      ->check(NumberIn(-100, 100))
      ->capture_default_str();
  cmd->add_option("--repeat", args->repeat, "times each matcher runs; the median")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  cmd->add_option("--set", args->set,
                  "KEY=VALUE: set one parameter (repeatable), e.g. nl1.cost=window_mean");
  cmd->add_flag("--json", args->json, "one JSON object on stdout");
  cmd->callback([args, run] { *run = [args] { return BenchFixation(*args); }; });
}

}  // namespace experiments
