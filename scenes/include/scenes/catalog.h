// The scene catalog: named MJCF scenes shipped under scenes/, and the
// procedural textures they (and user scenes) may name.
#pragma once

#include <string>
#include <vector>

#include "scenes/generated.h"
#include "sim/simulation.h"

namespace scenes {

/// The scene every command uses when none is given.
inline constexpr const char* kDefaultScene = "cylinder_planes";

/// Names of the catalog scenes.
std::vector<std::string> CatalogNames();

/// Folder holding the catalog's scene files: $FOVEA_SCENES_DIR if set, else
/// the source tree's scenes/ folder.
std::string ScenesDir();

/// What a scene name means, parsed once: a catalog scene ("two_planes": its
/// file under ScenesDir()), a generated random scene ("random",
/// "random:7", "random:7:10"), or the path of a user's MJCF file (anything
/// with a '/' or ending in ".xml").
struct SceneSource {
  enum class Kind { kCatalog, kRandom, kFile };
  Kind kind = Kind::kCatalog;
  std::string name;        ///< as given
  std::string path;        ///< the MJCF file (catalog or user); the name for a random scene
  RandomSceneSpec random;  ///< for kRandom
  /// Throws sim::SceneError for a name that is none of these (listing the
  /// catalog) and for a malformed random name.
  static SceneSource Parse(const std::string& name_or_path);
  /// Throws sim::SceneError unless the scene can be read: a catalog or user
  /// scene's file is a regular file of bounded size (a random one always can).
  void CheckReadable() const;
};

/// Serves generated assets to MuJoCo by file name (see scenes/README.md):
/// textures "<kind>-s<seed>.png" and meshes "cylinder-r<mm>-h<mm>.obj".
sim::AssetProvider TextureProvider();

/// Loads a scene by name or path with the procedural textures available.
std::unique_ptr<sim::Simulation> LoadScene(const std::string& name_or_path,
                                           const sim::SimRigConfig& config);

}  // namespace scenes
