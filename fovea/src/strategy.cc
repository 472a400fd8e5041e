#include "fovea/strategy.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <optional>

namespace fovea {
namespace {

// The paper's composite rule ("fovea") or its deterministic variant, in the
// current left view (or, with selection.view "reference", the reference
// view).
class CompositeStrategy : public FixationStrategy {
 public:
  CompositeStrategy(const SelectionOptions& s, const CriteriaOptions& c)
      : name_(s.Strategy()),
        view_(s.view == "reference" ? StrategyView::kReference : StrategyView::kCurrent),
        selector_(c.Make(), s) {}
  std::string Name() const override { return name_; }
  StrategyView View() const override { return view_; }
  SelectionSummary Choose(const SelectionContext& context, const PatchMap& map,
                          const std::vector<Eigen::Vector3d>& refused_W,
                          std::mt19937_64* rng) override {
    return selector_.Choose(context, map, refused_W, rng);
  }
  SelectionSummary ChooseAccepted(const SelectionContext& context, const PatchMap& map,
                                  std::vector<Eigen::Vector3d>* refused_W, std::mt19937_64* rng,
                                  const std::function<bool(const SelectionSummary&)>& accept,
                                  int max_passed, bool same_context) override {
    // The criteria and candidates once per context: a retry differs in its
    // refused points only.
    if (!same_context || !weights_) weights_ = selector_.Weigh(context);
    return ChooseUntil(
        [&](const std::vector<Eigen::Vector3d>& refused) {
          return selector_.Choose(context, *weights_, map, refused, rng);
        },
        refused_W, accept, max_passed);
  }

