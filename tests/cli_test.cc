// The fovea program as a user runs it: outputs, exit codes, one-line errors.
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "temp_scene.h"

namespace fs = std::filesystem;

namespace {

struct Result {
  int exit_code;
  std::string err;
};

// Runs `fovea ARGS`, capturing stderr.
Result Fovea(const std::string& args) {
  const fs::path err_file =
      fs::temp_directory_path() / ("fovea_cli_err_" + std::to_string(getpid()));
  const std::string cmd =
      std::string(FOVEA_BIN) + " " + args + " >/dev/null 2>" + err_file.string();
  const int status = std::system(cmd.c_str());
  std::ifstream in(err_file);
  std::stringstream ss;
  ss << in.rdbuf();
  fs::remove(err_file);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : 128, ss.str()};
}

std::string ReadText(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

int Lines(const std::string& s) { return static_cast<int>(std::count(s.begin(), s.end(), '\n')); }

fs::path TempDir(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("fovea_cli_" + name + "_" + std::to_string(getpid()));
  fs::remove_all(dir);
  return dir;
}

}  // namespace

TEST_CASE("fovea render writes both images and the true depth", "[cli]") {
  const fs::path out = TempDir("render");
  const Result r = Fovea("render --state -0.06,1.5,0,0.06,-1.5,0 --out " + out.string());
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  for (const char* f : {"left.png", "right.png", "depth_left.png", "depth_right.png",
                        "depth_left_mm.png", "depth_right_mm.png", "render.json"})
    CHECK(fs::file_size(out / f) > 100);
  // No temporary files left behind.
  for (const auto& e : fs::directory_iterator(out))
    CHECK(e.path().filename().string().find("partial") == std::string::npos);
  fs::remove_all(out);
}

TEST_CASE("a user scene in any folder renders through the CLI", "[cli]") {
  // Written as scenes/README.md says: include the rig, generated textures.
  const TempScene scene(
      "<geom name=\"board\" type=\"box\" size=\"0.5 0.4 0.005\" pos=\"0 0.905 0\" "
      "zaxis=\"0 -1 0\" material=\"bark\"/><geom name=\"can\" type=\"mesh\" mesh=\"can\" "
      "pos=\"0.05 0.7 0\" material=\"bark\"/>",
      "<texture name=\"bark\" type=\"2d\" file=\"wood-s7.png\"/><mesh name=\"can\" "
      "file=\"cylinder-r60-h300.obj\"/><material name=\"bark\" texture=\"bark\" "
      "texrepeat=\"4 4\" texuniform=\"true\" specular=\"0\"/>");
  const fs::path out = TempDir("user");
  const Result r = Fovea("render --scene " + scene.path() + " --out " + out.string());
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  CHECK(fs::file_size(out / "left.png") > 10000);
  fs::remove_all(out);
}

TEST_CASE("fovea bench fixation prints the figures scripts rely on", "[cli][slow]") {
  const fs::path out = TempDir("bench");
  fs::create_directories(out);
  const std::string cmd = std::string(FOVEA_BIN) + " bench fixation --json > " +
                          (out / "b.json").string() + " 2>/dev/null";
  REQUIRE(std::system(cmd.c_str()) == 0);
  std::ifstream in(out / "b.json");
  std::string line;
  std::getline(in, line);
  for (const char* key : {"\"foveated_ms\"", "\"full_res_ms\"", "\"sgbm_ms\"",
                          "\"foveal_error_px\"", "\"full_res_error_px\"", "\"sgbm_error_px\"",
                          "\"full_res_over_foveated\"", "\"sgbm_over_foveated\""})
    CHECK(line.find(key) != std::string::npos);
  // The breakdown of the median repeat: a time and a pixel count per
  // level, adding up with the wide search's time to the whole.
  const nlohmann::json j = nlohmann::json::parse(line);
  const auto& levels = j.at("level_ms");
  REQUIRE(levels.size() == j.at("levels").get<size_t>());
  REQUIRE(j.at("level_searched_px").size() == levels.size());
  double parts = j.at("silent_check_ms").get<double>();
  for (size_t l = 0; l < levels.size(); ++l) {
    CHECK(levels[l].get<double>() > 0);
    CHECK(j.at("level_searched_px")[l].get<int>() > 0);
    parts += levels[l].get<double>();
  }
  CHECK(parts == Approx(j.at("foveated_ms").get<double>()).epsilon(1e-9));
  fs::remove_all(out);
}

