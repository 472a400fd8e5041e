#include "scenes/textures.h"

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <regex>

#include "sim/config.h"

namespace scenes {
namespace {

using cv::Mat;

// Smooth random field: uniform noise on a cells x cells grid, upsampled with
// wrap-around so that the texture tiles seamlessly. Values in [0, 1].
Mat NoiseField(cv::RNG& rng, int size, int cells_x, int cells_y) {
  Mat grid(cells_y, cells_x, CV_32F);
  rng.fill(grid, cv::RNG::UNIFORM, 0.0, 1.0);
  if (cells_x >= size && cells_y >= size) return grid;
  // Pad by wrapping, upsample, crop: seamless at the borders.
  Mat padded;
  cv::copyMakeBorder(grid, padded, 2, 2, 2, 2, cv::BORDER_WRAP);
  const double sx = double(size) / cells_x, sy = double(size) / cells_y;
  Mat up;
  cv::resize(padded, up, cv::Size(), sx, sy, cv::INTER_CUBIC);
  const int ox = int(std::lround(2 * sx)), oy = int(std::lround(2 * sy));
  return up(cv::Rect(ox, oy, size, size)).clone();
}

// Fractal noise: octaves from `first_cells` cells up to one cell per texel,
// weights multiplied by `persistence` per octave. Normalized to [0, 1].
Mat Fractal(cv::RNG& rng, int size, int first_cells, double persistence) {
  Mat sum(size, size, CV_32F, cv::Scalar(0));
  double w = 1;
  for (int cells = first_cells; cells <= size; cells *= 2, w *= persistence)
    sum += w * NoiseField(rng, size, cells, cells);
  cv::normalize(sum, sum, 0, 1, cv::NORM_MINMAX);
  return sum;
}

// Maps t in [0, 1] to a colour between `dark` and `light` (BGR).
Mat Colorize(const Mat& t, cv::Vec3f dark, cv::Vec3f light) {
  Mat out(t.size(), CV_8UC3);
  for (int r = 0; r < t.rows; ++r) {
    const float* src = t.ptr<float>(r);
    cv::Vec3b* dst = out.ptr<cv::Vec3b>(r);
    for (int c = 0; c < t.cols; ++c) {
      const float s = std::clamp(src[c], 0.0f, 1.0f);
      for (int ch = 0; ch < 3; ++ch)
        dst[c][ch] = cv::saturate_cast<uchar>(dark[ch] + s * (light[ch] - dark[ch]));
    }
  }
  return out;
}

Mat Photo(cv::RNG& rng, int size) {
  const Mat lum = Fractal(rng, size, 4, 0.8);
  const Mat hue = Fractal(rng, size, 2, 0.5);
  Mat out = Colorize(lum, {25, 35, 45}, {230, 225, 215});
  for (int r = 0; r < size; ++r)
    for (int c = 0; c < size; ++c) {
      const float h = hue.at<float>(r, c);
      cv::Vec3b& px = out.at<cv::Vec3b>(r, c);
      px[0] = cv::saturate_cast<uchar>(px[0] * (0.75f + 0.5f * h));
      px[2] = cv::saturate_cast<uchar>(px[2] * (1.25f - 0.5f * h));
    }
  return out;
}

// Growth rings running vertically (along v), warped by smooth noise, with
// fine fibres: strong variation across the grain at the millimetre scale.
Mat Grain(cv::RNG& rng, int size, double rings_per_tile, double warp, double fibre_contrast,
          cv::Vec3f dark, cv::Vec3f light) {
  const Mat bend = NoiseField(rng, size, 4, 4);
  const Mat ripple = NoiseField(rng, size, 16, 32);
  // Fibres: fine across the grain, long along it.
  const Mat fibres = NoiseField(rng, size, size / 2, size / 32);
  const Mat speckle = NoiseField(rng, size, size, size);
  Mat t(size, size, CV_32F);
  for (int r = 0; r < size; ++r)
    for (int c = 0; c < size; ++c) {
      const double x = double(c) / size + warp * (bend.at<float>(r, c) - 0.5) +
                       0.15 * warp * (ripple.at<float>(r, c) - 0.5);
      const double phase = rings_per_tile * x;
      const double ring = std::pow(0.5 + 0.5 * std::sin(2 * M_PI * phase), 3.0);
      t.at<float>(r, c) =
          float(0.15 + 0.55 * ring + fibre_contrast * (fibres.at<float>(r, c) - 0.5) +
                0.12 * (speckle.at<float>(r, c) - 0.5));
    }
  return Colorize(t, dark, light);
}

// Glazed tiles 128 texels (62 mm) square with 6-texel grout; each tile a
// slightly different shade with a speckled glaze so its face is matchable.
Mat Tile(cv::RNG& rng, int size) {
  const int pitch = 128, grout = 6;
  const int n = size / pitch;
  Mat shade(n, n, CV_32F);
  rng.fill(shade, cv::RNG::UNIFORM, -0.08, 0.08);
  const Mat glaze = Fractal(rng, size, 32, 0.9);
  const Mat speckle = NoiseField(rng, size, size / 2, size / 2);  // 1 mm grains
  Mat t(size, size, CV_32F);
  for (int r = 0; r < size; ++r)
    for (int c = 0; c < size; ++c) {
      const int tr = r % pitch, tc = c % pitch;
      const bool in_grout = tr < grout || tc < grout;
      t.at<float>(r, c) = in_grout ? 0.12f + 0.1f * glaze.at<float>(r, c)
                                   : 0.62f + shade.at<float>(r / pitch, c / pitch) +
                                         0.35f * (glaze.at<float>(r, c) - 0.5f) +
                                         0.35f * (speckle.at<float>(r, c) - 0.5f);
    }
  return Colorize(t, {40, 45, 50}, {225, 235, 240});
}

// Plain weave (period 6 texels, 3 mm) under a plaid of coloured bands of
// random widths, with yarn irregularity.
Mat Fabric(cv::RNG& rng, int size) {
  std::vector<float> band_x(size), band_y(size);
  for (auto* band : {&band_x, &band_y}) {
    int pos = 0;
    while (pos < size) {
      const int width = rng.uniform(8, 60);
      const float level = float(rng.uniform(0.35, 1.0));
      for (int i = pos; i < std::min(size, pos + width); ++i) (*band)[i] = level;
      pos += width;
    }
  }
  const Mat yarn = NoiseField(rng, size, size / 2, size / 2);
  Mat t(size, size, CV_32F);
  for (int r = 0; r < size; ++r)
    for (int c = 0; c < size; ++c) {
      const bool warp_on_top = ((r / 3) + (c / 3)) % 2 == 0;
      const float cross = warp_on_top ? std::sin(float(M_PI) * (c % 3 + 0.5f) / 3)
                                      : std::sin(float(M_PI) * (r % 3 + 0.5f) / 3);
      const float colour = warp_on_top ? band_x[c] : band_y[r];
      t.at<float>(r, c) = colour * (0.55f + 0.35f * cross) + 0.25f * (yarn.at<float>(r, c) - 0.5f);
    }
  return Colorize(t, {80, 60, 50}, {240, 225, 215});
}

Mat Plywood(cv::RNG& rng, int size) {
  Mat out = Grain(rng, size, 9, 0.35, 0.6, {70, 120, 170}, {185, 222, 245});
  // A few dark knots.
  const int knots = rng.uniform(2, 5);
  for (int k = 0; k < knots; ++k) {
    const cv::Point centre(rng.uniform(0, size), rng.uniform(0, size));
    const cv::Size axes(rng.uniform(6, 14), rng.uniform(12, 30));
    for (int ring = 3; ring >= 0; --ring) {
      const double s = 1.0 + 0.6 * ring;
      const int v = 60 + 25 * ring;
      cv::ellipse(out, centre, cv::Size(int(axes.width * s), int(axes.height * s)), 0, 0, 360,
                  cv::Scalar(v, v + 25, v + 50), ring == 0 ? -1 : 2, cv::LINE_AA);
    }
  }
  return out;
}

// Strictly periodic square waves with anti-aliased edges; the seed picks the
// phase and the two colours, never the period.
Mat Periodic(cv::RNG& rng, int size, bool checker) {
  const int p = kPeriodicPeriodPx;
  const int phase = rng.uniform(0, p);
  const cv::Vec3f a(float(rng.uniform(10, 60)), float(rng.uniform(10, 60)),
                    float(rng.uniform(10, 60)));
  const cv::Vec3f b(float(rng.uniform(190, 250)), float(rng.uniform(190, 250)),
                    float(rng.uniform(190, 250)));
  auto wave = [&](int i) {
    // +1 on the first half period, -1 on the second, one-texel ramps.
    const double x = (i + phase) % p + 0.5;
    const double half = p / 2.0;
    const double d = std::min({x, std::abs(x - half), p - x});  // distance to an edge
    const double s = std::min(1.0, d);
    return (x < half ? 1.0 : -1.0) * s;
  };
  Mat t(size, size, CV_32F);
  for (int r = 0; r < size; ++r)
    for (int c = 0; c < size; ++c) {
      const double w = checker ? wave(c) * wave(r) : wave(c);
      t.at<float>(r, c) = float(0.5 + 0.5 * w);
    }
  return Colorize(t, a, b);
}

}  // namespace

std::vector<std::string> TextureKinds() {
  return {"wood", "tile", "fabric", "plywood", "photo", "stripes", "checker", "uniform"};
}

Mat MakeTexture(const std::string& kind, uint64_t seed, int size_px) {
  if (size_px < 64 || size_px % kPeriodicPeriodPx != 0)
    throw sim::SceneError("texture size must be a multiple of 32 and at least 64");
  cv::RNG rng(seed * 0x9E3779B97F4A7C15ULL + 0x632BE59BD9B4E019ULL);
  if (kind == "photo") return Photo(rng, size_px);
  if (kind == "wood") return Grain(rng, size_px, 22, 0.25, 0.45, {20, 45, 90}, {90, 150, 210});
  if (kind == "plywood") return Plywood(rng, size_px);
  if (kind == "tile") return Tile(rng, size_px);
  if (kind == "fabric") return Fabric(rng, size_px);
  if (kind == "stripes") return Periodic(rng, size_px, false);
  if (kind == "checker") return Periodic(rng, size_px, true);
  if (kind == "uniform") {
    const int g = rng.uniform(120, 200);
    return Mat(size_px, size_px, CV_8UC3, cv::Scalar(g, g + 5, g + 10));
  }
  throw sim::SceneError("unknown texture kind '" + rig::ClipForMessage(kind) + "'");
}

std::optional<TextureName> ParseTextureName(const std::string& file_name) {
  static const std::regex kPattern(R"(^([a-z_]+)-s([0-9]{1,18})\.png$)");
  std::smatch m;
  if (!std::regex_match(file_name, m, kPattern)) return std::nullopt;
  return TextureName{m[1].str(), std::stoull(m[2].str())};
}

}  // namespace scenes
