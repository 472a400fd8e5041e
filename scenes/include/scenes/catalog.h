// The scene catalog: named MJCF scenes shipped under scenes/, and the
// procedural textures they (and user scenes) may name.
#pragma once

#include <string>
#include <vector>

#include "sim/simulation.h"

namespace scenes {

/// The scene every command uses when none is given.
inline constexpr const char* kDefaultScene = "cylinder_planes";

/// Names of the catalog scenes.
std::vector<std::string> CatalogNames();

/// Folder holding the catalog's scene files: $FOVEA_SCENES_DIR if set, else
/// the source tree's scenes/ folder.
std::string ScenesDir();

/// A catalog name ("two_planes"), a random-scene name ("random:7:10", kept
/// as is) or a path to an MJCF file ("my/scene.xml", kept as is). A name that
/// is not in the catalog throws sim::SceneError listing the names.
std::string ResolveScene(const std::string& name_or_path);

/// Serves generated assets to MuJoCo by file name (see scenes/README.md):
/// textures "<kind>-s<seed>.png" and meshes "cylinder-r<mm>-h<mm>.obj".
sim::AssetProvider TextureProvider();

/// Loads a scene by name or path with the procedural textures available.
std::unique_ptr<sim::Simulation> LoadScene(const std::string& name_or_path,
                                           const sim::SimRigConfig& config);

}  // namespace scenes
