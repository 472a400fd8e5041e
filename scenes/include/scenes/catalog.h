// The scene catalog: named MJCF scenes shipped under scenes/, and the
// procedural textures they (and user scenes) may name.
#pragma once

#include <string>
#include <vector>

#include "sim/simulation.h"

namespace scenes {

/// The scene every command uses when none is given.
inline constexpr const char* kDefaultScene = "plane";

/// Names of the catalog scenes.
std::vector<std::string> CatalogNames();

/// Folder holding the catalog's scene files: $FOVEA_SCENES_DIR if set, else
/// the source tree's scenes/ folder.
std::string ScenesDir();

/// A catalog name ("plane") or a path to an MJCF file ("my/scene.xml"). A
/// name that is not in the catalog throws sim::SceneError listing the names.
std::string ResolveScene(const std::string& name_or_path);

/// Serves procedural textures to MuJoCo by file name (see scenes/README.md):
/// "<kind>-s<seed>.png", generated deterministically in memory.
sim::AssetProvider TextureProvider();

/// Loads a scene by name or path with the procedural textures available.
std::unique_ptr<sim::Simulation> LoadScene(const std::string& name_or_path,
                                           const sim::SimRigConfig& config);

}  // namespace scenes
