// fovea run: the full FOVEA loop on a scene, scored against ground truth after
// every fixation; fovea config: the effective configuration.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <set>

#include "commands.h"
#include "experiments/config/config.h"
#include "experiments/output/output.h"
#include "experiments/output/run_folder.h"
#include "experiments/output/run_output.h"
#include "experiments/scoring/baseline.h"
#include "experiments/scoring/run_eval.h"
#include "fovea/ddr.h"
#include "fovea/sgbm.h"
#include "fovea/timing.h"
#include "fovea/visibility.h"
#include "hardware_setup.h"
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

RunConfig EffectiveConfig(const RunArgs& args) {
  RunConfig c = args.config_path.empty() ? RunConfig{} : LoadConfig(args.config_path);
  SetParams(&c, args.set);
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
// The static baseline's options from the run's: its baseline, the scene's
// nearest depth and the fovea's patch size.
StaticSgbmOptions StaticOptionsOf(const RunConfig& config) {
  StaticSgbmOptions options;
  options.baseline_m = config.static_baseline_m;
  options.min_depth_m = config.fovea.idr.z_min_m;
  options.block_px = config.fovea.fixation.foveal.fovea_patch_px;
  return options;
}

// The static pair's map is read as rendered: the reading rule
// (integration.reference_flank_px) is FOVEA's, and the baseline stays one
// plain StereoSGBM frame.
constexpr int kStaticFlankPx = 0;

int RunStatic(const RunConfig& config, OutputFolder& folder, Clock::time_point t_wall) {
  namespace rf = run_folder;
  auto sim = LoadSceneOf(config);
  rig::Rig& rig = sim->rig();
  const std::string dir = folder.path();
  WriteTextAtomic(dir + "/" + rf::kConfig, DumpConfig(config));
  const ReferenceView ref = MakeReferenceView(rig, *sim);
  const StaticSgbmResult r = RunStaticSgbm(rig, StaticOptionsOf(config));
  const MapScore score =
      ScoreMap(r.map, kStaticFlankPx, ref, sim->truth(), r.baseline_m, /*per_patch=*/true);
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const fovea::Patch& p : r.map.patches()) centre += p.Centre() / double(r.map.size());
  char caption[200];
  std::snprintf(caption, sizeof caption, "%s, static StereoSGBM at %.3f m: %s",
                fs::path(sim->scene_path()).stem().c_str(), r.baseline_m,
                ScoreLine(score, true).c_str());
  WriteImageAtomic(dir + "/" + rf::kMapPicture,
                   MapSnapshot(r.map, kStaticFlankPx, ref, centre, caption));
  WriteImageAtomic(dir + "/" + rf::kReference, ref.view.gray);
  WriteImageAtomic(dir + "/" + rf::kErrorPicture, ErrorPicture(r.map, kStaticFlankPx, ref));
  WriteTextAtomic(dir + "/" + rf::kMapPly, PatchMapPly(r.map));
  WriteTextAtomic(dir + "/" + rf::kRecords, "");
  nlohmann::json summary =
      rf::SummaryJson(score, sim->scene_path(), config, {0, 0, static_cast<int>(r.map.size())},
                      r.motion_time_s, r.compute_time_s, Since(t_wall));
  summary["fixations"] = 0;
  summary["static_baseline_m"] = r.baseline_m;
  WriteTextAtomic(dir + "/" + rf::kSummary, summary.dump(2) + "\n");
  folder.Commit();
  std::fprintf(stderr, "fovea run: static StereoSGBM, baseline %.3f m: %s -> %s\n", r.baseline_m,
               ScoreLine(score).c_str(), folder.target().c_str());
  return 0;
}

// FOVEA's map against the static StereoSGBM baseline's on the pixels both
// map (summary: vs_static). Run after the fixations: the static pair's moves
// and captures change nothing the run did.
nlohmann::json VsStatic(rig::Rig& rig, const RunConfig& config, const fovea::PatchMap& map,
                        const ReferenceView& ref) {
  const StaticSgbmResult sgbm = RunStaticSgbm(rig, StaticOptionsOf(config));
  const CommonPixels common =
      CompareOnCommonPixels(map, config.fovea.integration.reference_flank_px, sgbm.map, ref);
  auto figure = [&](double v) { return common.pixels ? nlohmann::json(v) : nlohmann::json(); };
  return {{"pixels", common.pixels},
          {"fovea_median_abs_error_m", figure(common.median_abs_error_m)},
          {"static_median_abs_error_m", figure(common.other_median_abs_error_m)},
          {"static_baseline_m", sgbm.baseline_m}};
}

// Wall-clock seconds by stage over every attempt of a run.
fovea::StageTimes SumTimes(const std::vector<fovea::FixationRecord>& records) {
  fovea::StageTimes sum;
  for (const auto& r : records) {
    sum.select_s += r.time.select_s;
    sum.verge_s += r.time.verge_s;
    sum.servo_s += r.time.servo_s;
    sum.foveal_s += r.time.foveal_s;
    sum.match_s += r.time.match_s;
    sum.integrate_s += r.time.integrate_s;
  }
  return sum;
}

