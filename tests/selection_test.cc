// Fixation selection: normalized criteria, their product, the exponential
// draw, the deterministic mode, refused points.
#include "fovea/selection.h"

#include <catch2/catch.hpp>
#include <opencv2/imgproc.hpp>

#include "fovea/geometry.h"
#include "test_views.h"

namespace {

rig::CameraView View() { return ForwardView(160, 120, 150); }

fovea::Patch Square(double x0, double x1, double z0, double z1, double y, fovea::PatchLevel level) {
  fovea::Patch p;
  p.corners_W = {Eigen::Vector3d(x0, y, z0), Eigen::Vector3d(x1, y, z0), Eigen::Vector3d(x1, y, z1),
                 Eigen::Vector3d(x0, y, z1)};
  p.level = level;
  return p;
}

// Texture only in the right half of the image.
cv::Mat HalfTextured() {
  cv::Mat img(120, 160, CV_8U, cv::Scalar(128));
  cv::Mat noise(120, 80, CV_8U);
  cv::randu(noise, 0, 255);
  noise.copyTo(img(cv::Rect(80, 0, 80, 120)));
  return img;
}

}  // namespace

TEST_CASE("each criterion is normalized and says what it should", "[fovea][selection]") {
  fovea::PatchMap map;
  map.Add(Square(-1, 0, -1, 1, 1.0, fovea::PatchLevel::kFoveal));  // left half: foveal, 1 m
  map.Add(Square(0, 1, -1, 1, 2.0, fovea::PatchLevel::kIdr));      // right half: IDR, 2 m
  fovea::SelectionContext c = fovea::SelectionContext::Make(HalfTextured(), View(), map);
  c.has_fixation = true;
  c.fixation_depth_m = 1.0;
  c.z_t_near_m = c.z_t_far_m = 0.1;
  const fovea::CriteriaOptions o;  // the run's
  for (const auto& criterion : o.Make()) {
    INFO(criterion->Name());
    const cv::Mat w = criterion->Evaluate(c);
    CHECK(cv::sum(w)[0] == Approx(1.0));
    double lo;
    cv::minMaxLoc(w, &lo);
    CHECK(lo >= 0);
  }
  const fovea::GradientAttraction gradient(o);
  const fovea::LocalSuppression suppression(o);
  const fovea::Proximity2D p2d(o);
  const fovea::Proximity3D p3d(o);
  CHECK(gradient.Evaluate(c).at<double>(60, 120) > 20 * gradient.Evaluate(c).at<double>(60, 30));
  CHECK(suppression.Evaluate(c).at<double>(60, 120) ==
        Approx(suppression.Evaluate(c).at<double>(60, 30) / o.suppressed_weight));
  CHECK(p2d.Evaluate(c).at<double>(60, 80) > p2d.Evaluate(c).at<double>(5, 5));
  CHECK(p3d.Evaluate(c).at<double>(60, 30) ==
        Approx(p3d.Evaluate(c).at<double>(60, 120) / o.proximity_3d_low));
}

TEST_CASE("2D proximity is measured from the gaze when the choice is made in another view",
          "[fovea][selection]") {
  fovea::PatchMap map;
  map.Add(Square(-1, 1, -1, 1, 1.0, fovea::PatchLevel::kIdr));
  fovea::SelectionContext c = fovea::SelectionContext::Make(HalfTextured(), View(), map);
  const fovea::CriteriaOptions o;
  const fovea::Proximity2D p2d(o);
  cv::Point peak;
  cv::minMaxLoc(p2d.Evaluate(c), nullptr, nullptr, nullptr, &peak);
  CHECK(std::abs(peak.x - c.view.intrinsics.cx_px) <= 1);
  CHECK(std::abs(peak.y - c.view.intrinsics.cy_px) <= 1);
  // The current fixation point's image in this view, near its top right.
  c.gaze_px = Eigen::Vector2d(130, 20);
  const cv::Mat w = p2d.Evaluate(c);
  cv::minMaxLoc(w, nullptr, nullptr, nullptr, &peak);
  CHECK(peak == cv::Point(130, 20));
  CHECK(cv::sum(w)[0] == Approx(1.0));
  // exp(-r / s): 100 pixels farther from the gaze weigh exp(-100 / s) as much.
  CHECK(w.at<double>(20, 30) / w.at<double>(20, 130) ==
        Approx(std::exp(-100.0 / o.proximity_2d_scale_px)));
}

