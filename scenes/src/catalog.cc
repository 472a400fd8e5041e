#include "scenes/catalog.h"

#include <cstdlib>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "scenes/textures.h"

namespace scenes {

std::vector<std::string> CatalogNames() { return {"plane"}; }

std::string ScenesDir() {
  if (const char* env = std::getenv("FOVEA_SCENES_DIR"); env && *env) return env;
  return FOVEA_SCENES_SOURCE_DIR;
}

std::string ResolveScene(const std::string& name_or_path) {
  if (name_or_path.find('/') != std::string::npos ||
      std::filesystem::path(name_or_path).extension() == ".xml") {
    return name_or_path;
  }
  for (const auto& name : CatalogNames())
    if (name == name_or_path) return ScenesDir() + "/" + name + ".xml";
  std::string names;
  for (const auto& name : CatalogNames()) names += (names.empty() ? "" : ", ") + name;
  throw sim::SceneError("unknown scene '" + name_or_path + "' (catalog: " + names +
                        "; or give a path to an .xml file)");
}

sim::AssetProvider TextureProvider() {
  return [](const std::string& name) -> std::optional<std::vector<uint8_t>> {
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
  return sim::Simulation::Load(ResolveScene(name_or_path), config, TextureProvider());
}

}  // namespace scenes
