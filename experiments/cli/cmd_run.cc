// fovea run: the full FOVEA loop on a scene, scored against ground truth after
// every fixation; fovea config: the effective configuration.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>

#include "commands.h"
#include "experiments/config/config.h"
#include "experiments/output/output.h"
#include "experiments/output/run_output.h"
#include "experiments/scoring/baseline.h"
#include "experiments/scoring/run_eval.h"
#include "fovea/ddr.h"
#include "fovea/sgbm.h"
#include "fovea/timing.h"
#include "rig/hardware/hardware_rig.h"
#include "rig/hardware/indexer_emulator.h"
#include "scene_options.h"
#include "scenes/catalog.h"

namespace experiments {
namespace fs = std::filesystem;
namespace {

using fovea::Clock;
using fovea::Since;

struct RunArgs {
  std::string config_path;
  std::string scene, seed, fixations;  // as typed; "" = the config's
  bool deterministic = false;
  std::vector<std::string> set;
  std::string out;
  bool force = false;
};

nlohmann::json Vec(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

nlohmann::json RecordJson(const fovea::FixationRecord& r, const MapScore& score) {
  nlohmann::json j;
  j["attempt"] = r.attempt;
  j["fixation"] = r.fixation;
  j["ok"] = r.ok;
  if (!r.ok) j["why"] = r.why;
  const fovea::SelectionSummary& s = r.selection;
  j["selection"] = {{"pixel", {s.pixel.x(), s.pixel.y()}},
                    {"candidates", s.candidates},
                    {"composite_max", s.composite_max},
                    {"composite_chosen", s.composite_chosen},
                    {"drawn_value", s.drawn_value},
                    {"bin", s.bin},
                    {"in_hole", s.in_hole}};
  for (const auto& [name, v] : s.criteria) j["selection"]["criteria_vs_mean"][name] = v;
  j["target_W"] = Vec(r.target_W);
  j["motion_time_s"] = r.motion_time_s;
  j["time_s"] = {{"select", r.time.select_s},    {"verge", r.time.verge_s},
                 {"servo_wall", r.time.servo_s}, {"foveal", r.time.foveal_s},
                 {"match", r.time.match_s},      {"integrate", r.time.integrate_s}};
  if (r.ok) {
    j["fixation_W"] = Vec(r.fixation_W);
    const auto a = r.state.ToArray();
    j["stage_state"] = {{"left_baseline_m", a[0]}, {"left_pan_rad", a[1]},
                        {"left_tilt_rad", a[2]},   {"right_baseline_m", a[3]},
                        {"right_pan_rad", a[4]},   {"right_tilt_rad", a[5]}};
    j["placement"] = fovea::PlacementName(r.placement);
    j["servo"] = {{"iterations", r.servo_iterations},
                  {"residual_px", r.servo_residual_px},
                  {"converged", r.servo_converged}};
    j["tessellation"] = {{"fixation_depth_m", r.tessellation.fixation_depth_m},
                         {"z_t_near_m", r.tessellation.z_t_near_m},
                         {"z_t_far_m", r.tessellation.z_t_far_m},
                         {"levels", r.tessellation.rects.size()}};
    nlohmann::json levels = nlohmann::json::array();
    for (const fovea::LevelFigures& l : r.levels)
      levels.push_back({{"level", l.level},
                        {"rect", {l.rect.x, l.rect.y, l.rect.width, l.rect.height}},
                        {"searched", l.searched},
                        {"matched", l.matched},
                        {"patches", l.patches}});
    j["levels"] = levels;
    const fovea::IntegrationStats& in = r.integration;
    j["integration"] = {{"offered", in.offered},
                        {"added", in.added},
                        {"dropped_under_finer", in.dropped_under_finer},
                        {"replaced_idr", in.replaced[0]},
                        {"replaced_peripheral", in.replaced[1]},
                        {"replaced_foveal", in.replaced[2]}};
  }
  j["map_patches"] = {
      {"idr", r.map_by_level[0]}, {"peripheral", r.map_by_level[1]}, {"foveal", r.map_by_level[2]}};
  j["score"] = ScoreJson(score);
  return j;
}

RunConfig EffectiveConfig(const RunArgs& args) {
  RunConfig c = args.config_path.empty() ? RunConfig{} : LoadConfig(args.config_path);
  for (const std::string& kv : args.set) {
    const size_t eq = kv.find('=');
    if (eq == std::string::npos)
      throw UsageError("--set expects KEY=VALUE, got '" + rig::ClipForMessage(kv) + "'");
    SetParam(&c, kv.substr(0, eq), kv.substr(eq + 1));
  }
  if (!args.scene.empty()) SetParamFromFlag(&c, "--scene", "scene", args.scene);
  if (!args.seed.empty()) SetParamFromFlag(&c, "--seed", "seed", args.seed);
  if (!args.fixations.empty())
    SetParamFromFlag(&c, "--fixations", "loop.fixations", args.fixations);
  if (args.deterministic) c.fovea.selection.deterministic = true;
  if (c.scene.empty()) c.scene = scenes::kDefaultScene;
  c.Check();
  return c;
}

// The static StereoSGBM baseline, scored like a FOVEA run: summary.json with
// the same keys, map.ply, map.png, reference.png, an empty fixations.jsonl.
int RunStatic(const RunConfig& config, OutputFolder& folder, Clock::time_point t_wall) {
  auto sim = LoadSceneOf(config);
  rig::Rig& rig = sim->rig();
  const std::string dir = folder.path();
  WriteTextAtomic(dir + "/config.yaml", DumpConfig(config));
  const ReferenceView ref = MakeReferenceView(rig, sim->truth());
  StaticSgbmOptions options;
  options.baseline_m = config.static_baseline_m;
  options.min_depth_m = config.fovea.idr.z_min_m;
  options.block_px = config.fovea.fixation.foveal.fovea_patch_px;
  const StaticSgbmResult r = RunStaticSgbm(rig, options);
  const MapScore score = ScoreMap(r.map, ref, sim->truth(), r.baseline_m, true);
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const fovea::Patch& p : r.map.patches()) centre += p.Centre() / double(r.map.size());
  char caption[200];
  std::snprintf(caption, sizeof caption, "%s, static StereoSGBM at %.3f m: %s",
                fs::path(sim->scene_path()).stem().c_str(), r.baseline_m,
                ScoreLine(score, true).c_str());
  WriteImageAtomic(dir + "/map.png", MapSnapshot(r.map, ref, centre, caption));
  WriteImageAtomic(dir + "/reference.png", ref.view.gray);
  WriteTextAtomic(dir + "/map.ply", PatchMapPly(r.map));
  WriteTextAtomic(dir + "/fixations.jsonl", "");
  nlohmann::json summary = ScoreJson(score);
  summary["scene"] = sim->scene_path();
  summary["seed"] = config.seed;
  summary["method"] = config.method;
  summary["fixations"] = 0;
  summary["static_baseline_m"] = r.baseline_m;
  summary["map_patches"] = {{"idr", 0}, {"peripheral", 0}, {"foveal", r.map.size()}};
  summary["motion_time_s"] = r.motion_time_s;
  summary["compute_time_s"] = r.compute_time_s;
  summary["wall_time_s"] = Since(t_wall);
  WriteTextAtomic(dir + "/summary.json", summary.dump(2) + "\n");
  folder.Commit();
  std::fprintf(stderr, "fovea run: static StereoSGBM, baseline %.3f m: %s -> %s\n", r.baseline_m,
               ScoreLine(score).c_str(), folder.target().c_str());
  return 0;
}

// The real rig of rig.type: hardware: stages on rig.port (or on the indexer
// emulator, started here), cameras and calibration from the config; unit
// addresses and directions from rig.units / rig.directions, limits and steps
// from the rig.* keys.
std::unique_ptr<rig::HardwareRig> MakeHardwareRig(const RunConfig& c,
                                                  std::unique_ptr<rig::IndexerEmulator>* emulator) {
  const RunConfig::Hardware& h = c.hardware;
  rig::HardwareRigConfig hw;
  hw.calibration = rig::LoadCalibration(h.calibration);
  for (const rig::CameraIntrinsics* k : {&hw.calibration.left, &hw.calibration.right})
    if (k->width_px != c.rig.width_px || k->height_px != c.rig.height_px)
      throw rig::InputError("calibration " + rig::ClipForMessage(h.calibration) + " is for " +
                            std::to_string(k->width_px) + "x" + std::to_string(k->height_px) +
                            " images, rig.width_px x rig.height_px is " +
                            std::to_string(c.rig.width_px) + "x" + std::to_string(c.rig.height_px));
  const double lin = c.rig.baseline_steps_per_mm * 1000,
               ang = c.rig.pan_tilt_steps_per_deg * 180 / M_PI;
  const double pan = c.rig.pan_limit_deg * M_PI / 180, tilt = c.rig.tilt_limit_deg * M_PI / 180;
  const auto units = SixInts(h.units, "rig.units"),
             directions = SixInts(h.directions, "rig.directions");
  for (int i = 0; i < rig::kNumAxes; ++i) {
    rig::IndexerAxis& a = hw.stages.axes[i];
    const auto axis = static_cast<rig::Axis>(i);
    a.unit = units[i];
    a.sign = directions[i];
    const bool baseline = axis == rig::Axis::kLeftBaseline || axis == rig::Axis::kRightBaseline;
    a.steps_per_unit = baseline ? lin : ang;
    a.velocity = baseline ? h.baseline_velocity_m_s : h.pan_tilt_velocity_rad_s;
    a.acceleration = 10 * a.velocity;
    if (axis == rig::Axis::kLeftBaseline)
      a.min = -c.rig.carriage_max_m, a.max = -c.rig.carriage_min_m;
    else if (axis == rig::Axis::kRightBaseline)
      a.min = c.rig.carriage_min_m, a.max = c.rig.carriage_max_m;
    else if (axis == rig::Axis::kLeftPan || axis == rig::Axis::kRightPan)
      a.min = -pan, a.max = pan;
    else
      a.min = -tilt, a.max = tilt;
  }
  std::string port = h.port;
  if (h.emulate_stages) {
    *emulator =
        std::make_unique<rig::IndexerEmulator>(std::vector<int>(units.begin(), units.end()));
    port = (*emulator)->Path();
  }
  hw.line = rig::OpenSerialPort(port, h.baud);
  hw.left_camera = h.left_camera;
  hw.right_camera = h.right_camera;
  hw.home_baseline_m = c.rig.home_baseline_m;
  hw.frame_timeout = std::chrono::milliseconds(static_cast<long>(1000 * h.frame_timeout_s));
  return std::make_unique<rig::HardwareRig>(std::move(hw));
}

int Run(const RunArgs& args) {
  const auto t_wall = Clock::now();
  const RunConfig config = EffectiveConfig(args);
  OutputFolder folder(args.out, "--out", ExistingPolicy(args.force));
  if (config.method == "static_sgbm") return RunStatic(config, folder, t_wall);
  // The scene's model: the simulated rig, and the ground truth every run is
  // scored against (on hardware, the model of the scene in front of it).
  auto sim = LoadSceneOf(config);
  std::unique_ptr<rig::IndexerEmulator> emulator;
  std::unique_ptr<rig::HardwareRig> hardware;
  if (config.hardware.type == "hardware") hardware = MakeHardwareRig(config, &emulator);
  rig::Rig& rig = hardware ? static_cast<rig::Rig&>(*hardware) : sim->rig();
  if (!config.rig.record_dir.empty()) EnsureDirectory(config.rig.record_dir);
  const std::string dir = folder.path();
  WriteTextAtomic(dir + "/config.yaml", DumpConfig(config));

  auto t = Clock::now();
  const ReferenceView ref = MakeReferenceView(rig, sim->truth());
  const double reference_s = Since(t);
  std::unique_ptr<fovea::StereoMatcher> matcher;
  if (config.matcher == "sgbm")
    matcher = std::make_unique<fovea::SgbmMatcher>();
  else
    matcher = std::make_unique<fovea::Nl1Matcher>();

  const double baseline = config.fovea.fixation.baseline_m;
  const std::set<int> snapshots = {1, 5, 15, 25, config.fovea.fixations};
  Eigen::Vector3d view_target = Eigen::Vector3d::Zero();
  std::string jsonl;
  std::vector<Eigen::Vector3d> path, refused;
  double scoring_s = 0, output_s = 0;
  auto observer = [&](const fovea::FixationRecord& r, const fovea::PatchMap& map) {
    auto t0 = Clock::now();
    const MapScore score = ScoreMap(map, ref, sim->truth(), baseline, false);
    scoring_s += Since(t0);
    jsonl += RecordJson(r, score).dump() + "\n";
    if (r.ok)
      path.push_back(r.fixation_W);
    else
      refused.push_back(r.target_W);
    if (r.ok && r.fixation == 1) view_target = r.fixation_W;
    std::fprintf(
        stderr,
        "fovea run: fixation %2d/%d%s at (%+.3f, %.3f, %+.3f): %3d new patches, map %4d idr / %4d "
        "peripheral / %4d foveal, %s\n",
        r.fixation, config.fovea.fixations, r.ok ? "" : " REFUSED", r.target_W.x(), r.target_W.y(),
        r.target_W.z(), r.integration.added, r.map_by_level[0], r.map_by_level[1],
        r.map_by_level[2], ScoreLine(score, /*brief=*/true).c_str());
    if (!r.ok) std::fprintf(stderr, "fovea run:   refused: %s\n", r.why.c_str());
    t0 = Clock::now();
    if (r.ok && snapshots.count(r.fixation)) {
      char name[64], caption[200];
      std::snprintf(name, sizeof name, "/map_after_%02d.png", r.fixation);
      std::snprintf(caption, sizeof caption, "%s after fixation %d: %s",
                    fs::path(sim->scene_path()).stem().c_str(), r.fixation,
                    ScoreLine(score, /*brief=*/true).c_str());
      WriteImageAtomic(dir + name, MapSnapshot(map, ref, view_target, caption));
    }
    output_s += Since(t0);
  };

  fovea::FoveaOptions options = config.fovea;
  options.seed = config.seed;
  const fovea::FoveaRun run = fovea::RunFovea(rig, *matcher, options, observer);

  t = Clock::now();
  const MapScore final_score = ScoreMap(run.map, ref, sim->truth(), baseline, true);
  scoring_s += Since(t);
  t = Clock::now();
  WriteTextAtomic(dir + "/fixations.jsonl", jsonl);
  WriteTextAtomic(dir + "/map.ply", PatchMapPly(run.map));
  WriteImageAtomic(dir + "/fixation_path.png", FixationPath(ref, path, refused));
  WriteImageAtomic(dir + "/reference.png", ref.view.gray);
  output_s += Since(t);

  // Where the time went (wall clock).
  fovea::StageTimes sum;
  for (const auto& r : run.records) {
    sum.select_s += r.time.select_s;
    sum.verge_s += r.time.verge_s;
    sum.servo_s += r.time.servo_s;
    sum.foveal_s += r.time.foveal_s;
    sum.match_s += r.time.match_s;
    sum.integrate_s += r.time.integrate_s;
  }
  const double wall = Since(t_wall);
  nlohmann::json summary = ScoreJson(final_score);
  summary["scene"] = sim->scene_path();
  summary["seed"] = config.seed;
  summary["method"] = config.method;
  summary["fixations"] = run.fixations_done;
  summary["attempts"] = run.records.size();
  summary["refused"] = refused.size();
  summary["stop_reason"] = run.stop_reason;
  summary["matcher"] = config.matcher;
  const auto counts = run.map.CountByLevel();
  summary["map_patches"] = {{"idr", counts[0]}, {"peripheral", counts[1]}, {"foveal", counts[2]}};
  summary["idr"] = {
      {"stages", run.idr.stages.size()},
      {"final_baseline_m", run.idr.stages.empty() ? 0.0 : run.idr.stages.back().baseline_m},
      {"patches", run.idr.map.size()},
      {"stop_reason", run.idr.stop_reason}};
  summary["motion_time_s"] = run.motion_time_s;
  summary["compute_time_s"] = run.compute_time_s;
  summary["wall_time_s"] = wall;
  summary["time_s"] = {{"scene_load_and_reference", reference_s},
                       {"idr_compute", run.idr.compute_time_s},
                       {"select", sum.select_s},
                       {"verge", sum.verge_s},
                       {"servo_wall", sum.servo_s},
                       {"foveal", sum.foveal_s},
                       {"match", sum.match_s},
                       {"integrate", sum.integrate_s},
                       {"scoring", scoring_s},
                       {"outputs", output_s}};
  WriteTextAtomic(dir + "/summary.json", summary.dump(2) + "\n");
  folder.Commit();
  std::fprintf(stderr, "fovea run: %d fixations (%s): %s -> %s\n", run.fixations_done,
               run.stop_reason.c_str(), ScoreLine(final_score).c_str(), folder.target().c_str());
  std::fprintf(stderr,
               "fovea run: wall %.1f s: servo (moves, captures) %.1f, IDR %.1f (compute), foveal "
               "stereo %.1f "
               "(matching %.1f), selection %.1f, integration %.1f, scoring %.1f, pictures %.1f; "
               "simulated motion "
               "%.1f s\n",
               wall, sum.servo_s, run.idr.compute_time_s, sum.foveal_s, sum.match_s, sum.select_s,
               sum.integrate_s, scoring_s, output_s, run.motion_time_s);
  return 0;
}

}  // namespace

void AddRunCommand(CLI::App& app, std::function<int()>* run) {
  auto args = std::make_shared<RunArgs>();
  CLI::App* cmd =
      app.add_subcommand("run", "the full FOVEA loop on a scene, scored against ground truth");
  cmd->add_option("--scene", args->scene, "catalog scene name or path (overrides the config)");
  cmd->add_option("--config", args->config_path, "YAML configuration (see fovea config --dump)");
  cmd->add_option("--seed", args->seed, "the one seed (overrides the config)");
  cmd->add_option("--fixations", args->fixations,
                  "fixations to make (overrides the config: loop.fixations)");
  cmd->add_flag("--deterministic", args->deterministic, "always fixate the composite's maximum");
  cmd->add_option("--set", args->set, "KEY=VALUE: set one parameter (repeatable)");
  cmd->add_option("--out", args->out, "output folder (new, or empty)")->required();
  AddForceFlag(cmd, &args->force);
  cmd->callback([args, run] { *run = [args] { return Run(*args); }; });

  auto dump_args = std::make_shared<RunArgs>();
  auto dump = std::make_shared<bool>(false);
  CLI::App* cfg = app.add_subcommand("config", "the effective run configuration");
  cfg->add_flag("--dump", *dump, "print every parameter with its default (or the config's value)")
      ->required();
  cfg->add_option("--config", dump_args->config_path,
                  "YAML configuration to read over the defaults");
  cfg->add_option("--set", dump_args->set, "KEY=VALUE: set one parameter (repeatable)");
  cfg->callback([dump_args, run] {
    *run = [dump_args] {
      std::fputs(DumpConfig(EffectiveConfig(*dump_args)).c_str(), stdout);
      return 0;
    };
  });
}

}  // namespace experiments
