#include "fovea/placement.h"

#include <catch2/catch.hpp>
#include <cmath>

#include "test_rig.h"

namespace {
const rig::CameraIntrinsics kCamera =
    rig::CameraIntrinsics::FromHorizontalFov(640, 480, 30 * M_PI / 180);
constexpr double kBaseline = 0.06;

// The simulator's default rig, home pose 0.10 m wide.
fovea::PlacementRig TestRig(bool left_pair = true, bool left_pair_first = false) {
  fovea::PlacementRig r;
  r.geometry = TestGeometry();
  r.limits = TestLimits();
  r.left = r.right = kCamera;
  r.home_left_m = -0.05;
  r.left_pair = left_pair;
  r.left_pair_first = left_pair_first;
  return r;
}

// A square facing the rig (normal along world y), `half` metres to each side of centre_W.
fovea::Patch Square(const Eigen::Vector3d& centre_W, double half) {
  fovea::Patch p;
  p.corners_W = {
      centre_W + Eigen::Vector3d(-half, 0, -half), centre_W + Eigen::Vector3d(half, 0, -half),
      centre_W + Eigen::Vector3d(half, 0, half), centre_W + Eigen::Vector3d(-half, 0, half)};
  return p;
}

fovea::PlacementChoice Choose(const fovea::PatchMap& map, const Eigen::Vector3d& p_W,
                              const std::optional<fovea::DepthRange>& guessed = std::nullopt,
                              bool left_pair = true, bool left_pair_first = false) {
  return fovea::ChoosePlacement(TestRig(left_pair, left_pair_first), map, p_W, kBaseline, {},
                                guessed);
}

// The optical centre of one camera of the pair the choice uses.
Eigen::Vector3d OpticalCentre(const fovea::PlacementChoice& c, rig::Side side) {
  return TestRig()
      .For(c.placement)
      .geometry.WorldFromCamera(side, c.vergence.state[side])
      .translation();
}
}  // namespace

TEST_CASE("carriage placements keep the baseline and put the named carriage innermost",
          "[fovea][placement]") {
  const fovea::PlacementRig l = TestRig();
  using fovea::Placement;
  const rig::StageState sym = fovea::PlaceCarriages(l, kBaseline, Placement::kSymmetric);
  CHECK(sym.left.carriage_m == Approx(-0.03));
  CHECK(sym.right.carriage_m == Approx(0.03));
  const rig::StageState ri = fovea::PlaceCarriages(l, kBaseline, Placement::kRightInner);
  CHECK(ri.right.carriage_m == Approx(0.0005));
  CHECK(ri.left.carriage_m == Approx(-0.0595));
  const rig::StageState li = fovea::PlaceCarriages(l, kBaseline, Placement::kLeftInner);
  CHECK(li.left.carriage_m == Approx(-0.0005));
  CHECK(li.right.carriage_m == Approx(0.0595));
  // The left camera pair: its right stage at the home pose's left carriage.
  const rig::StageState lp = fovea::PlaceCarriages(l, kBaseline, Placement::kLeftPair);
  CHECK(lp.right.carriage_m == Approx(-0.05));
  CHECK(lp.left.carriage_m == Approx(-0.11));
  CHECK(l.For(Placement::kLeftPair).limits.Violation(lp).empty());
  CHECK_FALSE(l.limits.Violation(lp).empty());  // no place for the real right camera
  for (const rig::StageState& s : {sym, ri, li, lp}) CHECK(s.BaselineM() == Approx(kBaseline));
  CHECK(std::string(fovea::PlacementName(Placement::kRightInner)) == "right_inner");
}

TEST_CASE("placement: the right carriage innermost unless the map hides the point from it",
          "[fovea][placement]") {
  const Eigen::Vector3d p(0.0, 1.2, 0.0);
  fovea::PatchMap map;
  map.Add(Square(p, 0.2));  // the surface the point lies on

  fovea::PlacementChoice free = Choose(map, p);
  REQUIRE(free.vergence.ok);
  CHECK(free.placement == fovea::Placement::kRightInner);
  CHECK(free.occluded == 0);
  CHECK(free.vergence.state.right.carriage_m == Approx(0.0005).margin(1e-5));

  // A 1 cm square halfway along the right camera's line of sight from there:
  // the symmetric placement's cameras look past it (1.5 cm to either side).
  const Eigen::Vector3d right_c = OpticalCentre(free, rig::Side::kRight);
  map.Add(Square(0.5 * (right_c + p), 0.005));
  const fovea::PlacementChoice moved = Choose(map, p);
  REQUIRE(moved.vergence.ok);
  CHECK(moved.placement == fovea::Placement::kSymmetric);
  CHECK(moved.occluded == 0);
  CHECK(moved.vergence.state.BaselineM() == Approx(kBaseline).margin(1e-5));

  // A wall in front hides the point from every placement's both cameras
  // (the left camera pair's too): the first placement stays, with both
  // cameras counted.
  map.Add(Square({0.0, 0.8, 0.0}, 0.3));
  const fovea::PlacementChoice walled = Choose(map, p);
  REQUIRE(walled.vergence.ok);
  CHECK(walled.placement == fovea::Placement::kRightInner);
  CHECK(walled.occluded == 2);
}