TEST_CASE("the exponential draw favours high values with the scale asked for",
          "[fovea][selection]") {
  CHECK(fovea::DrawExponential(0.0, 0.5) == 0.0);
  CHECK(fovea::DrawExponential(1.0 - 1e-12, 0.5) == Approx(1.0).margin(1e-6));
  // Mean of u under density ~ exp(-u / s) on [0, 1], s = 0.5: s - e^(-1/s) / (1 - e^(-1/s)).
  double mean = 0;
  const int n = 100000;
  for (int i = 0; i < n; ++i) mean += fovea::DrawExponential((i + 0.5) / n, 0.5);
  mean /= n;
  CHECK(mean == Approx(0.5 - std::exp(-2.0) / (1 - std::exp(-2.0))).epsilon(1e-3));
  CHECK(fovea::DrawExponential(0.5, 0.1) < fovea::DrawExponential(0.5, 0.5));
}

TEST_CASE("selection: deterministic takes the maximum, and draws are reproducible from the seed",
          "[fovea][selection]") {
  fovea::PatchMap map;
  map.Add(Square(-1, 0, -1, 1, 1.0, fovea::PatchLevel::kFoveal));
  map.Add(Square(0, 1, -1, 1, 1.0, fovea::PatchLevel::kIdr));
  const fovea::SelectionContext c = fovea::SelectionContext::Make(HalfTextured(), View(), map);
  fovea::SelectionOptions o;
  o.deterministic = true;
  const fovea::FixationSelector det(fovea::CriteriaOptions{}.Make(), o);
  std::mt19937_64 rng(1);
  const auto s = det.Choose(c, map, {}, &rng);
  REQUIRE(s.ok);
  CHECK(s.composite_chosen == s.composite_max);
  CHECK(s.pixel.x() >= 80);                          // on the texture, not the foveal half
  CHECK(s.point_W.y() == Approx(1.0).margin(1e-9));  // raytraced into the map

  o.deterministic = false;
  const fovea::FixationSelector drawn(fovea::CriteriaOptions{}.Make(), o);
  std::mt19937_64 a(7), b(7), other(8);
  std::vector<Eigen::Vector2d> pa, pb, po;
  for (int i = 0; i < 10; ++i) {
    pa.push_back(drawn.Choose(c, map, {}, &a).pixel);
    pb.push_back(drawn.Choose(c, map, {}, &b).pixel);
    po.push_back(drawn.Choose(c, map, {}, &other).pixel);
  }
  CHECK(pa == pb);
  CHECK(pa != po);

  // A refused point takes its neighbourhood out of the candidates.
  const auto refused = det.Choose(c, map, {s.point_W}, &rng);
  REQUIRE(refused.ok);
  CHECK((refused.point_W - s.point_W).norm() >= o.refused_radius_m);
}

TEST_CASE("graded suppression: peripheral data weighs between foveal data and the rest",
          "[fovea][selection]") {
  fovea::PatchMap map;
  map.Add(Square(-1, -0.3, -1, 1, 1.0, fovea::PatchLevel::kFoveal));
  map.Add(Square(-0.3, 0.3, -1, 1, 1.0, fovea::PatchLevel::kPeripheral));
  map.Add(Square(0.3, 1, -1, 1, 1.0, fovea::PatchLevel::kIdr));
  const fovea::SelectionContext c = fovea::SelectionContext::Make(HalfTextured(), View(), map);
  // Columns: foveal at x = 10, peripheral at x = 80, IDR at x = 150 (f = 150, 1 m away).
  fovea::CriteriaOptions o;  // the run's: peripheral 0.3, foveal 0.02
  const cv::Mat graded = fovea::LocalSuppression(o).Evaluate(c);
  CHECK(graded.at<double>(60, 80) == Approx(0.3 * graded.at<double>(60, 150)));
  CHECK(graded.at<double>(60, 10) == Approx(0.02 * graded.at<double>(60, 150)));
  // The paper's rule: peripheral data is not suppressed.
  o.peripheral_weight = 1.0;
  const cv::Mat paper = fovea::LocalSuppression(o).Evaluate(c);
  CHECK(paper.at<double>(60, 80) == Approx(paper.at<double>(60, 150)));
}

