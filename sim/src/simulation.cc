#include "sim/simulation.h"

#include <mujoco/mjxmacro.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>

#include "sim/sim_rig.h"
#include "world.h"

namespace sim {
namespace {

// MuJoCo's default error handler prints and exits; ours says what failed in
// one line first. (Loading errors never reach it: mj_loadXML returns them.)
void MujocoError(const char* msg) {
  std::fprintf(stderr, "fovea: error: MuJoCo: %s\n", msg);
  std::exit(3);
}
void MujocoWarning(const char* msg) { std::fprintf(stderr, "fovea: warning: MuJoCo: %s\n", msg); }

// While a scene compiles, MuJoCo's warnings wait here: a scene refused for
// the reason a warning gives is one error line, not a warning and an error.
std::vector<std::string> g_load_warnings;
void HoldWarning(const char* msg) { g_load_warnings.emplace_back(msg); }

std::string OneLine(std::string s) {
  for (char& ch : s)
    if (ch == '\n' || ch == '\r') ch = ' ';
  while (!s.empty() && s.back() == ' ') s.pop_back();
  return s;
}

std::string BaseName(const std::string& path) {
  const size_t slash = path.find_last_of("/\\");
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

void AddToVfs(mjVFS* vfs, const std::string& name, const void* data, size_t size) {
  if (mj_findFileVFS(vfs, name.c_str()) >= 0) return;
  if (mj_makeEmptyFileVFS(vfs, name.c_str(), static_cast<int>(size)) != 0)
    throw SceneError("cannot add '" + name + "' to MuJoCo's virtual file system");
  std::memcpy(vfs->filedata[mj_findFileVFS(vfs, name.c_str())], data, size);
}

// Which kind of element a model array's rows belong to, by its row count's
// name; mjOBJ_UNKNOWN for arrays not indexed by one element kind.
int RowObject(const std::string& rows) {
  static const std::pair<const char*, int> kKinds[] = {
      {"nbody", mjOBJ_BODY},   {"njnt", mjOBJ_JOINT},     {"ngeom", mjOBJ_GEOM},
      {"nsite", mjOBJ_SITE},   {"ncam", mjOBJ_CAMERA},    {"nlight", mjOBJ_LIGHT},
      {"nmesh", mjOBJ_MESH},   {"nmat", mjOBJ_MATERIAL},  {"ntex", mjOBJ_TEXTURE},
      {"nu", mjOBJ_ACTUATOR},  {"nsensor", mjOBJ_SENSOR}, {"ntendon", mjOBJ_TENDON},
      {"neq", mjOBJ_EQUALITY}, {"nhfield", mjOBJ_HFIELD}};
  for (const auto& [name, kind] : kKinds)
    if (rows == name) return kind;
  return mjOBJ_UNKNOWN;
}

template <class T>
long FirstNonFinite(const T* values, long n) {
  if constexpr (std::is_floating_point_v<T>) {
    for (long i = 0; i < n; ++i)
      if (!std::isfinite(values[i])) return i;
  } else {
    (void)values, (void)n;
  }
  return -1;
}

// Throws SceneError naming the element and the field of the first NaN or
// infinite number in the compiled model (MuJoCo runs on with a warning).
void CheckFinite(const mjModel* m, const std::string& where) {
  MJMODEL_POINTERS_PREAMBLE(m)
  (void)nq, (void)nv, (void)na, (void)nu, (void)nmocap;
#define X(type, name, nr, nc)                                                              \
  if (const long at = FirstNonFinite(m->name, static_cast<long>(m->nr) * (nc)); at >= 0) { \
    const long row = at / (nc);                                                            \
    const int kind = RowObject(#nr);                                                       \
    const char* element =                                                                  \
        kind == mjOBJ_UNKNOWN ? nullptr : mj_id2name(m, kind, static_cast<int>(row));      \
    throw SceneError(                                                                      \
        where + ": " +                                                                     \
        (element ? std::string("'") + element + "'" : "element #" + std::to_string(row)) + \
        " has a non-finite number (NaN or infinity) in " #name);                           \
  }
  MJMODEL_POINTERS
#undef X
}

const char* const kAxisNames[rig::kNumAxes] = {"tavt_left_baseline", "tavt_left_pan",
                                               "tavt_left_tilt",     "tavt_right_baseline",
                                               "tavt_right_pan",     "tavt_right_tilt"};

}  // namespace

Simulation::Simulation() = default;
Simulation::~Simulation() = default;

std::unique_ptr<Simulation> Simulation::Load(const std::string& scene_path,
                                             const SimRigConfig& config,
                                             const AssetProvider& assets) {
  config.Check();
  std::string text;
  try {
    text = rig::ReadInputFile(scene_path, "scene file");
  } catch (const rig::InputError& e) {
    throw SceneError(e.what());
  }
  return LoadImpl(scene_path, text, /*from_memory=*/false, config, assets);
}

std::unique_ptr<Simulation> Simulation::LoadText(const std::string& name, const std::string& xml,
                                                 const SimRigConfig& config,
                                                 const AssetProvider& assets) {
  config.Check();
  return LoadImpl(name, xml, /*from_memory=*/true, config, assets);
}

namespace {

// The scene compiled with the rig, its numbers finite and its rules kept:
// everything of a load but the renderer. Throws SceneError.
std::unique_ptr<World> CompileWorld(const std::string& scene_path, const std::string& xml,
                                    bool from_memory, const SimRigConfig& config,
                                    const AssetProvider& assets) {
  mju_user_error = MujocoError;
  const std::string shown = rig::ClipForMessage(scene_path);
  if (xml.find("<mujoco") == std::string::npos)
    throw SceneError("scene file '" + shown + "' is not an MJCF model (no <mujoco> element)");

  // The rig model and any generated assets are served from memory.
  struct VfsDeleter {
    void operator()(mjVFS* vfs) const {
      mj_deleteVFS(vfs);
      delete vfs;
    }
  };
  const std::unique_ptr<mjVFS, VfsDeleter> vfs(new mjVFS);
  mj_defaultVFS(vfs.get());
  const std::string rig_xml = RigMjcf(config);
  AddToVfs(vfs.get(), kRigIncludeName, rig_xml.data(), rig_xml.size());
  // Files the scene names that MuJoCo would read itself from its folder
  // must be regular files of bounded size, like the scene.
  static const std::regex kFileAttr(R"(file\s*=\s*"([^"]+)\")");
  std::set<std::string> seen;
  const std::filesystem::path scene_dir = std::filesystem::path(scene_path).parent_path();
  for (auto it = std::sregex_iterator(xml.begin(), xml.end(), kFileAttr);
       it != std::sregex_iterator(); ++it) {
    const std::string file = (*it)[1].str(), name = BaseName(file);
    if (name == kRigIncludeName || !seen.insert(file).second) continue;
    if (assets)
      if (auto bytes = assets(name)) {
        AddToVfs(vfs.get(), name, bytes->data(), bytes->size());
        continue;
      }
    const std::filesystem::path on_disk = scene_dir / file;
    std::error_code ec;
    if (!from_memory && std::filesystem::exists(on_disk, ec)) try {
        rig::CheckInputFile(on_disk.string(), "scene '" + shown + "': file");
      } catch (const rig::InputError& e) {
        throw SceneError(e.what());
      }
  }
  const std::string main_name = from_memory ? "fovea_generated_scene.xml" : scene_path;
  if (from_memory) AddToVfs(vfs.get(), main_name, xml.data(), xml.size());
  char error[1024] = "";
  g_load_warnings.clear();
  mju_user_warning = HoldWarning;
  mjModel* m = mj_loadXML(main_name.c_str(), vfs.get(), error, sizeof error);
  mju_user_warning = MujocoWarning;
  if (!m) throw SceneError("cannot load scene '" + shown + "': " + OneLine(error));
  try {
    CheckFinite(m, "scene '" + shown + "'");
  } catch (...) {
    mj_deleteModel(m);
    throw;
  }
  for (const std::string& warning : g_load_warnings) MujocoWarning(warning.c_str());

  auto world = std::make_unique<World>();
  World& w = *world;
  w.m = m;
  w.scene_path = scene_path;
  for (int i = 0; i < rig::kNumAxes; ++i) {
    w.joint_ids[i] = mj_name2id(m, mjOBJ_JOINT, kAxisNames[i]);
    w.actuator_ids[i] = mj_name2id(m, mjOBJ_ACTUATOR, kAxisNames[i]);
    if (w.joint_ids[i] < 0 || w.actuator_ids[i] < 0) {
      throw SceneError("scene '" + shown + "' does not include the rig model (<include file=\"" +
                       kRigIncludeName + "\"/>): joint '" + kAxisNames[i] + "' is missing");
    }
  }
  w.camera_ids = {mj_name2id(m, mjOBJ_CAMERA, "tavt_left"),
                  mj_name2id(m, mjOBJ_CAMERA, "tavt_right")};
  w.truth_camera_id = mj_name2id(m, mjOBJ_CAMERA, "tavt_truth");
  // Depth resolution: near and far planes for a 0.05 to 30 m working range.
  m->vis.map.znear = static_cast<float>(0.05 / m->stat.extent);
  m->vis.map.zfar = static_cast<float>(30.0 / m->stat.extent);
  w.visible_groups = {1, 1, 1, 0, 0, 0};
  w.d = mj_makeData(m);
  mj_forward(m, w.d);
  CheckSceneRules(w, RigWorkspace(config));
  return world;
}

}  // namespace

void Simulation::CheckScene(const std::string& name, const std::string& xml,
                            const SimRigConfig& config, const AssetProvider& assets) {
  config.Check();
  CompileWorld(name, xml, /*from_memory=*/true, config, assets);
}

std::unique_ptr<Simulation> Simulation::LoadImpl(const std::string& scene_path,
                                                 const std::string& xml, bool from_memory,
                                                 const SimRigConfig& config,
                                                 const AssetProvider& assets) {
  std::unique_ptr<Simulation> sim(new Simulation());
  sim->world_ = CompileWorld(scene_path, xml, from_memory, config, assets);
  World& w = *sim->world_;
  const cv::Size render = RenderSize(config);
  w.renderer = new OffscreenRenderer(w.m, render.width, render.height);
  sim->rig_ = std::make_unique<SimRig>(sim->world_.get(), config);
  sim->truth_ = std::make_unique<GroundTruth>(sim->world_.get());
  sim->config_ = config;
  return sim;
}

rig::Rig& Simulation::rig() { return *rig_; }
SimRig& Simulation::sim_rig() { return *rig_; }
const GroundTruth& Simulation::truth() const { return *truth_; }
const SimRigConfig& Simulation::config() const { return config_; }
const std::string& Simulation::scene_path() const { return world_->scene_path; }

}  // namespace sim