TEST_CASE("placement: a guessed depth also weighs the points behind it", "[fovea][placement]") {
  // A hole's point guessed at 0.6 m with a mapped wall at 1.0 m behind it:
  // the samples past the wall are hidden from both cameras.
  const Eigen::Vector3d p(0.02, 0.6, 0.0);
  fovea::PatchMap map;
  map.Add(Square({0.0, 1.0, 0.0}, 1.0));
  const fovea::PlacementChoice known = Choose(map, p);
  REQUIRE(known.vergence.ok);
  CHECK(known.occluded == 0);
  const fovea::PlacementChoice guessed = Choose(map, p, fovea::DepthRange{0.4, 1e5});
  REQUIRE(guessed.vergence.ok);
  CHECK(guessed.occluded > 0);
  CHECK(guessed.occluded % 2 == 0);  // both cameras, every time
  // Points beyond the guessed range are not sampled.
  CHECK(Choose(map, p, fovea::DepthRange{0.4, 0.9}).occluded == 0);
}

TEST_CASE("placement: a point no placement can fixate is reported, with why",
          "[fovea][placement]") {
  const fovea::PlacementChoice behind = Choose({}, {0.0, -1.0, 0.0});
  CHECK_FALSE(behind.vergence.ok);
  CHECK_FALSE(behind.vergence.why.empty());
}

TEST_CASE(
    "placement: past a near left edge, where no right camera sees, the left camera pairs with "
    "itself",
    "[fovea][placement]") {
  // A block face at 0.5 m whose left edge is at x = -0.07, and the plane at
  // 1.2 m: the point just left of the edge (seen from the home pose's left
  // camera at x = -0.05) is hidden from every right camera position (x >=
  // 0.0005) by the block.
  const Eigen::Vector3d p(-0.13, 1.2, 0.0);
  fovea::PatchMap map;
  map.Add(Square(p, 0.1));
  fovea::Patch block;
  block.corners_W = {Eigen::Vector3d(-0.07, 0.5, -0.1), Eigen::Vector3d(0.2, 0.5, -0.1),
                     Eigen::Vector3d(0.2, 0.5, 0.1), Eigen::Vector3d(-0.07, 0.5, 0.1)};
  map.Add(block);
  const fovea::PlacementChoice without = Choose(map, p, std::nullopt, false);
  REQUIRE(without.vergence.ok);
  CHECK(without.occluded >= 1);
  const fovea::PlacementChoice with = Choose(map, p);
  REQUIRE(with.vergence.ok);
  CHECK(with.placement == fovea::Placement::kLeftPair);
  CHECK(with.occluded == 0);
  CHECK(with.vergence.state.right.carriage_m == Approx(-0.05).margin(1e-5));
  // Both of its "cameras" are the left head: on the point's line of sight
  // from either stage.
  const Eigen::Vector3d a = OpticalCentre(with, rig::Side::kLeft),
                        b = OpticalCentre(with, rig::Side::kRight);
  CHECK(a.x() < b.x());
  CHECK(b.x() < -0.04);
}

TEST_CASE(
    "placement: with left_pair_first the left camera pairs with itself unless the map hides "
    "the point from it",
    "[fovea][placement]") {
  const Eigen::Vector3d p(0.0, 1.2, 0.0);
  fovea::PatchMap map;
  map.Add(Square(p, 0.2));
  auto choose = [&](bool left_pair) { return Choose(map, p, std::nullopt, left_pair, true); };
  const fovea::PlacementChoice first = choose(true);
  REQUIRE(first.vergence.ok);
  CHECK(first.placement == fovea::Placement::kLeftPair);
  CHECK(first.occluded == 0);
  CHECK(first.vergence.state.right.carriage_m == Approx(-0.05).margin(1e-5));
  // Without the left camera pair the setting changes nothing.
  CHECK(choose(false).placement == fovea::Placement::kRightInner);

  // A 4 mm square halfway along the line of sight of the pair's "right"
  // stage (the home pose's left camera, x = -0.05): the right carriage
  // innermost is next, and its cameras (x = -0.0595 and 0.0005) look past
  // it, 4.75 mm and 25 mm from its centre there.
  const Eigen::Vector3d home_left = OpticalCentre(first, rig::Side::kRight);
  map.Add(Square(0.5 * (home_left + p), 0.002));
  const fovea::PlacementChoice moved = choose(true);
  REQUIRE(moved.vergence.ok);
  CHECK(moved.placement == fovea::Placement::kRightInner);
  CHECK(moved.occluded == 0);
}
