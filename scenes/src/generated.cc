#include "scenes/generated.h"

#include <cmath>
#include <opencv2/core.hpp>
#include <regex>
#include <sstream>

#include "scenes/textures.h"
#include "sim/config.h"

namespace scenes {

std::optional<std::string> MakeMesh(const std::string& file_name) {
  static const std::regex kCylinder(R"(^cylinder-r([0-9]{1,4})-h([0-9]{1,5})\.obj$)");
  std::smatch m;
  if (!std::regex_match(file_name, m, kCylinder)) return std::nullopt;
  const double r = std::stod(m[1].str()) / 1000, h = std::stod(m[2].str()) / 1000;
  if (r <= 0 || h <= 0) return std::nullopt;
  const int n = 720;
  std::ostringstream obj;
  obj.precision(9);
  obj << "# open cylinder r=" << r << " m h=" << h << " m\n";
  for (int i = 0; i <= n; ++i) {
    const double a = 2 * M_PI * i / n;
    for (double z : {-h / 2, h / 2})
      obj << "v " << r * std::cos(a) << " " << r * std::sin(a) << " " << z << "\n";
  }
  for (int i = 0; i <= n; ++i) {
    const double u = kTexTilesPerMetre * r * 2 * M_PI * i / n;
    obj << "vt " << u << " 0\nvt " << u << " " << kTexTilesPerMetre * h << "\n";
  }
  // Outward-facing triangles (counter-clockwise seen from outside).
  for (int i = 0; i < n; ++i) {
    const int a = 2 * i + 1, b = a + 1, c = a + 2, d = a + 3;
    obj << "f " << a << "/" << a << " " << c << "/" << c << " " << d << "/" << d << "\n";
    obj << "f " << a << "/" << a << " " << d << "/" << d << " " << b << "/" << b << "\n";
  }
  return obj.str();
}

std::optional<RandomSceneSpec> ParseRandomSceneName(const std::string& name) {
  if (name.rfind("random", 0) != 0) return std::nullopt;
  static const std::regex kName(R"(^random(?::([0-9]{1,18})(?::([0-9]{1,2}))?)?$)");
  std::smatch m;
  if (name.size() > 40 || !std::regex_match(name, m, kName))
    throw sim::SceneError("malformed random scene name '" + rig::ClipForMessage(name) +
                          "' (use random, random:SEED or random:SEED:N)");
  RandomSceneSpec spec;
  if (m[1].matched) spec.seed = std::stoull(m[1].str());
  if (m[2].matched) spec.objects = std::stoi(m[2].str());
  if (spec.objects < 1 || spec.objects > 30)
    throw sim::SceneError("random scene: N must be 1 to 30, got " + std::to_string(spec.objects));
  return spec;
}

std::string RandomSceneXml(const RandomSceneSpec& spec) {
  cv::RNG rng(spec.seed * 0xD1B54A32D192ED03ULL + 17);
  const std::vector<std::string> kinds = {"wood", "tile", "fabric", "plywood", "photo"};
  std::ostringstream assets, bodies;
  assets.precision(6);
  bodies.precision(6);
  auto material = [&](int i) {
    const std::string kind = kinds[rng.uniform(0, int(kinds.size()))];
    const int seed = rng.uniform(1, 100000);
    assets << "    <texture name=\"t" << i << "\" type=\"2d\" file=\"" << kind << "-s" << seed
           << ".png\"/>\n    <material name=\"m" << i << "\" texture=\"t" << i
           << "\" texrepeat=\"4 4\" texuniform=\"true\" specular=\"0\" shininess=\"0\"/>\n";
    return "m" + std::to_string(i);
  };
  const std::string wall = material(0);
  bodies << "    <geom name=\"back_wall\" type=\"box\" size=\"1.2 0.8 0.005\" pos=\"0 1.505 0\" "
            "zaxis=\"0 -1 0\" material=\""
         << wall << "\"/>\n";
  for (int i = 1; i <= spec.objects; ++i) {
    const std::string mat = material(i);
    const double y = rng.uniform(0.5, 1.3);
    const double x = rng.uniform(-0.3, 0.3) * y, z = rng.uniform(-0.2, 0.2) * y;
    const int type = rng.uniform(0, 3);
    bodies << "    <geom name=\"object_" << i << "\" ";
    if (type == 0) {  // box, turned about the vertical
      const double yaw = rng.uniform(-M_PI / 4, M_PI / 4);
      bodies << "type=\"box\" size=\"" << rng.uniform(0.03, 0.1) * y << " "
             << rng.uniform(0.03, 0.1) * y << " " << rng.uniform(0.03, 0.1) * y << "\" pos=\"" << x
             << " " << y << " " << z << "\" xyaxes=\"" << std::cos(yaw) << " " << std::sin(yaw)
             << " 0 " << -std::sin(yaw) << " " << std::cos(yaw) << " 0\"";
    } else if (type == 1) {  // vertical cylinder
      const int r_mm = int(rng.uniform(30, 81) * y), h_mm = rng.uniform(200, 601);
      assets << "    <mesh name=\"mesh" << i << "\" file=\"cylinder-r" << r_mm << "-h" << h_mm
             << ".obj\"/>\n";
      bodies << "type=\"mesh\" mesh=\"mesh" << i << "\" pos=\"" << x << " " << y << " " << z
             << "\"";
    } else {  // slanted plane: yaw up to 60 degrees, pitch up to 30
      const double yaw = rng.uniform(-M_PI / 3, M_PI / 3), pitch = rng.uniform(-M_PI / 6, M_PI / 6);
      const cv::Vec3d ax(std::cos(yaw), std::sin(yaw), 0);
      const cv::Vec3d ay(-std::sin(yaw) * std::sin(pitch), std::cos(yaw) * std::sin(pitch),
                         std::cos(pitch));
      bodies << "type=\"box\" size=\"" << rng.uniform(0.04, 0.15) * y << " "
             << rng.uniform(0.04, 0.15) * y << " 0.005\" pos=\"" << x << " " << y << " " << z
             << "\" xyaxes=\"" << ax[0] << " " << ax[1] << " " << ax[2] << " " << ay[0] << " "
             << ay[1] << " " << ay[2] << "\"";
    }
    bodies << " material=\"" << mat << "\"/>\n";
  }
  std::ostringstream xml;
  xml << "<!-- random scene, seed " << spec.seed << ", " << spec.objects << " objects -->\n"
      << "<mujoco model=\"random\">\n  <include file=\"tavt.xml\"/>\n  <asset>\n"
      << assets.str() << "  </asset>\n  <worldbody>\n"
      << "    <light name=\"key\" directional=\"true\" pos=\"0 0 3\" dir=\"0.3 0.8 -0.6\" "
         "diffuse=\"0.8 0.8 0.8\" specular=\"0 0 0\" castshadow=\"false\"/>\n"
      << bodies.str() << "  </worldbody>\n</mujoco>\n";
  return xml.str();
}

}  // namespace scenes
