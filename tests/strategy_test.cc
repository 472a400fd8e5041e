// The fixation strategies on synthetic maps with known answers: the
// next-best-view planner's choice of region, raster's scan, random's
// uniformity, and the names and settings that select them.
#include "fovea/strategy.h"

#include <catch2/catch.hpp>
#include <opencv2/imgproc.hpp>

#include "rig/input_file.h"
#include "test_views.h"

namespace {

constexpr int kWidth = 160, kHeight = 120;
constexpr double kFocal = 150, kDepth = 1.0;

rig::CameraView View() { return ForwardView(kWidth, kHeight, kFocal); }

// A fronto-parallel plane at kDepth seen by View(), as foveal patches of
// kCell px squares of depth sigma `sigma_m`, leaving out every cell that
// meets one of `holes` (image rectangles).
fovea::PatchMap PlaneWithHoles(const std::vector<cv::Rect>& holes, double sigma_m = 0) {
  constexpr int kCell = 4;
  const rig::CameraView v = View();
  auto world = [&](double u, double w) {  // image point -> plane point (X right, Z up)
    return Eigen::Vector3d((u - 0.5 - v.intrinsics.cx_px) / kFocal * kDepth, kDepth,
                           -(w - 0.5 - v.intrinsics.cy_px) / kFocal * kDepth);
  };
  fovea::PatchMap map;
  for (int y = 0; y < kHeight; y += kCell)
    for (int x = 0; x < kWidth; x += kCell) {
      const cv::Rect cell(x, y, kCell, kCell);
      if (std::any_of(holes.begin(), holes.end(),
                      [&](const cv::Rect& h) { return !(h & cell).empty(); }))
        continue;
      fovea::Patch p;
      p.corners_W = {world(x, y), world(x + kCell, y), world(x + kCell, y + kCell),
                     world(x, y + kCell)};
      p.level = fovea::PatchLevel::kFoveal;
      p.sigma_z_m = sigma_m;
      map.Add(p);
    }
  map.BuildIndex();
  return map;
}

fovea::SelectionContext Context(const fovea::PatchMap& map, bool fill_holes = true) {
  return fovea::SelectionContext::Make(cv::Mat(kHeight, kWidth, CV_8U, cv::Scalar(128)), View(),
                                       map, fill_holes);
}

fovea::SelectionOptions Options() {
  fovea::SelectionOptions o;
  o.border_px = 4;
  o.fovea_size_px = 32;
  return o;
}

// The view's pose turned about the world's vertical: > 0 looks left.
Eigen::Isometry3d Turned(double pan_rad) {
  Eigen::Isometry3d eye = View().world_T_camera;
  eye.linear() =
      Eigen::AngleAxisd(pan_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix() * eye.linear();
  return eye;
}

bool Inside(const cv::Rect& r, const Eigen::Vector2d& px) {
  return r.contains(cv::Point(static_cast<int>(px.x()), static_cast<int>(px.y())));
}

}  // namespace

TEST_CASE("next_best_view picks the largest reachable unmapped region", "[fovea][strategy]") {
  const cv::Rect large(20, 40, 30, 30), small(110, 50, 16, 16), largest(60, 70, 40, 40);
  const fovea::PatchMap map = PlaneWithHoles({large, small});
  fovea::NextBestViewStrategy nbv(Options(), fovea::CriteriaOptions{});
  std::mt19937_64 rng(0);
  const fovea::SelectionContext c = Context(map);
  const fovea::SelectionSummary s = nbv.Choose(c, map, {}, &rng);
  REQUIRE(s.ok);
  CHECK(s.in_hole);
  CHECK(Inside(large, s.pixel));
  CHECK(s.point_W.y() == Approx(kDepth).margin(1e-6));  // the hole's filled depth
  // A mapped pixel's gain follows its uncertainty: certain foveal data
  // offers nothing, a sigma of the half-known share of depth offers half.
  const cv::Mat gain = nbv.Gain(c, map);
  CHECK(gain.at<float>(5, 5) == 0.0f);
  CHECK(gain.at<float>(55, 35) == 1.0f);
  const fovea::PatchMap uncertain =
      PlaneWithHoles({large, small}, Options().half_known_rel_sigma * kDepth);
  CHECK(nbv.Gain(Context(uncertain), uncertain).at<float>(5, 5) == Approx(0.5).epsilon(1e-4));

  // A still larger hole that a refused point makes unreachable is passed over.
  const fovea::PatchMap three = PlaneWithHoles({large, small, largest});
  const fovea::SelectionContext c3 = Context(three);
  CHECK(Inside(largest, nbv.Choose(c3, three, {}, &rng).pixel));
  const Eigen::Vector3d refused = c3.MapPoint(80, 90);
  fovea::SelectionOptions wide = Options();
  wide.refused_radius_m = 0.3;  // 45 px at 1 m: the whole of `largest`
  fovea::NextBestViewStrategy nbv_wide(wide, fovea::CriteriaOptions{});
  CHECK(Inside(large, nbv_wide.Choose(c3, three, {refused}, &rng).pixel));
  // So is one the rig has fixated already (the fovea there yielded
  // nothing): its neighbourhood's gain is suppressed, its centre left out.
  fovea::SelectionContext visited = c3;
  visited.visits.push_back({refused, refused});
  fovea::CriteriaOptions far_visits;
  far_visits.suppression_radius_m = 0.3;
  fovea::NextBestViewStrategy nbv_visited(Options(), far_visits);
  CHECK(Inside(large, nbv_visited.Choose(visited, three, {}, &rng).pixel));
  // And a refused point suppresses the same way, beyond its own small radius.
  CHECK(Inside(large, nbv_visited.Choose(c3, three, {refused}, &rng).pixel));
  fovea::SelectionContext revisit = c3;
  revisit.visits.push_back({refused, refused});
  fovea::NextBestViewStrategy nbv_near(Options(), fovea::CriteriaOptions{});
  const Eigen::Vector2d near = nbv_near.Choose(revisit, three, {}, &rng).pixel;
  CHECK((revisit.MapPoint(int(near.x()), int(near.y())) - refused).norm() >=
        fovea::CriteriaOptions{}.revisit_radius_m);
}

TEST_CASE("next_best_view prefers the nearer of two equal regions", "[fovea][strategy]") {
  // Mirror images about the image centre: only the motion cost tells them apart.
  const cv::Rect left(20, 48, 24, 24), right(kWidth - 44, 48, 24, 24);
  const fovea::PatchMap map = PlaneWithHoles({left, right});
  fovea::NextBestViewStrategy nbv(Options(), fovea::CriteriaOptions{});
  std::mt19937_64 rng(0);
  fovea::SelectionContext c = Context(map);
  c.eye_W = Turned(-0.2);  // looking right of centre
  CHECK(Inside(right, nbv.Choose(c, map, {}, &rng).pixel));
  c.eye_W = Turned(0.2);
  CHECK(Inside(left, nbv.Choose(c, map, {}, &rng).pixel));
  // Without a motion cost the two are equal: the tie goes to the pixel
  // nearest the centre, whichever way the eye looks.
  fovea::SelectionOptions free = Options();
  free.motion_weight = 0;
  fovea::NextBestViewStrategy nbv_free(free, fovea::CriteriaOptions{});
  const Eigen::Vector2d a = nbv_free.Choose(c, map, {}, &rng).pixel;
  c.eye_W = Turned(-0.2);
  CHECK(nbv_free.Choose(c, map, {}, &rng).pixel == a);
}

TEST_CASE("raster visits every cell once per pass, in a serpentine", "[fovea][strategy]") {
  fovea::SelectionOptions o = Options();
  o.border_px = 0;
  o.fovea_size_px = 40;  // 4 x 3 cells over 160 x 120
  const fovea::PatchMap map = PlaneWithHoles({});
  const fovea::SelectionContext c = Context(map, false);
  fovea::RasterStrategy raster(o);
  const std::vector<cv::Rect> cells = raster.Cells(c.map_depth_m.size(), 0);
  REQUIRE(cells.size() == 12);
  CHECK(cells[3].x > cells[0].x);   // first row left to right,
  CHECK(cells[4].x == cells[3].x);  // the second back
  std::mt19937_64 rng(0);
  for (size_t i = 0; i < cells.size(); ++i) {
    INFO("cell " << i);
    const fovea::SelectionSummary s = raster.Choose(c, map, {}, &rng);
    REQUIRE(s.ok);
    CHECK(Inside(cells[i], s.pixel));
    const cv::Point centre(cells[i].x + cells[i].width / 2, cells[i].y + cells[i].height / 2);
    CHECK(std::abs(s.pixel.x() - centre.x) <= 1);
    CHECK(std::abs(s.pixel.y() - centre.y) <= 1);
  }
  // Then the next pass, on a grid shifted half a cell.
  const std::vector<cv::Rect> next = raster.Cells(c.map_depth_m.size(), 1);
  CHECK(next.size() == 15);
  CHECK(Inside(next[0], raster.Choose(c, map, {}, &rng).pixel));
  // Four passes in all, then nothing.
  int offered = 1;
  while (raster.Choose(c, map, {}, &rng).ok) ++offered;
  int total = 0;
  for (int pass = 1; pass < 4; ++pass)
    total += static_cast<int>(raster.Cells(c.map_depth_m.size(), pass).size());
  CHECK(offered == total);

  // A cell the map is silent in (holes left unfilled) is passed over.
  const fovea::PatchMap holed = PlaneWithHoles({cells[5]});
  const fovea::SelectionContext ch = Context(holed, false);
  fovea::RasterStrategy skipping(o);
  std::vector<int> visited(cells.size(), 0);
  for (size_t i = 0; i + 1 < cells.size(); ++i) {
    const fovea::SelectionSummary s = skipping.Choose(ch, holed, {}, &rng);
    REQUIRE(s.ok);
    for (size_t k = 0; k < cells.size(); ++k) visited[k] += Inside(cells[k], s.pixel);
  }
  for (size_t k = 0; k < cells.size(); ++k) CHECK(visited[k] == (k == 5 ? 0 : 1));
}

TEST_CASE("random is uniform over the candidates and keeps away from refused points",
          "[fovea][strategy]") {
  fovea::SelectionOptions o = Options();
  o.border_px = 0;
  const fovea::PatchMap map = PlaneWithHoles({});
  const fovea::SelectionContext c = Context(map, false);
  fovea::RandomStrategy random(o);
  std::mt19937_64 rng(7);
  // 16 bins of 40 x 30 px, equal areas: a chi-square test with 15 degrees
  // of freedom, at the 0.1% level (37.70).
  constexpr int kDraws = 3200, kBins = 16;
  std::vector<int> count(kBins, 0);
  for (int i = 0; i < kDraws; ++i) {
    const fovea::SelectionSummary s = random.Choose(c, map, {}, &rng);
    REQUIRE(s.ok);
    ++count[static_cast<int>(s.pixel.y()) / 30 * 4 + static_cast<int>(s.pixel.x()) / 40];
  }
  double chi2 = 0;
  const double expected = double(kDraws) / kBins;
  for (const int n : count) chi2 += (n - expected) * (n - expected) / expected;
  CHECK(chi2 < 37.70);
  // Refused points: nothing within their radius is ever drawn.
  const Eigen::Vector3d refused = c.MapPoint(80, 60);
  for (int i = 0; i < 200; ++i) {
    const fovea::SelectionSummary s = random.Choose(c, map, {refused}, &rng);
    REQUIRE(s.ok);
    CHECK((s.point_W - refused).norm() >= o.refused_radius_m - 1e-9);
  }
}

TEST_CASE("selection.strategy names the strategy; deterministic keeps its meaning",
          "[fovea][strategy]") {
  for (const char* name : {"fovea", "deterministic", "random", "raster", "next_best_view"}) {
    fovea::SelectionOptions o;
    o.strategy = name;
    REQUIRE_NOTHROW(o.Check());
    const auto s = fovea::MakeStrategy(o, fovea::CriteriaOptions{});
    CHECK(s->Name() == name);
    const bool current = std::string(name) == "fovea" || std::string(name) == "deterministic";
    CHECK((s->View() == fovea::StrategyView::kCurrent) == current);
  }
  for (const char* name : {"fovea", "deterministic"}) {
    fovea::SelectionOptions o;
    o.strategy = name;
    o.view = "reference";
    REQUIRE_NOTHROW(o.Check());
    CHECK(fovea::MakeStrategy(o, fovea::CriteriaOptions{})->View() ==
          fovea::StrategyView::kReference);
  }
  // The fallback replaces a composite rule's choice in the current view;
  // the strategies that choose in the reference view have none to replace
  // (and the default, "stalled", must not refuse them).
  CHECK(fovea::SelectionOptions{}.reference_fallback == "stalled");
  for (const char* fallback : {"mapped", "foveal", "stalled"}) {
    INFO(fallback);
    fovea::SelectionOptions f;
    f.reference_fallback = fallback;
    CHECK_NOTHROW(f.Check());
    CHECK(f.FallsBack());
    f.strategy = "deterministic";
    CHECK(f.FallsBack());
    f.view = "reference";
    CHECK_NOTHROW(f.Check());
    CHECK_FALSE(f.FallsBack());
    f.view = "current";
    for (const char* other : {"random", "raster", "next_best_view"}) {
      f.strategy = other;
      CHECK_NOTHROW(f.Check());
      CHECK_FALSE(f.FallsBack());
    }
  }
  fovea::SelectionOptions none;
  none.reference_fallback = "none";
  CHECK_FALSE(none.FallsBack());
  none.reference_fallback = "sometimes";
  CHECK_THROWS_WITH(none.Check(), Catch::Contains("selection.reference_fallback"));
  fovea::SelectionOptions o;
  o.view = "home";
  CHECK_THROWS_WITH(o.Check(), Catch::Contains("selection.view"));
  o.view = "current";
  o.deterministic = true;
  CHECK(fovea::MakeStrategy(o, fovea::CriteriaOptions{})->Name() == "deterministic");
  o.strategy = "random";
  CHECK_THROWS_AS(o.Check(), rig::InputError);
  o.strategy = "greedy";
  o.deterministic = false;
  CHECK_THROWS_WITH(o.Check(), Catch::Contains("selection.strategy"));
}

TEST_CASE("the paper's rule chooses again in one context as if from scratch", "[fovea][strategy]") {
  // A textured image, so that every criterion has something to weigh.
  cv::Mat image(kHeight, kWidth, CV_8U);
  cv::randu(image, 0, 255);
  cv::GaussianBlur(image, image, cv::Size(0, 0), 1.5);
  const fovea::PatchMap map = PlaneWithHoles({cv::Rect(20, 40, 30, 30)});
  const fovea::SelectionContext c = fovea::SelectionContext::Make(image, View(), map, true);
  const std::unique_ptr<fovea::FixationStrategy> rule =
      fovea::MakeStrategy(Options(), fovea::CriteriaOptions{});
  // The first three choices are passed over: the weights kept between the
  // tries must give what weighing afresh each time (the default) gives.
  int calls = 0;
  auto pass_three = [&calls](const fovea::SelectionSummary&) { return ++calls > 3; };
  std::vector<Eigen::Vector3d> kept, fresh;
  std::mt19937_64 a(7), b(7);
  const fovea::SelectionSummary s = rule->ChooseAccepted(c, map, &kept, &a, pass_three, 8, false);
  calls = 0;
  const fovea::SelectionSummary t =
      rule->FixationStrategy::ChooseAccepted(c, map, &fresh, &b, pass_three, 8, false);
  REQUIRE(s.ok);
  CHECK(s.prescreened == 3);
  CHECK(t.prescreened == 3);
  CHECK(s.pixel == t.pixel);
  CHECK(s.composite_chosen == t.composite_chosen);
  REQUIRE(kept.size() == 3);
  CHECK(kept == fresh);
  // Each choice passed over is refused with its neighbourhood: no two alike.
  CHECK(kept[0] != kept[1]);
  CHECK(kept[1] != kept[2]);
  // The next call in the same context (the loop's attempt was refused)
  // keeps the weights too: the same choice as afresh.
  kept.push_back(s.point_W);
  fresh.push_back(t.point_W);
  auto take = [](const fovea::SelectionSummary&) { return true; };
  const fovea::SelectionSummary s2 = rule->ChooseAccepted(c, map, &kept, &a, take, 8, true);
  const fovea::SelectionSummary t2 =
      rule->FixationStrategy::ChooseAccepted(c, map, &fresh, &b, take, 8, true);
  CHECK(s2.pixel == t2.pixel);
  CHECK(s2.pixel != s.pixel);
  // At most max_passed are passed over.
  std::vector<Eigen::Vector3d> none;
  const fovea::SelectionSummary u = rule->ChooseAccepted(
      c, map, &none, &a, [](const fovea::SelectionSummary&) { return false; }, 2, false);
  CHECK(u.prescreened == 2);
  CHECK(none.size() == 2);
}
