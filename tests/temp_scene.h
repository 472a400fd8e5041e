// Test helper: a user scene written to a fresh temporary folder, removed when
// the object goes out of scope.
#pragma once

#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <string>

class TempScene {
 public:
  /// `body` goes inside <worldbody>; `assets` inside <asset>; `extra` after
  /// </worldbody> (actuators, equality constraints).
  TempScene(const std::string& body, const std::string& assets = "",
            const std::string& extra = "") {
    static std::atomic<int> counter{0};
    dir_ = std::filesystem::temp_directory_path() /
           ("fovea_test_scene_" + std::to_string(getpid()) + "_" + std::to_string(counter++));
    std::filesystem::create_directories(dir_);
    path_ = (dir_ / "scene.xml").string();
    std::ofstream(path_) << "<mujoco>\n  <include file=\"tavt.xml\"/>\n  <asset>" << assets
                         << "</asset>\n  <worldbody>\n"
                         << "    <light directional=\"true\" pos=\"0 0 3\" dir=\"0.3 0.8 -0.6\" "
                            "diffuse=\"0.8 0.8 0.8\" specular=\"0 0 0\"/>\n"
                         << body << "\n  </worldbody>\n"
                         << extra << "</mujoco>\n";
  }
  ~TempScene() { std::filesystem::remove_all(dir_); }
  const std::string& path() const { return path_; }

  /// A photo-textured fronto-parallel plane whose front face is at world y.
  static std::string PlaneAt(double y) {
    return "<geom name=\"plane\" type=\"box\" size=\"0.8 0.6 0.005\" pos=\"0 " +
           std::to_string(y + 0.005) + " 0\" zaxis=\"0 -1 0\" material=\"photo\"/>";
  }
  static std::string PhotoAsset() {
    return "<texture name=\"photo\" type=\"2d\" file=\"photo-s1.png\"/><material name=\"photo\" "
           "texture=\"photo\" texrepeat=\"4 4\" texuniform=\"true\" specular=\"0\"/>";
  }

 private:
  std::filesystem::path dir_;
  std::string path_;
};