TEST_CASE("bad input gives one line on stderr, a non-zero exit and no output", "[cli]") {
  const fs::path out = TempDir("bad");
  const fs::path dir = TempDir("scenes");
  fs::create_directories(dir);
  std::ofstream(dir / "broken.xml") << "<mujoco><worldbody><geom type=\"box\"</worldbody>";
  std::ofstream(dir / "norig.xml") << "<mujoco><worldbody><geom size=\"1\"/></worldbody></mujoco>";
  std::ofstream(dir / "notxml.xml") << "hello";
  std::ofstream(dir / "unknown.yaml") << "loop:\n  fixation: 3\n";
  std::ofstream(dir / "type.yaml") << "loop:\n  fixations: many\n";
  std::ofstream(dir / "range.yaml") << "foveal:\n  baseline_m: -0.1\n";
  std::ofstream(dir / "zero.yaml") << "loop:\n  fixations: 0\n";
  std::ofstream(dir / "bad.yaml") << "idr: [1, 2\n";
  const TempScene intruder("<geom type=\"box\" size=\"0.05 0.05 0.05\" pos=\"0 0.1 0\"/>");
  const TempScene driver("<geom type=\"box\" size=\"0.5 0.5 0.01\" pos=\"0 1 0\"/>", "",
                         "<actuator><motor joint=\"tavt_right_tilt\"/></actuator>");
  struct Case {
    std::string args, expect;
  };
  const std::vector<Case> cases = {
      {"render --scene /nonexistent/scene.xml", "/nonexistent/scene.xml"},
      {"render --scene no_such_scene", "unknown scene 'no_such_scene'"},
      {"render --scene " + (dir / "broken.xml").string(), "broken.xml"},
      {"render --scene " + (dir / "norig.xml").string(), "does not include the rig"},
      {"render --scene " + (dir / "notxml.xml").string(), "not an MJCF"},
      {"render --state 0,0,0,0.05,0,0", "left baseline"},
      {"render --state -0.05,0,0,0.05,75,0", "right pan"},
      {"render --state 1,2,3", "exactly 6"},
      {"render --state -0.05,x,0,0.05,0,0", "'x' is not a number"},
      {"render --baseline 2.0", "baseline"},
      {"render --scene " + intruder.path(), "rig's workspace"},
      {"render --scene " + driver.path(), "may not move the rig"},
      {"render --scene random:1:99", "N must be 1 to 30"},
      {"fixate --point 0 0.9", "point"},
      {"fixate --point 3 0.5 0", "cannot fixate"},
      {"fixate --point 0 0.9 0 --matcher census", "matcher"},
      {"run --config " + (dir / "unknown.yaml").string(), "unknown key 'loop.fixation'"},
      {"run --config " + (dir / "type.yaml").string(), "key 'loop.fixations': expected a number"},
      {"run --config " + (dir / "range.yaml").string(),
       "key 'foveal.baseline_m': -0.1 is out of range"},
      {"run --config " + (dir / "zero.yaml").string(),
       "key 'loop.fixations': 0 is out of range [1, 10000]"},
      {"run --config " + (dir / "bad.yaml").string(), "not valid YAML"},
      {"run --config /nonexistent/run.yaml", "cannot be read"},
      {"run --scene no_such_scene", "unknown scene"},
      {"run --set matcher=census", "key 'matcher'"},
      {"run --set selection.deterministic=maybe", "expected true or false"},
  };
  for (const Case& c : cases) {
    const Result r = Fovea(c.args + " --out " + out.string());
    INFO(c.args << " -> exit " << r.exit_code << ": " << r.err);
    CHECK(r.exit_code != 0);
    CHECK(r.exit_code < 128);  // an exit, not a signal
    CHECK(Lines(r.err) == 1);
    CHECK(r.err.find(c.expect) != std::string::npos);
    CHECK_FALSE(fs::exists(out));
  }
  fs::remove_all(dir);
}

