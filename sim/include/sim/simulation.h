// A scene loaded with the simulated TAVT in it: the rig (behind rig::Rig) and
// the ground truth, sharing one MuJoCo model.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "rig/rig.h"
#include "sim/config.h"
#include "sim/ground_truth.h"

namespace sim {

/// Supplies the bytes of an asset file a scene names (for instance a
/// procedural texture) by its file name without directory; returns nullopt
/// for names it does not know, which MuJoCo then reads from disk.
using AssetProvider = std::function<std::optional<std::vector<uint8_t>>(const std::string& name)>;

/// Name under which scenes include the rig model: <include file="tavt.xml"/>.
inline constexpr const char* kRigIncludeName = "tavt.xml";

/// MJCF text of the TAVT for a configuration (what a scene's include reads).
std::string RigMjcf(const SimRigConfig& config);

/// The head the simulated rig really has (its imperfections included), as
/// rig::HeadGeometry (rail zero at the world origin).
rig::HeadGeometry TrueHead(const SimRigConfig& config, rig::Side side);
/// The camera the simulated rig really has: the ideal intrinsics of the
/// configuration's size and field, with the lenses' true distortion.
rig::CameraIntrinsics TrueIntrinsics(const SimRigConfig& config);
/// The size the rig's cameras render at: the images' size for an
/// undistorted lens; for a distorted one, an undistorted image of the same
/// focal length and centred principal point wide and high enough that every
/// pixel of the distorted image lies inside it.
cv::Size RenderSize(const SimRigConfig& config);

/// The box, in the world, that scene geometry must keep out of: the rig's
/// rail, carriages and heads over their whole travel (scene rule 3, see
/// scenes/README.md).
struct Box3 {
  Eigen::Vector3d min_W, max_W;
};
Box3 RigWorkspace(const SimRigConfig& config);

class SimRig;

class Simulation {
 public:
  /// Loads an MJCF scene file that includes the rig model. Throws SceneError
  /// (one line naming the file and the problem) if the file cannot be read or
  /// parsed, or lacks the rig; throws SceneError if `config` is invalid.
  static std::unique_ptr<Simulation> Load(const std::string& scene_path, const SimRigConfig& config,
                                          const AssetProvider& assets = {});

  /// Same, for a scene given as MJCF text (a generated scene); `name` stands
  /// for its path in messages. Relative asset paths resolve from the working
  /// folder.
  static std::unique_ptr<Simulation> LoadText(const std::string& name, const std::string& xml,
                                              const SimRigConfig& config,
                                              const AssetProvider& assets = {});
  /// Compiles MJCF text with the rig and applies the checks a load applies
  /// (finite numbers, the rig included, the scene rules) without creating a
  /// renderer: cheap enough to check many scenes. Throws SceneError.
  static void CheckScene(const std::string& name, const std::string& xml,
                         const SimRigConfig& config, const AssetProvider& assets = {});

  ~Simulation();
  Simulation(const Simulation&) = delete;
  Simulation& operator=(const Simulation&) = delete;

  rig::Rig& rig();
  /// The same rig, with what only a simulated rig can say (SimRig::True).
  SimRig& sim_rig();
  const GroundTruth& truth() const;
  const SimRigConfig& config() const;
  const std::string& scene_path() const;

 private:
  Simulation();
  static std::unique_ptr<Simulation> LoadImpl(const std::string& name, const std::string& xml,
                                              bool from_memory, const SimRigConfig& config,
                                              const AssetProvider& assets);
  std::unique_ptr<World> world_;
  std::unique_ptr<SimRig> rig_;
  std::unique_ptr<GroundTruth> truth_;
  SimRigConfig config_;
};

}  // namespace sim
