// fovea render: both cameras' images and their true depth at one stage state.
#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include "commands.h"
#include "experiments/output/output.h"
#include "scene_options.h"

namespace experiments {
namespace {

nlohmann::json PoseJson(const Eigen::Isometry3d& pose) {
  nlohmann::json j;
  j["translation_m"] = {pose.translation().x(), pose.translation().y(), pose.translation().z()};
  nlohmann::json rows = nlohmann::json::array();
  for (int r = 0; r < 3; ++r)
    rows.push_back({pose.linear()(r, 0), pose.linear()(r, 1), pose.linear()(r, 2)});
  j["rotation"] = rows;
  return j;
}

struct RenderArgs {
  SceneOptions scene;
  std::string out;
  bool force = false;
};

int Render(const RenderArgs& args) {
  RunConfig config;
  config.rig.noise.read_noise_sigma_dn = 0;  // render shows the scene as it is, unless --noise
  args.scene.ApplyTo(&config);
  const std::optional<rig::StageState> asked = args.scene.TargetState();
  OutputFolder folder(args.out, "--out", ExistingPolicy(args.force));
  auto sim = LoadSceneOf(config);
  rig::Rig& rig = sim->rig();
  const rig::StageState target = asked ? *asked : rig.Home();
  const std::string violation = rig.Limits().Violation(target);
  if (!violation.empty()) throw UsageError("stage state refused: " + violation);

  const rig::MoveResult move = rig.MoveTo(target);
  const rig::StereoFrame frame = rig.Capture({/*color=*/true});
  const std::string dir = folder.path();
  nlohmann::json meta;
  meta["scene"] = sim->scene_path();
  meta["motion_time_s"] = move.motion_time_s;
  const auto q = frame.state.ToArray();
  meta["state"] = {{"left_baseline_m", q[0]},  {"left_pan_rad", q[1]},  {"left_tilt_rad", q[2]},
                   {"right_baseline_m", q[3]}, {"right_pan_rad", q[4]}, {"right_tilt_rad", q[5]}};
  for (rig::Side side : {rig::Side::kLeft, rig::Side::kRight}) {
    const rig::CameraView& view = frame[side];
    const std::string name = rig::SideName(side);
    const sim::TrueView truth = sim->truth().Render(view.world_T_camera, view.intrinsics);
    WriteImageAtomic(dir + "/" + name + ".png", view.bgr);
    WriteImageAtomic(dir + "/depth_" + name + ".png", ColorizeDepth(truth.depth_m));
    cv::Mat depth_mm;
    truth.depth_m.convertTo(depth_mm, CV_16U, 1000.0);
    WriteImageAtomic(dir + "/depth_" + name + "_mm.png", depth_mm);
    const rig::CameraIntrinsics& k = view.intrinsics;
    meta[name] = {{"intrinsics",
                   {{"fx_px", k.fx_px},
                    {"fy_px", k.fy_px},
                    {"cx_px", k.cx_px},
                    {"cy_px", k.cy_px},
                    {"width_px", k.width_px},
                    {"height_px", k.height_px}}},
                  {"world_T_camera", PoseJson(view.world_T_camera)}};
  }
  WriteTextAtomic(dir + "/render.json", meta.dump(2) + "\n");
  folder.Commit();
  std::fprintf(stderr, "fovea render: %s at %s -> %s\n", sim->scene_path().c_str(),
               frame.state.ToString().c_str(), folder.target().c_str());
  return 0;
}

}  // namespace

void AddRenderCommand(CLI::App& app, std::function<int()>* run) {
  auto args = std::make_shared<RenderArgs>();
  CLI::App* cmd = app.add_subcommand(
      "render", "write both cameras' images and their colour-mapped true depth as PNG");
  args->scene.Register(cmd, /*with_state=*/true);
  cmd->add_option("--out", args->out, "output folder (new, or empty)")->required();
  AddForceFlag(cmd, &args->force);
  cmd->callback([args, run] { *run = [args] { return Render(*args); }; });
}

}  // namespace experiments
