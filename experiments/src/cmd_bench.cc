// fovea bench: speed figures printed by the program, never asserted in tests.
#include <chrono>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "output.h"
#include "scene_options.h"

namespace experiments {
namespace {

struct BenchRenderArgs {
  SceneOptions scene;
  int frames = 20;
  bool json = false;
};

int BenchRender(const BenchRenderArgs& args) {
  using Clock = std::chrono::steady_clock;
  auto sim = args.scene.Load();
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
  render->add_option("--frames", args->frames, "frames per measurement")->check(CLI::Range(1, 10000));
  render->add_flag("--json", args->json, "one JSON object on stdout");
  render->callback([args, run] { *run = [args] { return BenchRender(*args); }; });
}

}  // namespace experiments