TEST_CASE("hole width: a hole's weight grades from its edge inwards, either way",
          "[fovea][selection]") {
  // f = 150 px, 1 m away: column x lies at (x - 80) / 150 m. Peripheral data
  // on columns 0-80 and 86-110; a hole 6 columns wide between them and one
  // from column 110 to the image's edge.
  fovea::PatchMap map;
  map.Add(Square(-1, 0, -1, 1, 1.0, fovea::PatchLevel::kPeripheral));
  map.Add(Square(0.04, 0.2, -1, 1, 1.0, fovea::PatchLevel::kPeripheral));
  const fovea::SelectionContext c = fovea::SelectionContext::Make(HalfTextured(), View(), map);
  REQUIRE(c.map_level.at<signed char>(60, 83) == -1);
  REQUIRE(c.map_level.at<signed char>(60, 150) == -1);
  fovea::CriteriaOptions o;  // peripheral 0.3; a hole: 0.3 at its edge, 1 inside
  // The paper's rule: every hole weighs the same.
  const cv::Mat paper = fovea::LocalSuppression(o).Evaluate(c);
  CHECK(paper.at<double>(60, 83) == Approx(paper.at<double>(60, 150)));
  CHECK(paper.at<double>(60, 40) == Approx(0.3 * paper.at<double>(60, 150)));
  o.hole_width_px = 10;
  const cv::Mat w = fovea::LocalSuppression(o).Evaluate(c);
  const double peripheral = w.at<double>(60, 40);
  REQUIRE(peripheral > 0);
  // 40 columns inside the wide hole: the full weight, 1 / 0.3 of peripheral
  // data's. The strip's pixels lie at most 3-4 columns from mapped data:
  // above peripheral data, well below the full weight. At the hole's edge
  // the weight is close to peripheral data's, and it rises inwards.
  CHECK(w.at<double>(60, 150) == Approx(peripheral / 0.3));
  for (int x = 81; x <= 85; ++x) {
    INFO("column " << x);
    CHECK(w.at<double>(60, x) > peripheral * 1.1);
    CHECK(w.at<double>(60, x) < peripheral * (0.3 + 0.7 * 0.45) / 0.3);
  }
  CHECK(w.at<double>(60, 111) < peripheral * (0.3 + 0.7 * 0.25) / 0.3);
  CHECK(w.at<double>(60, 111) < w.at<double>(60, 115));
  CHECK(w.at<double>(60, 115) < w.at<double>(60, 119));
  CHECK(w.at<double>(60, 125) == Approx(peripheral / 0.3));
  CHECK(cv::sum(w)[0] == Approx(1.0));
  // The other way: the edges of holes weigh 1, their insides 0.3, as much
  // as peripheral data.
  o.hole_edge_weight = 1;
  o.hole_inside_weight = 0.3;
  const cv::Mat edges = fovea::LocalSuppression(o).Evaluate(c);
  const double p = edges.at<double>(60, 40);
  CHECK(edges.at<double>(60, 150) == Approx(p));
  for (int x = 81; x <= 85; ++x) {
    INFO("column " << x);
    CHECK(edges.at<double>(60, x) > p * (1 - 0.7 * 0.45) / 0.3);
    CHECK(edges.at<double>(60, x) < p * (1 - 0.7 * 0.05) / 0.3);
  }
  CHECK(edges.at<double>(60, 111) > edges.at<double>(60, 115));
}