// The algorithm's compute per fixation (selection, vergence, foveal stereo,
// integration; refused attempts counted with the fixation that followed
// them), excluding simulated rendering and physics: over the run, and over
// its first and last 25 fixations (whether it grows with the map).
struct ComputePerFixation {
  double mean_s = 0, first_s = 0, last_s = 0;
};

ComputePerFixation PerFixation(const fovea::FoveaRun& run) {
  std::vector<double> per;  // by fixation
  double pending = 0;
  for (const auto& r : run.records) {
    pending += r.time.ComputeS();
    if (r.ok) {
      per.push_back(pending);
      pending = 0;
    }
  }
  ComputePerFixation c;
  if (per.empty()) return c;
  auto mean = [](auto begin, auto end) {
    return std::accumulate(begin, end, 0.0) / std::max<long>(1, std::distance(begin, end));
  };
  const size_t n = std::min<size_t>(25, per.size());
  c.mean_s = mean(per.begin(), per.end());
  c.first_s = mean(per.begin(), per.begin() + n);
  c.last_s = mean(per.end() - n, per.end());
  return c;
}

// summary.json of a FOVEA run.
nlohmann::json FoveaSummary(const fovea::FoveaRun& run, const MapScore& score,
                            const std::string& scene_path, const RunConfig& config,
                            const run_folder::Recorder& recorder, double reference_s,
                            double wall_s) {
  nlohmann::json summary =
      run_folder::SummaryJson(score, scene_path, config, run.map.CountByLevel(), run.motion_time_s,
                              run.compute_time_s, wall_s);
  summary["fixations"] = run.fixations_done;
  summary["attempts"] = run.records.size();
  summary["refused"] = recorder.refused().size();
  summary["stop_reason"] = run.stop_reason;
  summary["fovea"] = run_folder::FoveaSizesJson(run.records);
  summary["matcher"] = config.matcher;
  summary["idr"] = {
      {"stages", run.idr.stages.size()},
      {"final_baseline_m", run.idr.stages.empty() ? 0.0 : run.idr.stages.back().baseline_m},
      {"patches", run.idr.map.size()},
      {"hidden_in_reference", run.idr_hidden},
      {"stop_reason", run.idr.stop_reason}};
  double pan = 0, tilt = 0, carriage = 0, loop_motion = 0;
  for (const auto& r : run.records)
    pan += r.pan_rad, tilt += r.tilt_rad, carriage += r.carriage_m, loop_motion += r.motion_time_s;
  summary["selection_strategy"] = config.fovea.selection.Strategy();
  summary["travel"] = run_folder::TravelJson(pan, tilt, carriage);
  summary["travel"]["motion_time_s"] = loop_motion;
  const fovea::StageTimes sum = SumTimes(run.records);
  const ComputePerFixation per = PerFixation(run);
  summary["time_s"] = {
      {"scene_load_and_reference", reference_s},
      {"idr_compute", run.idr.compute_time_s},
      {"select", sum.select_s},
      {"verge", sum.verge_s},
      {"servo_wall", sum.servo_s},
      {"foveal", sum.foveal_s},
      {"match", sum.match_s},
      {"integrate", sum.integrate_s},
      {"scoring", recorder.scoring_s},
      {"outputs", recorder.output_s},
      {"compute_per_fixation",
       {{"mean", per.mean_s}, {"first_25", per.first_s}, {"last_25", per.last_s}}}};
  return summary;
}