TEST_CASE("bad sweep files each give one line naming the key, exit 2 and no output folder",
          "[cli][sweep]") {
  const fs::path out = TempDir("sweep_bad");
  const fs::path dir = TempDir("sweeps");
  fs::create_directories(dir);
  struct Case {
    std::string name, text, expect;
  };
  const std::vector<Case> cases = {
      {"unknown_key", "config: {loop: {fixation: 3}}\naxes: {seed: [0, 1]}\n",
       "unknown key 'loop.fixation'"},
      {"wrong_type", "config: {loop: {fixations: many}}\naxes: {seed: [0, 1]}\n",
       "key 'loop.fixations': expected a number"},
      {"negative_baseline", "axes: {foveal.baseline_m: [0.1, -0.1]}\n",
       "key 'foveal.baseline_m': -0.1 is out of range"},
      {"zero_fixations", "axes: {loop.fixations: [0, 5]}\n",
       "key 'loop.fixations': 0 is out of range [1, 10000]"},
      {"missing_scene", "axes: {scene: [two_planes, no_such_scene]}\n",
       "unknown scene 'no_such_scene'"},
      {"missing_scene_file", "axes: {scene: [/nonexistent/scene.xml]}\n",
       "scene file '/nonexistent/scene.xml' cannot be read: no such file"},
      {"not_yaml", "axes: [1, 2\n", "not valid YAML"},
      {"unknown_axis", "axes: {foveal.nope: [1, 2]}\n", "unknown key 'foveal.nope'"},
      {"no_axes", "config: {seed: 3}\n", "key 'axes'"},
      {"bad_range", "axes: {seed: {from: 3, to: 1, step: 1}}\n", "range needs from <= to"},
      {"unknown_top_key", "axis: {seed: [0]}\n", "unknown key 'axis'"},
      {"missing_base", "base: nope.yaml\naxes: {seed: [0]}\n", "cannot be read"},
      {"too_wide",
       "config: {rig: {carriage_max_m: 0.05}}\naxes: {foveal.baseline_m: [0.08, 0.12]}\n",
       "key 'foveal.baseline_m': 0.12 is wider than the carriages allow"},
      {"unknown_baseline", "axes: {seed: [0]}\nbaselines: [oracle]\n", "'oracle' is not one of"},
      {"bad_jobs", "axes: {seed: [0]}\njobs: -1\n", "key 'jobs'"},
      {"bad_bool", "axes: {criteria.suppression: [yes_please]}\n", "expected true or false"},
  };
  for (const Case& c : cases) {
    const fs::path file = dir / (c.name + ".yaml");
    std::ofstream(file) << c.text;
    const Result r = Fovea("sweep " + file.string() + " --out " + out.string());
    INFO(c.name << " -> exit " << r.exit_code << ": " << r.err);
    CHECK(r.exit_code == 2);
    CHECK(Lines(r.err) == 1);
    CHECK(r.err.find(c.expect) != std::string::npos);
    CHECK_FALSE(fs::exists(out));
  }
  const fs::path good = dir / "good.yaml";
  std::ofstream(good) << "axes: {seed: [0, 1]}\n";
  for (const std::string& args : std::vector<std::string>{
           "sweep /nonexistent/sweep.yaml", "sweep " + good.string() + " --shard 3/2",
           "sweep " + good.string() + " --shard x", "collect /nonexistent/folder",
           "report /nonexistent/folder"}) {
    const Result r = Fovea(args + (args.rfind("sweep", 0) == 0 ? " --out " + out.string() : ""));
    INFO(args << " -> exit " << r.exit_code << ": " << r.err);
    CHECK(r.exit_code == 2);
    CHECK(Lines(r.err) == 1);
    CHECK_FALSE(fs::exists(out));
  }
  fs::remove_all(dir);
}

TEST_CASE("hardware rig setup errors are one line, non-zero exit and no output",
          "[cli][hardware]") {
  const fs::path out = TempDir("hw_bad");
  const fs::path dir = TempDir("hw");
  fs::create_directories(dir);
  const std::string configs = std::string(FOVEA_SCENES_DIR) + "/../experiments/configs";
  const std::string base = "run --config " + configs +
                           "/emulated-hardware.yaml --set rig.calibration=" + configs +
                           "/emulated-hardware-calibration.yaml";
  // A calibration for another image size.
  std::ofstream(dir / "small.yaml")
      << "%YAML:1.0\n---\nleft: {width_px: 320, height_px: 240, fx_px: 600., fy_px: 600., "
         "cx_px: 159.5, cy_px: 119.5}\nright: {width_px: 320, height_px: 240, fx_px: 600., "
         "fy_px: 600., cx_px: 159.5, cy_px: 119.5}\n";
  std::ofstream(dir / "broken.yaml") << "%YAML:1.0\n---\nleft: {width_px: 640}\n";
  struct Case {
    std::string args, expect;
  };
  const std::vector<Case> cases = {
      {base + " --set rig.emulate_stages=false --set rig.port=/dev/ttyNOPE0",
       "serial port '/dev/ttyNOPE0' does not exist"},
      {base + " --set rig.baud=12345", "baud rate 12345"},
      {base + " --set rig.left_camera=/nonexistent/left_%05d.png",
       "camera '/nonexistent/left_%05d.png' cannot be opened"},
      {base + " --set rig.calibration=" + (dir / "small.yaml").string(), "is for 320x240 images"},
      {base + " --set rig.calibration=" + (dir / "broken.yaml").string(),
       "missing number 'height_px'"},
      {base + " --set rig.calibration=/nonexistent/calibration.yaml", "cannot be read"},
      {base + " --set rig.emulate_stages=false", "key 'rig.port'"},
      {base + " --set rig.units=1,2,3,4,5,5", "key 'rig.units': address 5 appears twice"},
      {base + " --set rig.directions=1,1,1,1,2,1", "key 'rig.directions'"},
      {"calibrate --left '/nonexistent/*.png' --right '/nonexistent/*.png' --board 9x6 --square "
       "0.025",
       "no files match"},
      {"calibrate --left '/nonexistent/*.png' --right '/nonexistent/*.png' --board 9by6 --square "
       "0.025",
       "--board expects WxH"},
  };
  for (const Case& c : cases) {
    const Result r = Fovea(c.args + " --out " + out.string());
    INFO(c.args << " -> exit " << r.exit_code << ": " << r.err);
    CHECK(r.exit_code != 0);
    CHECK(r.exit_code < 128);
    CHECK(Lines(r.err) == 1);
    CHECK(r.err.find(c.expect) != std::string::npos);
    CHECK_FALSE(fs::exists(out));
  }
  fs::remove_all(dir);
}