TEST_CASE("local suppression: zero weight at earlier fixations, low weight around them",
          "[fovea][selection]") {
  fovea::PatchMap map;
  map.Add(Square(-1, 0, -1, 1, 1.0, fovea::PatchLevel::kFoveal));  // left half foveal, 1 m
  map.Add(Square(0, 1, -1, 1, 1.0, fovea::PatchLevel::kIdr));      // right half IDR, 1 m
  fovea::SelectionContext c = fovea::SelectionContext::Make(HalfTextured(), View(), map);
  // f = 150 px, 1 m away: pixel column x lies at (x - 80) / 150 m.
  const Eigen::Vector3d a(40.0 / 150, 1.0, 0.0), b(-40.0 / 150, 1.0, 0.0);
  c.visits = {{a, a}, {b, b}};
  fovea::CriteriaOptions o;  // the run's: 0.02, 8 cm, peripheral 0.3, revisit 3 cm
  const cv::Mat w = fovea::LocalSuppression(o).Evaluate(c);
  const double free = w.at<double>(60, 150);  // 0.2 m from the nearest fixation
  REQUIRE(free > 0);
  CHECK(w.at<double>(60, 120) == 0.0);                  // on the IDR fixation point
  CHECK(w.at<double>(60, 123) == 0.0);                  // 2 cm away
  CHECK(w.at<double>(60, 126) == Approx(0.02 * free));  // 4 cm away: within the radius
  CHECK(w.at<double>(60, 40) == 0.0);                   // foveal data is 0 at a fixation too
  CHECK(w.at<double>(60, 10) == Approx(0.02 * free));   // and 0.02 elsewhere
  // Without a revisit radius the fixation point itself keeps the low weight.
  o.revisit_radius_m = 0;
  const cv::Mat paper = fovea::LocalSuppression(o).Evaluate(c);
  CHECK(paper.at<double>(60, 120) == Approx(0.02 * paper.at<double>(60, 150)));
  // A point aimed at where the servo settled 20 cm away is suppressed too;
  // one where it settled 2 cm away adds nothing beyond the settled point.
  o.revisit_radius_m = 0.03;
  const Eigen::Vector3d settled(40.0 / 150, 1.0, 0.0), far_aim(70.0 / 150, 1.0, 0.0);
  c.visits = {{settled, far_aim}};
  const cv::Mat aimed = fovea::LocalSuppression(o).Evaluate(c);
  CHECK(aimed.at<double>(60, 150) == 0.0);  // on the point aimed at
  c.visits = {{settled, Eigen::Vector3d(43.0 / 150, 1.0, 0.0)}};
  const cv::Mat near_aim = fovea::LocalSuppression(o).Evaluate(c);
  c.visits = {{settled, settled}};
  CHECK(cv::norm(near_aim, fovea::LocalSuppression(o).Evaluate(c), cv::NORM_INF) == 0.0);
}

TEST_CASE("holes in the map take the nearest mapped depth and can be fixated",
          "[fovea][selection]") {
  fovea::PatchMap map;
  map.Add(Square(-1, 0, -1, 1, 2.0, fovea::PatchLevel::kPeripheral));  // left half only, 2 m
  const cv::Mat image = HalfTextured();  // texture on the right: the hole
  const fovea::SelectionContext plain = fovea::SelectionContext::Make(image, View(), map);
  const fovea::SelectionContext filled = fovea::SelectionContext::Make(image, View(), map, true);
  CHECK(plain.map_depth_m.at<float>(60, 120) == 0.f);
  CHECK(filled.map_depth_m.at<float>(60, 120) == Approx(2.0));
  CHECK(filled.map_level.at<signed char>(60, 120) == -1);  // still known as a hole
  CHECK(filled.map_depth_m.at<float>(60, 30) == plain.map_depth_m.at<float>(60, 30));

  fovea::SelectionOptions o;
  o.deterministic = true;
  const fovea::FixationSelector selector(fovea::CriteriaOptions{}.Make(), o);
  std::mt19937_64 rng(1);
  // Without filling, only the untextured mapped half can be chosen.
  const auto s_plain = selector.Choose(plain, map, {}, &rng);
  REQUIRE(s_plain.ok);
  CHECK(s_plain.pixel.x() < 80);
  CHECK_FALSE(s_plain.in_hole);
  // With it, the textured hole wins, at the guessed depth.
  const auto s_filled = selector.Choose(filled, map, {}, &rng);
  REQUIRE(s_filled.ok);
  CHECK(s_filled.pixel.x() >= 80);
  CHECK(s_filled.in_hole);
  CHECK(s_filled.point_W.y() == Approx(2.0).margin(1e-6));
}