int Run(const RunArgs& args) {
  namespace rf = run_folder;
  const auto t_wall = Clock::now();
  const RunConfig config = EffectiveConfig(args);
  OutputFolder folder(args.out, "--out", ExistingPolicy(args.force));
  if (config.method == "static_sgbm") return RunStatic(config, folder, t_wall);
  // The real rig first: its port, cameras and calibration are checked in
  // moments (no stage moves yet), before the scene's model loads.
  std::unique_ptr<rig::IndexerEmulator> emulator;
  std::unique_ptr<rig::HardwareRig> hardware;
  if (config.hardware.type == "hardware") hardware = MakeHardwareRig(config, &emulator);
  // The scene's model: the simulated rig, and the ground truth every run is
  // scored against (on hardware, the model of the scene in front of it).
  auto sim = LoadSceneOf(config);
  rig::Rig& rig = hardware ? static_cast<rig::Rig&>(*hardware) : sim->rig();
  if (!config.rig.record_dir.empty()) EnsureDirectory(config.rig.record_dir);
  const std::string dir = folder.path();
  WriteTextAtomic(dir + "/" + rf::kConfig, DumpConfig(config));
  auto t = Clock::now();
  const ReferenceView ref = MakeReferenceView(rig, *sim);
  const double reference_s = Since(t);
  rf::Recorder recorder(dir, sim->scene_path(), ref, sim->truth(), config);
  fovea::FoveaOptions options = config.fovea;
  options.seed = config.seed;
  const fovea::FoveaRun run =
      fovea::RunFovea(rig, *fovea::MakeMatcher(config.matcher, config.fovea), options,
                      std::ref(recorder), &ref.view);
  recorder.Finish();
  t = Clock::now();
  // What the map shows in the reference view: the patches the reference
  // camera sees (the map keeps the others), read by the reading rule.
  const fovea::PatchMap seen = fovea::ReferenceMap(run.map);
  const int flank_px = config.fovea.integration.reference_flank_px;
  const MapScore score = ScoreMap(seen, flank_px, ref, sim->truth(),
                                  config.fovea.fixation.baseline_m, /*per_patch=*/true);
  // Where the fixations started from: the curves of coverage against
  // fixations and motion begin here.
  const MapScore idr_score =
      ScoreMap(run.idr.map, flank_px, ref, sim->truth(), config.fovea.fixation.baseline_m, false);
  const nlohmann::json vs_static =
      config.compare_static ? VsStatic(rig, config, seen, ref) : nlohmann::json();
  recorder.scoring_s += Since(t);
  t = Clock::now();
  WriteTextAtomic(dir + "/" + rf::kRecords, recorder.records());
  WriteTextAtomic(dir + "/" + rf::kMapPly, PatchMapPly(run.map));
  WriteImageAtomic(dir + "/" + rf::kFixationPath,
                   FixationPath(ref, recorder.path(), recorder.refused()));
  WriteImageAtomic(dir + "/" + rf::kReference, ref.view.gray);
  WriteImageAtomic(dir + "/" + rf::kErrorPicture, ErrorPicture(seen, flank_px, ref));
  recorder.output_s += Since(t);
  const double wall = Since(t_wall);
  nlohmann::json summary =
      FoveaSummary(run, score, sim->scene_path(), config, recorder, reference_s, wall);
  if (!vs_static.is_null()) summary["vs_static"] = vs_static;
  const nlohmann::json idr_json = ScoreJson(idr_score);
  for (const char* key : {"coverage", "good_coverage"}) summary["idr"][key] = idr_json.at(key);
  WriteTextAtomic(dir + "/" + rf::kSummary, summary.dump(2) + "\n");
  folder.Commit();
  const fovea::StageTimes sum = SumTimes(run.records);
  std::fprintf(stderr, "fovea run: %d fixations (%s): %s -> %s\n", run.fixations_done,
               run.stop_reason.c_str(), ScoreLine(score).c_str(), folder.target().c_str());
  const nlohmann::json& fovea_sizes = summary["fovea"];
  if (fovea_sizes["fixations"].get<int>() > 0)
    std::fprintf(
        stderr,
        "fovea run: fovea median %gx%g px (smallest %gx%g), median image share %.3f, %d "
        "under 32 px\n",
        fovea_sizes["width_px"]["median"].get<double>(),
        fovea_sizes["height_px"]["median"].get<double>(),
        fovea_sizes["width_px"]["min"].get<double>(), fovea_sizes["height_px"]["min"].get<double>(),
        fovea_sizes["image_share"]["median"].get<double>(), fovea_sizes["under_32px"].get<int>());
  std::fprintf(stderr,
               "fovea run: wall %.1f s: servo (moves, captures) %.1f, IDR %.1f (compute), foveal "
               "stereo %.1f "
               "(matching %.1f), selection %.1f, integration %.1f, scoring %.1f, pictures %.1f; "
               "simulated motion "
               "%.1f s\n",
               wall, sum.servo_s, run.idr.compute_time_s, sum.foveal_s, sum.match_s, sum.select_s,
               sum.integrate_s, recorder.scoring_s, recorder.output_s, run.motion_time_s);
  const nlohmann::json& per = summary["time_s"]["compute_per_fixation"];
  std::fprintf(stderr,
               "fovea run: compute per fixation %.0f ms (rendering and physics excluded); first 25 "
               "fixations %.0f ms, last 25 %.0f ms\n",
               1e3 * per["mean"].get<double>(), 1e3 * per["first_25"].get<double>(),
               1e3 * per["last_25"].get<double>());
  const nlohmann::json& travel = summary["travel"];
  const double n = std::max(1, run.fixations_done);
  std::fprintf(stderr,
               "fovea run: strategy %s: selection %.0f ms per fixation; per fixation pan %.1f deg, "
               "tilt %.1f deg, carriages %.0f mm, motion %.2f s (both cameras' axes summed)\n",
               config.fovea.selection.Strategy().c_str(), 1e3 * sum.select_s / n,
               travel["pan_deg"].get<double>() / n, travel["tilt_deg"].get<double>() / n,
               1e3 * travel["carriage_m"].get<double>() / n,
               travel["motion_time_s"].get<double>() / n);
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
  // The callback holds every value the options write into (as each
  // command's does), so that they outlive this function.
  cfg->callback([dump_args, dump, run] {
    *run = [dump_args] {
      std::fputs(DumpConfig(EffectiveConfig(*dump_args)).c_str(), stdout);
      return 0;
    };
  });
}

}  // namespace experiments
