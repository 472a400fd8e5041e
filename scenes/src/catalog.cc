#include "scenes/catalog.h"

#include <cstdlib>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "scenes/generated.h"
#include "scenes/textures.h"

namespace scenes {

std::vector<std::string> CatalogNames() {
  return {"fronto_planes", "cylinder_planes", "two_planes", "three_surfaces", "periodic",
          "textureless",   "sphere_wall",     "staircase",  "post_slant",     "random"};
}

std::string ScenesDir() {
  if (const char* env = std::getenv("FOVEA_SCENES_DIR"); env && *env) return env;
  return FOVEA_SCENES_SOURCE_DIR;
}

SceneSource SceneSource::Parse(const std::string& name_or_path) {
  SceneSource source;
  source.name = name_or_path;
  source.path = name_or_path;
  if (name_or_path.find('/') != std::string::npos ||
      std::filesystem::path(name_or_path).extension() == ".xml") {
    source.kind = Kind::kFile;
    return source;
  }
  if (const auto spec = ParseRandomSceneName(name_or_path)) {
    source.kind = Kind::kRandom;
    source.random = *spec;
    return source;
  }
  for (const auto& name : CatalogNames())
    if (name == name_or_path) {
      source.kind = Kind::kCatalog;
      source.path = ScenesDir() + "/" + name + ".xml";
      return source;
    }
  std::string names;
  for (const auto& name : CatalogNames()) names += (names.empty() ? "" : ", ") + name;
  throw sim::SceneError("unknown scene '" + rig::ClipForMessage(name_or_path) +
                        "' (catalog: " + names + "; or give a path to an .xml file)");
}

void SceneSource::CheckReadable() const {
  if (kind == Kind::kRandom) return;
  try {
    rig::CheckInputFile(path, "scene file");
  } catch (const rig::InputError& e) {
    throw sim::SceneError(e.what());
  }
}

sim::AssetProvider TextureProvider() {
  return [](const std::string& name) -> std::optional<std::vector<uint8_t>> {
    if (auto mesh = MakeMesh(name)) return std::vector<uint8_t>(mesh->begin(), mesh->end());
    const auto parsed = ParseTextureName(name);
    if (!parsed) return std::nullopt;
    const auto kinds = TextureKinds();
    if (std::find(kinds.begin(), kinds.end(), parsed->kind) == kinds.end()) return std::nullopt;
    std::vector<uint8_t> png;
    cv::imencode(".png", MakeTexture(parsed->kind, parsed->seed), png,
                 {cv::IMWRITE_PNG_COMPRESSION, 1});
    return png;
  };
}

std::unique_ptr<sim::Simulation> LoadScene(const std::string& name_or_path,
                                           const sim::SimRigConfig& config) {
  const SceneSource source = SceneSource::Parse(name_or_path);
  if (source.kind == SceneSource::Kind::kRandom)
    return sim::Simulation::LoadText(source.name, RandomSceneXml(source.random), config,
                                     TextureProvider());
  return sim::Simulation::Load(source.path, config, TextureProvider());
}

}  // namespace scenes
