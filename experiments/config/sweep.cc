#include "experiments/config/sweep.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include "experiments/usage_error.h"
#include "rig/input_file.h"
#include "scenes/catalog.h"

namespace experiments {
namespace fs = std::filesystem;
namespace {

std::string Number(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.12g", v);
  return buf;
}

// The values of one axis: a list of scalars, or {from, to, step | count}.
std::vector<std::string> AxisValues(const YAML::Node& node, const std::string& where) {
  std::vector<std::string> values;
  if (node.IsSequence()) {
    for (const auto& v : node) {
      if (!v.IsScalar()) throw UsageError(where + "expected a list of single values");
      values.push_back(v.Scalar());
    }
  } else if (node.IsMap()) {
    std::map<std::string, double> r;
    for (const auto& kv : node) {
      const std::string key = kv.first.as<std::string>();
      if (key != "from" && key != "to" && key != "step" && key != "count")
        throw UsageError(where + "unknown range key '" + key +
                         "' (expected from, to, step or count)");
      const std::optional<double> v =
          kv.second.IsScalar() ? ParseNumber(kv.second.Scalar()) : std::nullopt;
      if (!v) throw UsageError(where + "range key '" + key + "': expected a number");
      r[key] = *v;
    }
    if (!r.count("from") || !r.count("to")) throw UsageError(where + "a range needs from and to");
    if (r.count("step") == r.count("count"))
      throw UsageError(where + "a range needs exactly one of step or count");
    const double from = r["from"], to = r["to"];
    int n;
    double step;
    if (r.count("count")) {
      if (!(r["count"] >= 1 && r["count"] <= kMaxSweepRuns && r["count"] == std::floor(r["count"])))
        throw UsageError(where + "range count must be a whole number from 1 to " +
                         std::to_string(kMaxSweepRuns));
      n = static_cast<int>(r["count"]);
      step = n > 1 ? (to - from) / (n - 1) : 0;
    } else {
      step = r["step"];
      if (!(step > 0)) throw UsageError(where + "range step must be positive");
      if (to < from) throw UsageError(where + "range needs from <= to");
      const double k = std::floor((to - from) / step + 1e-9);
      if (k + 1 > kMaxSweepRuns)
        throw UsageError(where + "range has more than " + std::to_string(kMaxSweepRuns) +
                         " values");
      n = static_cast<int>(k) + 1;
    }
    for (int i = 0; i < n; ++i) values.push_back(Number(from + i * step));
  } else if (node.IsScalar()) {
    values.push_back(node.Scalar());
  } else {
    throw UsageError(where + "expected a list of values or a range {from, to, step}");
  }
  if (values.empty()) throw UsageError(where + "has no values");
  return values;
}

void CheckScene(const std::string& scene, const std::string& where) {
  if (scene.empty()) return;
  try {
    scenes::SceneSource::Parse(scene).CheckReadable();
  } catch (const sim::SceneError& e) {
    throw UsageError(where + e.what());
  }
}

std::string Variant(const RunConfig& c) {
  if (c.method == "static_sgbm") return "static_sgbm";
  return c.fovea.selection.deterministic ? "deterministic" : "fovea";
}

// Axes a static baseline keeps (the rest do not concern it).
bool ConcernsStatic(const std::string& path) {
  return path == "scene" || path == "seed" || path.rfind("rig.", 0) == 0 ||
         path.rfind("static.", 0) == 0 || path == "idr.z_min_m" || path == "foveal.fovea_patch_px";
}

}  // namespace

Sweep LoadSweep(const std::string& path) {
  std::string text;
  try {
    text = rig::ReadInputFile(path, "file");
  } catch (const rig::InputError& e) {
    throw UsageError("sweep " + rig::ClipForMessage(path) + ": " + e.what());
  }
  return ParseSweep(text, path);
}

namespace {

using Point = std::vector<std::pair<std::string, std::string>>;  ///< axis path -> value

// The base configuration: the defaults, a `base:` config file (relative to
// the sweep file) and the `config:` mapping over it.
RunConfig ParseBase(const YAML::Node& root, const std::string& path, const std::string& where) {
  RunConfig base;
  if (root["base"]) {
    if (!root["base"].IsScalar()) throw UsageError(where + "key 'base': expected a file name");
    fs::path b = root["base"].Scalar();
    if (b.is_relative()) b = fs::path(path).parent_path() / b;
    base = LoadConfig(b.string());
  }
  if (root["config"]) {
    if (!root["config"].IsMap())
      throw UsageError(where + "key 'config': expected a mapping of parameters");
    ApplyYaml(root["config"], &base, where + "config: ");
  }
  CheckScene(base.scene, where + "key 'scene': ");
  return base;
}

int ParseJobs(const YAML::Node& root, const std::string& where) {
  if (!root["jobs"]) return 0;
  const std::optional<double> jobs =
      root["jobs"].IsScalar() ? ParseNumber(root["jobs"].Scalar()) : std::nullopt;
  if (!jobs || *jobs != std::floor(*jobs) || *jobs < 0 || *jobs > 1024)
    throw UsageError(where + "key 'jobs': expected a whole number in [0, 1024] (0 = every core)");
  return static_cast<int>(*jobs);
}

// The axes, each value checked over the base configuration.
std::vector<SweepAxis> ParseAxes(const YAML::Node& root, const RunConfig& base,
                                 const std::string& where) {
  if (!root["axes"] || !root["axes"].IsMap() || root["axes"].size() == 0)
    throw UsageError(where + "key 'axes': expected a mapping of parameter paths to values");
  std::vector<SweepAxis> axes;
  for (const auto& kv : root["axes"]) {
    SweepAxis axis;
    axis.path = kv.first.as<std::string>();
    RunConfig probe = base;
    try {
      ParamText(&probe, axis.path);
    } catch (const UsageError&) {
      throw UsageError(where + "axes: unknown key '" + rig::ClipForMessage(axis.path) + "'");
    }
    axis.values = AxisValues(kv.second, where + "axes: key '" + axis.path + "': ");
    for (const std::string& v : axis.values) {
      try {
        SetParam(&probe, axis.path, v);
      } catch (const UsageError& e) {
        throw UsageError(where + "axes: " + e.what());
      }
      if (axis.path == "scene") CheckScene(v, where + "axes: key 'scene': ");
    }
    axes.push_back(axis);
  }
  return axes;
}

std::vector<std::string> ParseBaselines(const YAML::Node& root, const std::string& where) {
  std::vector<std::string> baselines;
  if (!root["baselines"]) return baselines;
  if (!root["baselines"].IsSequence()) throw UsageError(where + "key 'baselines': expected a list");
  for (const auto& b : root["baselines"]) {
    const std::string name = b.IsScalar() ? b.Scalar() : "";
    if (name != "deterministic" && name != "static_sgbm")
      throw UsageError(where + "key 'baselines': '" + rig::ClipForMessage(name) +
                       "' is not one of deterministic, static_sgbm");
    baselines.push_back(name);
  }
  return baselines;
}

// Every point of the grid, last axis fastest; refuses a grid past the limit.
std::vector<Point> GridPoints(const std::vector<SweepAxis>& axes, size_t baselines,
                              const std::string& where) {
  long total = 1;
  for (const SweepAxis& a : axes) {
    total *= static_cast<long>(a.values.size());
    if (total * static_cast<long>(1 + baselines) > kMaxSweepRuns)
      throw UsageError(where + "the grid has more than " + std::to_string(kMaxSweepRuns) +
                       " runs (the limit of one sweep; split it into several)");
  }
  std::vector<Point> points;
  std::vector<size_t> index(axes.size(), 0);
  for (long i = 0; i < total; ++i) {
    Point point;
    for (size_t a = 0; a < axes.size(); ++a)
      point.emplace_back(axes[a].path, axes[a].values[index[a]]);
    points.push_back(point);
    for (size_t a = axes.size(); a-- > 0;) {
      if (++index[a] < axes[a].values.size()) break;
      index[a] = 0;
    }
  }
  return points;
}

// Adds the run of one grid point (or one baseline's), checked, unless an
// identical configuration is there already.
void AddRun(RunConfig config, const Point& point, const std::string& where,
            std::set<std::string>* seen, Sweep* sweep) {
  if (config.scene.empty()) config.scene = scenes::kDefaultScene;
  try {
    config.Check();
  } catch (const rig::InputError& e) {
    std::string at;
    for (const auto& [p, v] : point) at += (at.empty() ? "" : ", ") + p + "=" + v;
    throw UsageError(where + "run " + at + ": " + e.what());
  }
  SweepRun run{ConfigHash(config), Variant(config), config, point};
  if (seen->insert(run.id).second) sweep->runs.push_back(std::move(run));
}

}  // namespace

Sweep ParseSweep(const std::string& text, const std::string& path) {
  const std::string where = "sweep " + rig::ClipForMessage(path) + ": ";
  const YAML::Node root = ParseYaml(text, where);
  if (!root.IsMap())
    throw UsageError(where + "expected a mapping with base, config, axes, baselines, jobs");
  for (const auto& kv : root) {
    const std::string key = kv.first.as<std::string>();
    if (key != "base" && key != "config" && key != "axes" && key != "baselines" && key != "jobs")
      throw UsageError(where + "unknown key '" + rig::ClipForMessage(key) +
                       "' (expected base, config, axes, baselines, jobs)");
  }
  Sweep sweep;
  sweep.file = path;
  const RunConfig base = ParseBase(root, path, where);
  sweep.jobs = ParseJobs(root, where);
  sweep.axes = ParseAxes(root, base, where);
  sweep.baselines = ParseBaselines(root, where);
  const std::vector<Point> points = GridPoints(sweep.axes, sweep.baselines.size(), where);
  std::set<std::string> seen;
  for (const Point& point : points) {
    RunConfig c = base;
    for (const auto& [p, v] : point) SetParam(&c, p, v);
    AddRun(c, point, where, &seen, &sweep);
  }
  for (const std::string& b : sweep.baselines)
    for (const Point& point : points) {
      RunConfig c = base;
      Point kept;
      for (const auto& [p, v] : point)
        if (b == "deterministic" || ConcernsStatic(p)) {
          SetParam(&c, p, v);
          kept.emplace_back(p, v);
        }
      if (b == "deterministic")
        c.fovea.selection.deterministic = true;
      else
        c.method = "static_sgbm";
      AddRun(c, kept, where, &seen, &sweep);
    }
  return sweep;
}

nlohmann::json GridJson(const Sweep& sweep) {
  nlohmann::json j;
  j["axes"] = nlohmann::json::array();
  for (const SweepAxis& a : sweep.axes)
    j["axes"].push_back({{"path", a.path}, {"values", a.values}});
  j["baselines"] = sweep.baselines;
  j["runs"] = nlohmann::json::array();
  for (const SweepRun& r : sweep.runs) {
    nlohmann::json run;
    run["id"] = r.id;
    run["variant"] = r.variant;
    run["point"] = nlohmann::json::object();
    for (const auto& [p, v] : r.point) run["point"][p] = v;
    nlohmann::json params = nlohmann::json::array();
    for (const auto& [path, value] : ParamValues(r.config)) params.push_back({path, value});
    run["config"] = params;
    j["runs"].push_back(run);
  }
  return j;
}

bool IsWallClockColumn(const std::string& column) {
  return column == "wall_time_s" || column == "compute_time_s" || column.rfind("time_s.", 0) == 0;
}

namespace {

void Flatten(const nlohmann::json& j, const std::string& prefix,
             std::map<std::string, std::string>* out) {
  if (j.is_object()) {
    for (auto it = j.begin(); it != j.end(); ++it)
      Flatten(it.value(), prefix.empty() ? it.key() : prefix + "." + it.key(), out);
  } else if (j.is_string()) {
    (*out)[prefix] = j.get<std::string>();
  } else if (j.is_number() || j.is_boolean()) {
    (*out)[prefix] = j.dump();
  }
}

std::string CsvField(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (const char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

}  // namespace

nlohmann::json ReadJson(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read '" + path + "'");
  try {
    return nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error("'" + path + "' is not valid JSON: " + e.what());
  }
}

nlohmann::json ReadGridJson(const std::string& dir) {
  const std::string path = dir + "/grid.json";
  const nlohmann::json grid = ReadJson(path);
  auto fail = [&](const std::string& where, const std::string& what) {
    throw std::runtime_error("'" + rig::ClipForMessage(path) + "' is not a sweep grid: " + where +
                             ": " + what);
  };
  auto strings = [&](const nlohmann::json& j, const std::string& where) {
    if (!j.is_array()) fail(where, "expected a list");
    for (size_t i = 0; i < j.size(); ++i)
      if (!j[i].is_string()) fail(where + "[" + std::to_string(i) + "]", "expected a string");
  };
  auto field = [&](const nlohmann::json& j, const char* key,
                   const std::string& where) -> const nlohmann::json& {
    if (!j.is_object() || !j.contains(key)) fail(where, std::string("no '") + key + "'");
    return j.at(key);
  };
  if (!grid.is_object()) fail("the file", "expected an object");
  const nlohmann::json& axes = field(grid, "axes", "the file");
  if (!axes.is_array()) fail("axes", "expected a list");
  for (size_t i = 0; i < axes.size(); ++i) {
    const std::string where = "axes[" + std::to_string(i) + "]";
    if (!field(axes[i], "path", where).is_string()) fail(where + ".path", "expected a string");
    strings(field(axes[i], "values", where), where + ".values");
  }
  strings(field(grid, "baselines", "the file"), "baselines");
  const nlohmann::json& runs = field(grid, "runs", "the file");
  if (!runs.is_array() || runs.empty()) fail("runs", "expected a list of at least one run");
  for (size_t i = 0; i < runs.size(); ++i) {
    const std::string where = "runs[" + std::to_string(i) + "]";
    const nlohmann::json& id = field(runs[i], "id", where);
    // A folder name inside DIR/runs, never a path out of it.
    if (!id.is_string() || id.get<std::string>().empty() ||
        id.get<std::string>().find_first_not_of(
            "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ"
            "0123456789_-") != std::string::npos)
      fail(where + ".id", "expected a name of letters, digits, '_' and '-'");
    if (!field(runs[i], "variant", where).is_string())
      fail(where + ".variant", "expected a string");
    const nlohmann::json& point = field(runs[i], "point", where);
    if (!point.is_object()) fail(where + ".point", "expected an object");
    for (auto it = point.begin(); it != point.end(); ++it)
      if (!it.value().is_string()) fail(where + ".point." + it.key(), "expected a string");
    const nlohmann::json& config = field(runs[i], "config", where);
    if (!config.is_array()) fail(where + ".config", "expected a list");
    for (size_t k = 0; k < config.size(); ++k)
      if (!config[k].is_array() || config[k].size() != 2 || !config[k][0].is_string() ||
          !config[k][1].is_string())
        fail(where + ".config[" + std::to_string(k) + "]", "expected [parameter, value]");
  }
  return grid;
}

std::string ResultsCsv(const std::string& dir, const nlohmann::json& grid,
                       std::vector<std::string>* missing) {
  std::vector<std::string> param_columns;
  for (const auto& p : grid.at("runs").at(0).at("config"))
    param_columns.push_back(p.at(0).get<std::string>());
  std::vector<std::map<std::string, std::string>> rows;
  std::set<std::string> figure_columns;
  for (const auto& run : grid.at("runs")) {
    const std::string id = run.at("id").get<std::string>();
    const std::string summary_path = dir + "/runs/" + id + "/summary.json";
    if (!fs::exists(summary_path)) {
      missing->push_back(id);
      continue;
    }
    std::map<std::string, std::string> figures;
    Flatten(ReadJson(summary_path), "", &figures);
    for (const char* own : {"scene", "seed", "method", "matcher"})
      figures.erase(own);  // parameters already
    for (const auto& [k, v] : figures) figure_columns.insert(k);
    std::map<std::string, std::string> row = figures;
    for (const auto& p : run.at("config"))
      row["param:" + p.at(0).get<std::string>()] = p.at(1).get<std::string>();
    row["run_id"] = id;
    row["variant"] = run.at("variant").get<std::string>();
    rows.push_back(std::move(row));
  }
  std::string csv = "run_id,variant";
  for (const std::string& c : param_columns) csv += "," + CsvField(c);
  for (const std::string& c : figure_columns) csv += "," + CsvField(c);
  csv += "\n";
  for (const auto& row : rows) {
    auto get = [&](const std::string& k) {
      const auto it = row.find(k);
      return it == row.end() ? std::string() : CsvField(it->second);
    };
    csv += get("run_id") + "," + get("variant");
    for (const std::string& c : param_columns) csv += "," + get("param:" + c);
    for (const std::string& c : figure_columns) csv += "," + get(c);
    csv += "\n";
  }
  return csv;
}

std::pair<int, int> ParseShard(const std::string& text) {
  int i = 0, n = 0;
  char extra;
  if (std::sscanf(text.c_str(), "%d/%d%c", &i, &n, &extra) != 2 || n < 1 || i < 1 || i > n)
    throw UsageError("--shard expects I/N with 1 <= I <= N, got '" + text + "'");
  return {i, n};
}

}  // namespace experiments