TEST_CASE("a sweep over catalog, generated and numbered random scenes runs", "[cli][sweep]") {
  const fs::path dir = TempDir("scene_sweep");
  fs::create_directories(dir);
  std::ofstream(dir / "scenes.yaml")
      << "config: {loop: {fixations: 1}, rig: {width_px: 160, height_px: 120}}\n"
         "axes: {scene: [random, \"random:2\"]}\n";
  const Result r = Fovea("sweep " + (dir / "scenes.yaml").string() +
                         " --no-report --jobs 2 --out " + (dir / "out").string());
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  std::ifstream csv(dir / "out" / "results.csv");
  int rows = -1;  // the header
  for (std::string line; std::getline(csv, line);) rows += !line.empty();
  CHECK(rows == 2);
  fs::remove_all(dir);
}

TEST_CASE("a sweep over selection.strategy gets the report's Strategies section", "[cli][sweep]") {
  const fs::path dir = TempDir("strategy_sweep");
  fs::create_directories(dir);
  std::ofstream(dir / "strategies.yaml")
      << "config: {loop: {fixations: 2}, score: {compare_static: false}, rig: {width_px: 160, "
         "height_px: 120}}\n"
         "axes: {selection.strategy: [fovea, next_best_view], scene: [two_planes]}\n";
  const Result r = Fovea("sweep " + (dir / "strategies.yaml").string() + " --jobs 2 --out " +
                         (dir / "out").string());
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  const std::string page = ReadText(dir / "out" / "report.html");
  CHECK(page.find("<h2>Strategies</h2>") != std::string::npos);
  // A table row per strategy, each over its one run, in strategies.md too.
  const std::string md = ReadText(dir / "out" / "strategies.md");
  CHECK(md.find("| fovea | 1 |") != std::string::npos);
  CHECK(md.find("| next_best_view | 1 |") != std::string::npos);
  for (const char* png :
       {"strategies_coverage_vs_fixations.png", "strategies_good_vs_motion.png"}) {
    INFO(png);
    CHECK(fs::file_size(dir / "out" / png) > 1000);
  }
  // Each run's summary names its strategy and its travel.
  std::ifstream csv(dir / "out" / "results.csv");
  std::string header;
  std::getline(csv, header);
  CHECK(header.find("selection_strategy") != std::string::npos);
  CHECK(header.find("travel.pan_deg") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("fovea fixate fixates a point the way fovea run does", "[cli][slow]") {
  // Noise off: the run's reference view draws from the noise generator before
  // IDR, fixate's does not; without noise both see the same images. The
  // run's first target is IDR's mapped point (a point the strategy chose may
  // lie in a hole, whose servo search spans every depth: fixate aims at
  // mapped points).
  const fs::path run = TempDir("same_run"), fix = TempDir("same_fix");
  Result r = Fovea(
      "run --scene two_planes --fixations 1 --set rig.noise_sigma_dn=0 --set "
      "selection.first_fixation=idr --out " +
      run.string());
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  std::ifstream records(run / "fixations.jsonl");
  std::string line;
  std::getline(records, line);
  const nlohmann::json first = nlohmann::json::parse(line);
  REQUIRE(first["ok"] == true);
  char point[200];
  std::snprintf(point, sizeof point, "%.17g %.17g %.17g", first["target_W"][0].get<double>(),
                first["target_W"][1].get<double>(), first["target_W"][2].get<double>());
  r = Fovea(std::string("fixate --scene two_planes --noise 0 --point ") + point + " --out " +
            fix.string());
  REQUIRE(r.exit_code == 0);
  std::ifstream in(fix / "fixate.json");
  const nlohmann::json fixate = nlohmann::json::parse(in);
  for (int i = 0; i < 3; ++i)
    CHECK(fixate["fixation_W"][i].get<double>() == first["fixation_W"][i].get<double>());
  CHECK(fixate["servo"]["iterations"] == first["servo"]["iterations"]);
  CHECK(fixate["servo"]["residual_px"].get<double>() ==
        first["servo"]["residual_px"].get<double>());
  CHECK(fixate["tessellation"]["z_t_far_m"].get<double>() ==
        first["tessellation"]["z_t_far_m"].get<double>());
  fs::remove_all(run);
  fs::remove_all(fix);
}
