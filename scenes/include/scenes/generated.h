// Scene content made by code: meshes served to MuJoCo by file name, and the
// random scene generator.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

namespace scenes {

/// Texture coordinates of generated meshes run 2 tiles per metre of surface,
/// like the catalog's texuniform materials (texrepeat="4 4", which MuJoCo 2.2
/// turns into 2 tiles per metre); mesh materials keep texrepeat="1 1".
inline constexpr double kTexTilesPerMetre = 2.0;

/// Wavefront OBJ text for "cylinder-r<radius mm>-h<height mm>.obj": an open,
/// vertical cylinder centred at the origin, 720 facets (its chord deviates
/// from the true circle by under 1e-5 of the radius), with texture
/// coordinates by arc length and height. nullopt for other names.
std::optional<std::string> MakeMesh(const std::string& file_name);

/// Parameters of the `random` scene: "random", "random:SEED" or
/// "random:SEED:N" (N objects, 1 to 30).
struct RandomSceneSpec {
  uint64_t seed = 1;
  int objects = 6;
};
/// nullopt if `name` is not a random-scene name; throws sim::SceneError for
/// a malformed one.
std::optional<RandomSceneSpec> ParseRandomSceneName(const std::string& name);

/// MJCF of N textured boxes, cylinders and slanted planes placed from the
/// seed between 0.5 and 1.3 m in front of the rig, before a textured back
/// wall at 1.5 m. Same spec, same text.
std::string RandomSceneXml(const RandomSceneSpec& spec);

}  // namespace scenes