 private:
  std::string name_;
  StrategyView view_;
  FixationSelector selector_;
  std::optional<FixationSelector::Weights> weights_;  ///< of the last context
};

}  // namespace

SelectionSummary FixationStrategy::ChooseAccepted(
    const SelectionContext& context, const PatchMap& map, std::vector<Eigen::Vector3d>* refused_W,
    std::mt19937_64* rng, const std::function<bool(const SelectionSummary&)>& accept,
    int max_passed, bool /*same_context*/) {
  return ChooseUntil(
      [&](const std::vector<Eigen::Vector3d>& refused) {
        return Choose(context, map, refused, rng);
      },
      refused_W, accept, max_passed);
}

SelectionSummary FixationStrategy::ChooseUntil(
    const std::function<SelectionSummary(const std::vector<Eigen::Vector3d>&)>& choose,
    std::vector<Eigen::Vector3d>* refused_W,
    const std::function<bool(const SelectionSummary&)>& accept, int max_passed) {
  for (int i = 0;; ++i) {
    SelectionSummary s = choose(*refused_W);
    s.prescreened = i;
    if (!s.ok || i == max_passed || accept(s)) return s;
    refused_W->push_back(s.point_W);
  }
}

std::unique_ptr<FixationStrategy> MakeStrategy(const SelectionOptions& selection,
                                               const CriteriaOptions& criteria) {
  const std::string name = selection.Strategy();
  if (name == "random") return std::make_unique<RandomStrategy>(selection);
  if (name == "raster") return std::make_unique<RasterStrategy>(selection);
  if (name == "next_best_view") return std::make_unique<NextBestViewStrategy>(selection, criteria);
  return std::make_unique<CompositeStrategy>(selection, criteria);  // fovea, deterministic
}

SelectionSummary RandomStrategy::Choose(const SelectionContext& c, const PatchMap& map,
                                        const std::vector<Eigen::Vector3d>& refused_W,
                                        std::mt19937_64* rng) {
  SelectionSummary s;
  std::vector<cv::Point> candidates;
  cv::findNonZero(Candidates(c, refused_W, options_), candidates);
  s.candidates = static_cast<int>(candidates.size());
  if (candidates.empty()) {
    s.why = kNoCandidate;
    return s;
  }
  const size_t i = std::min(candidates.size() - 1,
                            static_cast<size_t>(UniformDraw(rng) * double(candidates.size())));
  AimAt(c, map, candidates[i].x, candidates[i].y, &s);
  return s;
}

std::vector<cv::Rect> RasterStrategy::Cells(cv::Size size, int pass) const {
  // Passes: the grid, then shifted half a cell right, down, and both.
  static constexpr double kShift[][2] = {{0, 0}, {0.5, 0}, {0, 0.5}, {0.5, 0.5}};
  if (pass < 0 || pass >= 4) return {};
  const int b = options_.border_px;
  const cv::Rect inner(b, b, size.width - 2 * b, size.height - 2 * b);
  if (inner.width <= 0 || inner.height <= 0) return {};
  const int nx =
      std::max(1, static_cast<int>(std::lround(double(inner.width) / options_.fovea_size_px)));
  const int ny =
      std::max(1, static_cast<int>(std::lround(double(inner.height) / options_.fovea_size_px)));
  const double w = double(inner.width) / nx, h = double(inner.height) / ny;
  const double sx = kShift[pass][0], sy = kShift[pass][1];
  const int cols = nx + (sx > 0), rows = ny + (sy > 0);
  std::vector<cv::Rect> cells;
  for (int j = 0; j < rows; ++j)
    for (int k = 0; k < cols; ++k) {
      const int i = j % 2 ? cols - 1 - k : k;  // serpentine
      const cv::Point tl(inner.x + static_cast<int>(std::lround((i - sx) * w)),
                         inner.y + static_cast<int>(std::lround((j - sy) * h)));
      const cv::Point br(inner.x + static_cast<int>(std::lround((i + 1 - sx) * w)),
                         inner.y + static_cast<int>(std::lround((j + 1 - sy) * h)));
      const cv::Rect cell = cv::Rect(tl, br) & inner;
      if (!cell.empty()) cells.push_back(cell);
    }
  return cells;
}

SelectionSummary RasterStrategy::Choose(const SelectionContext& c, const PatchMap& map,
                                        const std::vector<Eigen::Vector3d>& refused_W,
                                        std::mt19937_64* /*rng*/) {
  SelectionSummary s;
  const cv::Mat candidates = Candidates(c, refused_W, options_);
  s.candidates = cv::countNonZero(candidates);
  for (std::vector<cv::Rect> cells = Cells(candidates.size(), pass_); !cells.empty();
       cells = Cells(candidates.size(), ++pass_), next_ = 0) {
    while (next_ < cells.size()) {
      const cv::Rect cell = cells[next_++];
      const double cx = cell.x + 0.5 * (cell.width - 1), cy = cell.y + 0.5 * (cell.height - 1);
      int bx = -1, by = -1;
      double best = std::numeric_limits<double>::infinity();
      for (int y = cell.y; y < cell.y + cell.height; ++y)
        for (int x = cell.x; x < cell.x + cell.width; ++x)
          if (candidates.at<uchar>(y, x))
            if (const double d = std::hypot(x - cx, y - cy); d < best) best = d, bx = x, by = y;
      if (bx < 0) continue;  // nothing to fixate in this cell
      SelectionSummary aimed = s;
      AimAt(c, map, bx, by, &aimed);
      if (aimed.ok) return aimed;
    }
  }
  s.why = "raster: every cell of every pass has been offered";
  return s;
}

cv::Mat NextBestViewStrategy::Gain(const SelectionContext& c, const PatchMap& map) const {
  cv::Mat gain(c.map_id.size(), CV_32F);
  const double h2 = options_.half_known_rel_sigma * options_.half_known_rel_sigma;
  for (int y = 0; y < gain.rows; ++y)
    for (int x = 0; x < gain.cols; ++x) {
      const int id = c.map_id.at<int>(y, x);
      float& g = gain.at<float>(y, x);
      if (id < 0) {
        g = 1;
        continue;
      }
      const Patch& p = map[id];
      const double z = c.map_depth_m.at<float>(y, x);
      if (p.sigma_z_m > 0 && z > 0) {
        const double s = p.sigma_z_m / z;
        g = static_cast<float>(s * s / (s * s + h2));
      } else {
        g = p.level == PatchLevel::kIdr ? 1.f : p.level == PatchLevel::kPeripheral ? 0.5f : 0.f;
      }
    }
  return gain;
}

SelectionSummary NextBestViewStrategy::Choose(const SelectionContext& c, const PatchMap& map,
                                              const std::vector<Eigen::Vector3d>& refused_W,
                                              std::mt19937_64* /*rng*/) {
  SelectionSummary s;
  cv::Mat candidates = Candidates(c, refused_W, options_);
  std::vector<Eigen::Vector3d> visited;
  for (const SelectionContext::Visit& v : c.visits) {
    visited.push_back(v.settled_W);
    visited.push_back(v.aimed_W);
  }
  ClearNear(c, visited, criteria_.revisit_radius_m, &candidates);
  s.candidates = cv::countNonZero(candidates);
  if (s.candidates == 0) {
    s.why = kNoCandidate;
    return s;
  }
  // The window's mean gain; outside the image counts as nothing to gain.
  cv::Mat information;
  const int k = options_.fovea_size_px;
  cv::Mat gain = Gain(c, map);
  std::vector<Eigen::Vector3d> suppressing = visited;
  suppressing.insert(suppressing.end(), refused_W.begin(), refused_W.end());
  CapNear(c, suppressing, criteria_.suppression_radius_m,
          static_cast<float>(criteria_.suppressed_weight), &gain);
  cv::boxFilter(gain, information, CV_32F, cv::Size(k, k), cv::Point(-1, -1), true,
                cv::BORDER_CONSTANT);
  const Eigen::Vector3d eye = c.eye_W.translation(), axis = c.eye_W.linear().col(2);
  const double cx = c.view.intrinsics.cx_px, cy = c.view.intrinsics.cy_px;
  int bx = -1, by = -1;
  double best = -std::numeric_limits<double>::infinity(), best_dist = 0, best_turn = 0;
  double sum_info = 0, sum_turn = 0;
  for (int y = 0; y < candidates.rows; ++y)
    for (int x = 0; x < candidates.cols; ++x) {
      if (!candidates.at<uchar>(y, x)) continue;
      const double info = information.at<float>(y, x);
      const double turn =
          std::acos(std::clamp((c.MapPoint(x, y) - eye).normalized().dot(axis), -1.0, 1.0));
      sum_info += info;
      sum_turn += turn;
      const double score = info - options_.motion_weight * turn;
      const double dist = std::hypot(x - cx, y - cy);
      if (score > best || (score == best && dist < best_dist))
        best = score, best_dist = dist, best_turn = turn, bx = x, by = y;
    }
  s.composite_max = s.composite_chosen = best;
  AimAt(c, map, bx, by, &s);
  const double n = s.candidates;
  s.criteria = {
      {"information", sum_info > 0 ? information.at<float>(by, bx) / (sum_info / n) : 0.0},
      {"turn", sum_turn > 0 ? best_turn / (sum_turn / n) : 0.0}};
  return s;
}

}  // namespace fovea
