// Where to look next: the fixation strategies behind one interface
// (selection.strategy). The paper's composite rule and its deterministic
// variant choose in the current left view, whose criteria look at what the
// cameras see now; the baselines and the next-best-view planner choose in
// the reference view (IDR's final left view: the region the run maps), a
// fixed frame in which "every cell" and "the unmapped part" mean the same
// thing from one fixation to the next.
#pragma once

#include <functional>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "fovea/selection.h"

namespace fovea {

/// The view a strategy chooses in.
enum class StrategyView { kCurrent, kReference };

class FixationStrategy {
 public:
  virtual ~FixationStrategy() = default;
  virtual std::string Name() const = 0;
  virtual StrategyView View() const = 0;
  /// The next target among the candidates of `context` (Candidates: the
  /// same border, region and refused points for every strategy). All
  /// randomness comes from `rng`. Strategies may keep state between calls
  /// (raster's place in its scan).
  virtual SelectionSummary Choose(const SelectionContext& context, const PatchMap& map,
                                  const std::vector<Eigen::Vector3d>& refused_W,
                                  std::mt19937_64* rng) = 0;
  /// Chooses in `context` until `accept` takes the choice, adding each
  /// choice it passes over to `refused_W` (its neighbourhood goes with it),
  /// at most `max_passed` times; a choice that is not ok ends the search.
  /// The choice returned has `prescreened` set to the number passed over.
  /// A strategy may keep what it computed from the context alone between
  /// the tries (the default calls Choose each time), and into the next call
  /// when `same_context` says that its context is this call's, unchanged
  /// (the loop's attempt was refused: the view and the map stay).
  virtual SelectionSummary ChooseAccepted(
      const SelectionContext& context, const PatchMap& map, std::vector<Eigen::Vector3d>* refused_W,
      std::mt19937_64* rng, const std::function<bool(const SelectionSummary&)>& accept,
      int max_passed, bool same_context);

 protected:
  /// ChooseAccepted's loop around `choose` (a choice given the refused points).
  static SelectionSummary ChooseUntil(
      const std::function<SelectionSummary(const std::vector<Eigen::Vector3d>&)>& choose,
      std::vector<Eigen::Vector3d>* refused_W,
      const std::function<bool(const SelectionSummary&)>& accept, int max_passed);
};

/// The strategy `selection.Strategy()` names, with its settings. `options`
/// must have passed Check().
std::unique_ptr<FixationStrategy> MakeStrategy(const SelectionOptions& selection,
                                               const CriteriaOptions& criteria);

/// "random": a candidate drawn uniformly (53 random bits per draw).
class RandomStrategy : public FixationStrategy {
 public:
  explicit RandomStrategy(const SelectionOptions& o) : options_(o) {}
  std::string Name() const override { return "random"; }
  StrategyView View() const override { return StrategyView::kReference; }
  SelectionSummary Choose(const SelectionContext& context, const PatchMap& map,
                          const std::vector<Eigen::Vector3d>& refused_W,
                          std::mt19937_64* rng) override;

 private:
  SelectionOptions options_;
};

/// "raster": the view inside its border cut into cells of about
/// fovea_size_px, visited row by row, alternating direction (a serpentine,
/// which keeps each move short); in each cell the candidate nearest its
/// centre. A cell without a candidate is passed over. Each cell is offered
/// once per pass; further passes shift the grid by half a cell (right,
/// down, then both), so that a long run keeps finding new targets. Fails
/// when every pass is spent.
class RasterStrategy : public FixationStrategy {
 public:
  explicit RasterStrategy(const SelectionOptions& o) : options_(o) {}
  std::string Name() const override { return "raster"; }
  StrategyView View() const override { return StrategyView::kReference; }
  SelectionSummary Choose(const SelectionContext& context, const PatchMap& map,
                          const std::vector<Eigen::Vector3d>& refused_W,
                          std::mt19937_64* rng) override;
  /// The cells of pass `pass` over a view of `size`, in visiting order
  /// (empty past the last pass).
  std::vector<cv::Rect> Cells(cv::Size size, int pass) const;

 private:
  SelectionOptions options_;
  int pass_ = 0;
  size_t next_ = 0;  ///< the next cell of the pass
};

/// "next_best_view": the candidate p maximizing
///   I(p) - motion_weight * angle(p),
/// I(p) the mean over a fovea_size_px window about p of each pixel's gain
/// (1 where the map is silent; where it is mapped, s^2 / (s^2 + h^2), s its
/// patch's depth sigma over its depth and h = half_known_rel_sigma; by level
/// when the sigma is unknown: IDR 1, peripheral 0.5, foveal 0), and angle(p)
/// the turn of the current left camera's axis to p's map point. Local
/// suppression as the paper's rule has it: within
/// criteria.suppression_radius_m of an earlier fixation (where the servo
/// settled, and the point aimed at) or of a refused point the gain is at
/// most criteria.suppressed_weight (what a fovea there could yield was had,
/// or could not be: a strip no right camera sees stays unmapped), and
/// candidates within criteria.revisit_radius_m of an earlier fixation are
/// left out. Ties go to the pixel nearest the centre. O(pixels + points x
/// their neighbourhoods) per choice (a box filter).
class NextBestViewStrategy : public FixationStrategy {
 public:
  NextBestViewStrategy(const SelectionOptions& o, const CriteriaOptions& c)
      : options_(o), criteria_(c) {}
  std::string Name() const override { return "next_best_view"; }
  StrategyView View() const override { return StrategyView::kReference; }
  SelectionSummary Choose(const SelectionContext& context, const PatchMap& map,
                          const std::vector<Eigen::Vector3d>& refused_W,
                          std::mt19937_64* rng) override;
  /// Each pixel's gain (CV_32F, in [0, 1]), as above, before suppression.
  cv::Mat Gain(const SelectionContext& context, const PatchMap& map) const;

 private:
  SelectionOptions options_;
  CriteriaOptions criteria_;
};

}  // namespace fovea
