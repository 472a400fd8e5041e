// A run folder (`fovea run --out DIR`): its files, its records and summary,
// and which of their keys are wall-clock times.
#pragma once

#include <Eigen/Core>
#include <array>
#include <future>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "experiments/config/config.h"
#include "experiments/scoring/run_eval.h"
#include "fovea/ddr.h"

namespace experiments::run_folder {

inline constexpr char kConfig[] = "config.yaml";       ///< the effective configuration
inline constexpr char kSummary[] = "summary.json";     ///< the run's figures
inline constexpr char kRecords[] = "fixations.jsonl";  ///< a record per attempt
inline constexpr char kMapPly[] = "map.ply";           ///< the patch map as quads
inline constexpr char kMapPicture[] = "map.png";       ///< static baseline: its map
inline constexpr char kFixationPath[] = "fixation_path.png";
inline constexpr char kReference[] = "reference.png";  ///< the reference view
/// The final map's error in the reference view (ErrorPicture).
inline constexpr char kErrorPicture[] = "error.png";
inline constexpr char kReport[] = "report.html";

/// The fixations after which the map is pictured, as in the paper's
/// figures (and the run's last one).
inline constexpr std::array<int, 4> kSnapshotFixations = {1, 5, 15, 25};

/// "map_after_05.png": the picture of the map after fixation `fixation`.
std::string SnapshotName(int fixation);

/// Whether a key of summary.json or of a record (or a flattened CSV column
/// "time_s.select") is a wall-clock time: wall_time_s, compute_time_s and
/// time_s. They are the only figures that differ between two runs of one
/// configuration.
bool IsWallClockKey(const std::string& key);

/// Stage travel: {"pan_deg", "tilt_deg", "carriage_m"}, both cameras summed.
nlohmann::json TravelJson(double pan_rad, double tilt_rad, double carriage_m);

/// One attempt's record (a line of fixations.jsonl).
nlohmann::json RecordJson(const fovea::FixationRecord& record, const MapScore& score);

/// The fovea's size over a run's fixations (summary.json "fovea"): level
/// 0's width and height (min, median, max), its share of the image (min,
/// median, mean, max), how many foveas were narrower or shorter than 32 px
/// and how many were matched in the fixation frame. Sizes are null without a
/// fixation.
nlohmann::json FoveaSizesJson(const std::vector<fovea::FixationRecord>& records);

/// What every summary.json holds, FOVEA's and the static baseline's: the
/// score, the scene, seed and method, the patches by level and the times.
nlohmann::json SummaryJson(const MapScore& score, const std::string& scene_path,
                           const RunConfig& config, const std::array<int, 3>& patches_by_level,
                           double motion_time_s, double compute_time_s, double wall_time_s);

/// The fixation observer of a run: scores the map after every attempt,
/// keeps the records, the fixation path, and the map's pictures after the
/// snapshot fixations, and prints a progress line.
///
/// An attempt's map is scored on a second thread, from a copy of the map,
/// while the run goes on to the next attempt (servoing, which renders and
/// steps the simulation, is most of a fixation's wall time); the record is
/// completed, in order, when the next attempt arrives or at Finish. Only the
/// scoring runs there: it reads the reference view and the model's names,
/// never the simulation's state, so the records are the same as scored in
/// line. The true surface a fixation landed on (ray casts into the
/// simulation) is found at once.
class Recorder {
 public:
  Recorder(const std::string& dir, const std::string& scene_path, const ReferenceView& ref,
           const sim::GroundTruth& truth, const RunConfig& config);
  /// Waits for an attempt still being scored (its result is dropped).
  ~Recorder();
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;
  void operator()(const fovea::FixationRecord& record, const fovea::PatchMap& map);
  /// Completes the last attempt's record; call it before reading the
  /// records, the path or the refused points.
  void Finish();
  const std::string& records() const { return jsonl_; }
  const std::vector<Eigen::Vector3d>& path() const { return path_; }
  const std::vector<Eigen::Vector3d>& refused() const { return refused_; }
  /// Wall clock the run waited for scoring (scoring that overlapped the
  /// next attempt is not counted) and spent writing.
  double scoring_s = 0, output_s = 0;
  /// The true surface nearest a point ({"name", "distance_m"}, nulls when
  /// nothing is near): which surface a fixation landed on, and how far off
  /// it (a false fixation floats).
  nlohmann::json SurfaceAt(const Eigen::Vector3d& p_W) const;

 private:
  /// An attempt whose map is being scored.
  struct Pending {
    fovea::FixationRecord record;
    nlohmann::json surface;
    std::shared_ptr<const fovea::PatchMap> map;
    std::future<MapScore> score;
  };
  void Complete(Pending* pending);

  std::string dir_, scene_name_;
  const ReferenceView& ref_;
  const sim::GroundTruth& truth_;
  double baseline_m_;
  int flank_px_;  ///< IntegrationOptions::reference_flank_px
  int fixations_;
  std::vector<int> snapshots_;
  Eigen::Vector3d view_target_ = Eigen::Vector3d::Zero();
  std::string jsonl_;
  std::vector<Eigen::Vector3d> path_, refused_;
  std::optional<Pending> pending_;
};

}  // namespace experiments::run_folder
