#include "sim/simulation.h"

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
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

const char* const kAxisNames[rig::kNumAxes] = {"tavt_left_baseline",  "tavt_left_pan",
                                               "tavt_left_tilt",      "tavt_right_baseline",
                                               "tavt_right_pan",      "tavt_right_tilt"};

}  // namespace

Simulation::Simulation() = default;
Simulation::~Simulation() = default;

std::unique_ptr<Simulation> Simulation::Load(const std::string& scene_path,
                                             const SimRigConfig& config,
                                             const AssetProvider& assets) {
  config.Check();
  std::ifstream in(scene_path, std::ios::binary);
  if (!in) {
    throw SceneError("cannot read scene file '" + scene_path + "': " + std::strerror(errno));
  }
  std::stringstream text;
  text << in.rdbuf();
  return LoadImpl(scene_path, text.str(), /*from_memory=*/false, config, assets);
}

std::unique_ptr<Simulation> Simulation::LoadText(const std::string& name, const std::string& xml,
                                                 const SimRigConfig& config,
                                                 const AssetProvider& assets) {
  config.Check();
  return LoadImpl(name, xml, /*from_memory=*/true, config, assets);
}

std::unique_ptr<Simulation> Simulation::LoadImpl(const std::string& scene_path,
                                                 const std::string& xml, bool from_memory,
                                                 const SimRigConfig& config,
                                                 const AssetProvider& assets) {
  mju_user_error = MujocoError;
  mju_user_warning = MujocoWarning;
  if (xml.find("<mujoco") == std::string::npos)
    throw SceneError("scene file '" + scene_path + "' is not an MJCF model (no <mujoco> element)");

  // The rig model and any generated assets are served from memory.
  auto vfs = std::make_unique<mjVFS>();
  mj_defaultVFS(vfs.get());
  const std::string rig_xml = RigMjcf(config);
  AddToVfs(vfs.get(), kRigIncludeName, rig_xml.data(), rig_xml.size());
  if (assets) {
    static const std::regex kFileAttr(R"(file\s*=\s*"([^"]+)\")");
    std::set<std::string> seen;
    for (auto it = std::sregex_iterator(xml.begin(), xml.end(), kFileAttr);
         it != std::sregex_iterator(); ++it) {
      const std::string name = BaseName((*it)[1].str());
      if (name == kRigIncludeName || !seen.insert(name).second) continue;
      if (auto bytes = assets(name)) AddToVfs(vfs.get(), name, bytes->data(), bytes->size());
    }
  }
  const std::string main_name = from_memory ? "fovea_generated_scene.xml" : scene_path;
  if (from_memory) AddToVfs(vfs.get(), main_name, xml.data(), xml.size());
  char error[1024] = "";
  mjModel* m = mj_loadXML(main_name.c_str(), vfs.get(), error, sizeof error);
  mj_deleteVFS(vfs.get());
  if (!m) throw SceneError("cannot load scene '" + scene_path + "': " + OneLine(error));

  std::unique_ptr<Simulation> sim(new Simulation());
  sim->world_ = std::make_unique<World>();
  World& w = *sim->world_;
  w.m = m;
  w.scene_path = scene_path;
  for (int i = 0; i < rig::kNumAxes; ++i) {
    w.joint_ids[i] = mj_name2id(m, mjOBJ_JOINT, kAxisNames[i]);
    w.actuator_ids[i] = mj_name2id(m, mjOBJ_ACTUATOR, kAxisNames[i]);
    if (w.joint_ids[i] < 0 || w.actuator_ids[i] < 0) {
      throw SceneError("scene '" + scene_path + "' does not include the rig model (<include file=\"" +
                       kRigIncludeName + "\"/>): joint '" + kAxisNames[i] + "' is missing");
    }
  }
  w.camera_ids = {mj_name2id(m, mjOBJ_CAMERA, "tavt_left"), mj_name2id(m, mjOBJ_CAMERA, "tavt_right")};
  w.truth_camera_id = mj_name2id(m, mjOBJ_CAMERA, "tavt_truth");
  // Depth resolution: near and far planes for a 0.05 to 30 m working range.
  m->vis.map.znear = static_cast<float>(0.05 / m->stat.extent);
  m->vis.map.zfar = static_cast<float>(30.0 / m->stat.extent);
  w.visible_groups = {1, 1, 1, 0, 0, 0};
  w.d = mj_makeData(m);
  mj_forward(m, w.d);
  CheckSceneRules(w, RigWorkspace(config));
  w.renderer = new OffscreenRenderer(m, config.width_px, config.height_px);

  sim->rig_ = std::make_unique<SimRig>(sim->world_.get(), config);
  sim->truth_ = std::make_unique<GroundTruth>(sim->world_.get());
  sim->config_ = config;
  return sim;
}

rig::Rig& Simulation::rig() { return *rig_; }
const GroundTruth& Simulation::truth() const { return *truth_; }
const SimRigConfig& Simulation::config() const { return config_; }
const std::string& Simulation::scene_path() const { return world_->scene_path; }

}  // namespace sim
