// Procedural, deterministic textures (OpenCV). Same kind and seed, same bytes.
//
// Scale: catalog materials tile a texture every 0.5 m (texrepeat="4 4"
// texuniform="true": MuJoCo 2.2 tiles texrepeat / 2 times per metre, measured
// by tests/catalog_test.cc), so one texel of a 1024-texel texture is 0.49 mm: the
// pixel footprint of the default camera (f = 1194 px) is 0.33 mm at 0.4 m and
// 1.26 mm at 1.5 m, so every textured kind has detail at the pixel scale over
// the paper's working range.
#pragma once

#include <cstdint>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

namespace scenes {

/// Texture side in texels, and the strict period of the periodic kinds.
inline constexpr int kTextureSizePx = 1024;
inline constexpr int kPeriodicPeriodPx = 32;  ///< 15.6 mm on a 0.5 m tile

/// The texture kinds a scene may name: wood, tile, fabric, plywood, photo,
/// stripes, checker (textured) and uniform (no texture at all).
std::vector<std::string> TextureKinds();

/// A square BGR texture of `kind` from `seed`. Throws sim::SceneError for an
/// unknown kind.
cv::Mat MakeTexture(const std::string& kind, uint64_t seed, int size_px = kTextureSizePx);

/// "<kind>-s<seed>.png" parsed; nullopt if the name does not follow it.
struct TextureName {
  std::string kind;
  uint64_t seed = 0;
};
std::optional<TextureName> ParseTextureName(const std::string& file_name);

}  // namespace scenes
