// Procedural, deterministic textures (OpenCV). Same kind and seed, same bytes.
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

namespace scenes {

/// The texture kinds a scene may name.
std::vector<std::string> TextureKinds();

/// A square BGR texture of `kind`, `size_px` on a side, from `seed`. Throws
/// sim::SceneError for an unknown kind.
cv::Mat MakeTexture(const std::string& kind, uint64_t seed, int size_px = 1024);

/// Parses "<kind>-s<seed>.png"; nullopt if the name does not follow it.
struct TextureName {
  std::string kind;
  uint64_t seed = 0;
};
std::optional<TextureName> ParseTextureName(const std::string& file_name);

}  // namespace scenes