TEST_CASE("selection at a reduced resolution: the same rays, sizes in full-resolution pixels",
          "[fovea][selection]") {
  rig::CameraView full = View();
  full.gray = HalfTextured();
  for (const int level : {1, 2}) {
    INFO("level " << level);
    const rig::CameraView reduced = fovea::ReducedView(full, level);
    CHECK(reduced.intrinsics.width_px == 160 >> level);
    CHECK(reduced.intrinsics.height_px == 120 >> level);
    CHECK(reduced.gray.size() == cv::Size(160 >> level, 120 >> level));
    // Each reduced pixel looks along the ray of its block's centre.
    for (const Eigen::Vector2d& p : {Eigen::Vector2d(0, 0), Eigen::Vector2d(7, 3),
                                     Eigen::Vector2d(reduced.intrinsics.width_px - 1, 10)}) {
      const Eigen::Vector2d q = fovea::FullResolutionPixel(p, level);
      const double n = 1 << level;
      CHECK(q.x() == Approx(n * p.x() + (n - 1) / 2));
      const fovea::Ray a = fovea::PixelRay(reduced.world_T_camera, reduced.intrinsics, p);
      const fovea::Ray b = fovea::PixelRay(full.world_T_camera, full.intrinsics, q);
      CHECK((a.direction_W - b.direction_W).norm() < 1e-12);
    }
    // The image is averaged over the blocks: the texture stays on the right.
    CHECK(reduced.gray.at<uchar>(5, 2) == 128);
  }
  fovea::SelectionOptions selection;
  fovea::CriteriaOptions criteria;
  criteria.hole_width_px = 16;
  fovea::AtResolutionLevel(1, &selection, &criteria);
  CHECK(selection.border_px == 8);
  CHECK(selection.fovea_size_px == 64);
  CHECK(criteria.gradient_blur_px == 1.0);
  CHECK(criteria.proximity_2d_scale_px == 160);
  CHECK(criteria.hole_width_px == 8);
  selection.fovea_size_px = 8;  // the smallest allowed stays
  fovea::AtResolutionLevel(2, &selection, &criteria);
  CHECK(selection.fovea_size_px == 8);
  CHECK(selection.border_px == 2);
  CHECK_NOTHROW(selection.Check());

  // Chosen in the reduced view, the deterministic maximum still lies on the
  // texture, and its full-resolution pixel ray hits the map where the
  // choice's point says.
  fovea::PatchMap map;
  map.Add(Square(-1, 0, -1, 1, 1.0, fovea::PatchLevel::kFoveal));
  map.Add(Square(0, 1, -1, 1, 1.0, fovea::PatchLevel::kIdr));
  const rig::CameraView reduced = fovea::ReducedView(full, 1);
  const fovea::SelectionContext c =
      fovea::SelectionContext::Make(reduced.gray, reduced, map, false);
  fovea::SelectionOptions o;
  fovea::CriteriaOptions co;
  o.deterministic = true;
  fovea::AtResolutionLevel(1, &o, &co);
  std::mt19937_64 rng(1);
  const auto s = fovea::FixationSelector(co.Make(), o).Choose(c, map, {}, &rng);
  REQUIRE(s.ok);
  const Eigen::Vector2d q = fovea::FullResolutionPixel(s.pixel, 1);
  CHECK(q.x() >= 80);
  const fovea::Ray ray = fovea::PixelRay(full.world_T_camera, full.intrinsics, q);
  CHECK((ray.origin_W + ray.direction_W * ((s.point_W - ray.origin_W).norm()) - s.point_W).norm() <
        1e-9);
}

TEST_CASE("staying in the region: no candidate on a patch the reference camera does not see",
          "[fovea][selection]") {
  // A wall at 2 m; its right half is a separate patch marked hidden from
  // the reference camera (a surface seen past a nearer one's edge).
  fovea::PatchMap map;
  map.Add(Square(-3, 0, -1, 1, 2.0, fovea::PatchLevel::kFoveal));
  fovea::Patch hidden = Square(0, 3, -1, 1, 2.0, fovea::PatchLevel::kFoveal);
  hidden.hidden_in_reference = true;
  map.Add(hidden);
  fovea::SelectionContext c = fovea::SelectionContext::Make(HalfTextured(), View(), map);
  const fovea::SelectionOptions o;  // border 16 px
  c.region = View();                // the frame alone
  cv::Mat candidates = fovea::Candidates(c, {}, o);
  CHECK(candidates.at<uchar>(60, 40) == 255);
  CHECK(candidates.at<uchar>(60, 120) == 255);
  c.SetRegion(View(), map);  // and the hidden patches
  REQUIRE(c.region_hidden.size() == c.map_id.size());
  candidates = fovea::Candidates(c, {}, o);
  CHECK(candidates.at<uchar>(60, 40) == 255);
  CHECK(candidates.at<uchar>(60, 120) == 0);
  CHECK(cv::countNonZero(candidates(cv::Rect(81, 16, 63, 88))) == 0);
  // The selector then fixates the half the reference camera sees, though
  // the texture lies in the other.
  fovea::SelectionOptions deterministic;
  deterministic.deterministic = true;
  const fovea::FixationSelector selector(fovea::CriteriaOptions{}.Make(), deterministic);
  std::mt19937_64 rng(1);
  const auto choice = selector.Choose(c, map, {}, &rng);
  REQUIRE(choice.ok);
  CHECK(choice.pixel.x() < 80);
}
