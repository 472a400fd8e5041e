// The full FOVEA run as a user runs it (fovea run): records, summary,
// reproducibility, local suppression, the paper's near-then-far behaviour.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

fs::path Out(const std::string& name) {
  const fs::path dir =
      fs::temp_directory_path() / ("fovea_ddr_" + name + "_" + std::to_string(getpid()));
  fs::remove_all(dir);
  return dir;
}

void RunFovea(const std::string& args, const fs::path& out) {
  const std::string cmd =
      std::string(FOVEA_BIN) + " run " + args + " --out " + out.string() + " 2>/dev/null";
  REQUIRE(std::system(cmd.c_str()) == 0);
}

std::vector<json> Records(const fs::path& out) {
  std::ifstream in(out / "fixations.jsonl");
  std::vector<json> r;
  for (std::string line; std::getline(in, line);) r.push_back(json::parse(line));
  return r;
}

json Summary(const fs::path& out) {
  std::ifstream in(out / "summary.json");
  return json::parse(in);
}

// Leaves out the wall-clock keys, at any depth.
json WithoutWallClock(json j) {
  if (j.is_object()) {
    for (const char* k : {"time_s", "compute_time_s", "wall_time_s"}) j.erase(k);
    for (auto& [k, v] : j.items()) v = WithoutWallClock(v);
  }
  return j;
}

std::string Text(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace

TEST_CASE("fovea run: the same seed gives the same run, another seed another one", "[ddr][slow]") {
  const fs::path a = Out("a"), b = Out("b"), c = Out("c");
  RunFovea("--scene two_planes --fixations 6 --seed 1", a);
  RunFovea("--scene two_planes --fixations 6 --seed 1", b);
  RunFovea("--scene two_planes --fixations 6 --seed 2", c);
  const auto ra = Records(a), rb = Records(b), rc = Records(c);
  REQUIRE(ra.size() == rb.size());
  for (size_t i = 0; i < ra.size(); ++i) {
    INFO("record " << i);
    CHECK(WithoutWallClock(ra[i]).dump() == WithoutWallClock(rb[i]).dump());
    CHECK(ra[i].contains("motion_time_s"));  // simulated, deterministic: it stays in
  }
  CHECK(WithoutWallClock(Summary(a)).dump() == WithoutWallClock(Summary(b)).dump());
  CHECK(Text(a / "map.ply") == Text(b / "map.ply"));
  std::vector<json> ta, tc;
  for (const auto& r : ra) ta.push_back(r["target_W"]);
  for (const auto& r : rc) tc.push_back(r["target_W"]);
  CHECK(ta != tc);
  for (const auto& d : {a, b, c}) fs::remove_all(d);
}

TEST_CASE(
    "fovea run on two_planes: near plane first, then the far one, with its outputs and summary "
    "keys",
    "[ddr][slow]") {
  const fs::path out = Out("two");
  RunFovea("--scene two_planes", out);
  const auto records = Records(out);
  const json s = Summary(out);
  for (const char* key :
       {"scene", "seed", "fixations", "coverage", "foveal_coverage", "median_abs_error_m",
        "median_rel_error", "rmse_m", "compute_time_s", "motion_time_s", "wall_time_s"}) {
    INFO(key);
    CHECK(s.contains(key));
  }
  CHECK(s["fixations"] == 25);
  for (const char* f : {"map.ply", "fixation_path.png", "map_after_01.png", "map_after_05.png",
                        "map_after_15.png", "map_after_25.png", "config.yaml"})
    CHECK(fs::exists(out / f));
  // Near plane at y = 0.6 m, far plane at 1.3 m.
  std::vector<bool> near;
  for (const auto& r : records)
    if (r["ok"]) near.push_back(r["fixation_W"][1].get<double>() < 0.95);
  REQUIRE(near.size() == 25);
  for (int i = 0; i < 5; ++i) CHECK(near[i]);              // stays on the near plane for a while
  CHECK(std::count(near.begin(), near.end(), false) > 0);  // then moves to the far one
  const auto first_far = std::find(near.begin(), near.end(), false) - near.begin();
  CHECK(std::count(near.begin() + first_far, near.end(), true) <= 2);  // and mostly stays there
  // The map's foveal share grows with fixations; the whole map stays accurate.
  const double f1 = records.front()["score"]["foveal_coverage"],
               f25 = records.back()["score"]["foveal_coverage"];
  CHECK(f25 > f1);
  CHECK(s["median_rel_error"].get<double>() < 0.01);
  CHECK(s["coverage"].get<double>() >= 0.95);  // measured 0.989
  fs::remove_all(out);
}

TEST_CASE("local suppression: without it, fixations revisit mapped places more", "[ddr][slow]") {
  auto revisits = [](const std::string& suppression) {
    const fs::path out = Out("sup" + suppression);
    RunFovea("--scene cylinder_planes --fixations 12 --set criteria.suppression=" + suppression,
             out);
    std::vector<Eigen::Vector3d> pts;
    for (const auto& r : Records(out))
      if (r["ok"]) pts.emplace_back(r["fixation_W"][0], r["fixation_W"][1], r["fixation_W"][2]);
    fs::remove_all(out);
    int n = 0;
    for (size_t i = 0; i < pts.size(); ++i)
      for (size_t j = 0; j < i; ++j)
        if ((pts[i] - pts[j]).norm() < 0.03) {
          ++n;
          break;
        }
    return n;
  };
  const int with = revisits("true"), without = revisits("false");
  INFO("revisits within 3 cm: with suppression " << with << ", without " << without);
  CHECK(without >= with + 3);
}
