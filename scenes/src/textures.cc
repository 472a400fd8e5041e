#include "scenes/textures.h"

#include <opencv2/imgproc.hpp>
#include <regex>

#include "sim/config.h"

namespace scenes {
namespace {

// Fractal (1/f-like) noise: octaves of uniform noise, each upsampled smoothly
// and weighted by its scale, normalized to [0, 1]. Detail at every scale, so
// it stays matchable at any viewing distance (a photograph's statistics).
cv::Mat FractalNoise(cv::RNG& rng, int size, int octaves, double persistence) {
  cv::Mat sum(size, size, CV_32F, cv::Scalar(0));
  double weight = 1.0;
  for (int o = 0; o < octaves; ++o) {
    const int cells = std::max(2, size >> (octaves - 1 - o));
    cv::Mat noise(cells, cells, CV_32F);
    rng.fill(noise, cv::RNG::UNIFORM, 0.0, 1.0);
    cv::Mat up;
    cv::resize(noise, up, cv::Size(size, size), 0, 0, cells < size ? cv::INTER_CUBIC : cv::INTER_NEAREST);
    sum += weight * up;
    weight *= persistence;
  }
  cv::normalize(sum, sum, 0, 1, cv::NORM_MINMAX);
  return sum;
}

cv::Mat ToBgr(const cv::Mat& gray01, cv::Scalar dark, cv::Scalar light) {
  cv::Mat bgr(gray01.size(), CV_8UC3);
  for (int r = 0; r < gray01.rows; ++r)
    for (int c = 0; c < gray01.cols; ++c) {
      const float t = std::clamp(gray01.at<float>(r, c), 0.0f, 1.0f);
      for (int ch = 0; ch < 3; ++ch)
        bgr.at<cv::Vec3b>(r, c)[ch] = cv::saturate_cast<uchar>(dark[ch] + t * (light[ch] - dark[ch]));
    }
  return bgr;
}

}  // namespace

std::vector<std::string> TextureKinds() { return {"photo", "uniform"}; }

cv::Mat MakeTexture(const std::string& kind, uint64_t seed, int size_px) {
  cv::RNG rng(seed * 0x9E3779B97F4A7C15ULL + 0x632BE59BD9B4E019ULL);
  if (kind == "photo") {
    cv::Mat n = FractalNoise(rng, size_px, 9, 0.85);
    cv::Mat color = FractalNoise(rng, size_px, 4, 0.6);
    cv::Mat bgr = ToBgr(n, cv::Scalar(20, 30, 40), cv::Scalar(235, 225, 215));
    // A gentle hue variation over large scales.
    for (int r = 0; r < size_px; ++r)
      for (int c = 0; c < size_px; ++c) {
        const float t = color.at<float>(r, c);
        cv::Vec3b& px = bgr.at<cv::Vec3b>(r, c);
        px[0] = cv::saturate_cast<uchar>(px[0] * (0.8f + 0.4f * t));
        px[2] = cv::saturate_cast<uchar>(px[2] * (1.2f - 0.4f * t));
      }
    return bgr;
  }
  if (kind == "uniform") return cv::Mat(size_px, size_px, CV_8UC3, cv::Scalar(150, 160, 170));
  throw sim::SceneError("unknown texture kind '" + kind + "'");
}

std::optional<TextureName> ParseTextureName(const std::string& file_name) {
  static const std::regex kPattern(R"(^([a-z_]+)-s([0-9]{1,18})\.png$)");
  std::smatch m;
  if (!std::regex_match(file_name, m, kPattern)) return std::nullopt;
  return TextureName{m[1].str(), std::stoull(m[2].str())};
}

}  // namespace scenes
