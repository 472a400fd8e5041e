// The reference check: a patch is kept only where the reference camera sees
// its texture (HiddenQuarters, MarkHiddenFromReference, ReferenceMap).
#include "fovea/visibility.h"

#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>

#include "test_views.h"

namespace {

// A scene of two textured planes facing the cameras (world X right, Y
// forward, Z up): a near half-plane at Y = 0.6 m where X < 0, its edge at
// X = 0, before a far plane at Y = 1.3 m. From a camera at X = c the far
// plane shows for X > -1.1667 c, past the near plane's edge.
constexpr double kNearY = 0.6, kFarY = 1.3;

// Value noise: a random grey level per cell of `cell_m`, bilinear between
// cells (splitmix64 of the cell and the seed).
double Texture(double x, double z, std::uint64_t seed, double cell_m) {
  auto cell = [seed](std::int64_t i, std::int64_t j) {
    std::uint64_t h = seed * 0x9e3779b97f4a7c15ull +
                      static_cast<std::uint64_t>(i) * 0xbf58476d1ce4e5b9ull +
                      static_cast<std::uint64_t>(j) * 0x94d049bb133111ebull;
    h = (h ^ (h >> 30)) * 0xbf58476d1ce4e5b9ull;
    h = (h ^ (h >> 27)) * 0x94d049bb133111ebull;
    h ^= h >> 31;
    return double(h % 200) + 28;
  };
  const double u = x / cell_m, v = z / cell_m;
  const auto i = static_cast<std::int64_t>(std::floor(u)),
             j = static_cast<std::int64_t>(std::floor(v));
  const double fu = u - i, fv = v - j;
  return (1 - fv) * ((1 - fu) * cell(i, j) + fu * cell(i + 1, j)) +
         fv * ((1 - fu) * cell(i, j + 1) + fu * cell(i + 1, j + 1));
}

// A forward-looking camera at X = x_m, its image of the scene; the far
// plane's texture at `far_contrast` of its full contrast about grey 128.
rig::CameraView Camera(double x_m, double far_contrast = 1) {
  rig::CameraView view = ForwardView(320, 240, 600);
  view.world_T_camera.translation() = Eigen::Vector3d(x_m, 0, 0);
  const rig::CameraIntrinsics& k = view.intrinsics;
  view.gray = cv::Mat(k.height_px, k.width_px, CV_8U);
  for (int v = 0; v < k.height_px; ++v)
    for (int u = 0; u < k.width_px; ++u) {
      const Eigen::Vector3d d =
          view.world_T_camera.linear() *
          Eigen::Vector3d((u - k.cx_px) / k.fx_px, (v - k.cy_px) / k.fy_px, 1);
      Eigen::Vector3d p = view.world_T_camera.translation() + d * (kNearY / d.y());
      const bool near = p.x() < 0;
      if (!near) p = view.world_T_camera.translation() + d * (kFarY / d.y());
      view.gray.at<uchar>(v, u) = cv::saturate_cast<uchar>(
          near ? Texture(p.x(), p.z(), 1, 0.002)
               : 128 + far_contrast * (Texture(p.x(), p.z(), 2, 0.004) - 128));
    }
  return view;
}

// A 24 mm square patch on the plane at depth y, centred at X = x, Z = 0.
fovea::Patch Square(double x, double y) {
  constexpr double h = 0.012;
  fovea::Patch p;
  p.corners_W = {Eigen::Vector3d(x - h, y, h), Eigen::Vector3d(x + h, y, h),
                 Eigen::Vector3d(x + h, y, -h), Eigen::Vector3d(x - h, y, -h)};
  return p;
}

}  // namespace

TEST_CASE(
    "the quarters of patches of a farther surface seen past a nearer one's edge are hidden "
    "from the reference camera; what it sees is not",
    "[fovea][visibility]") {
  // Measured from X = +4 cm; the reference camera stands at X = -1 cm. The
  // far plane shows for X > -4.7 cm from the first, X > +1.17 cm from the
  // second.
  const rig::CameraView measured = Camera(0.04), reference = Camera(-0.01);
  fovea::PatchMap patches;
  patches.Add(Square(-0.025, kFarY));  // seen past the edge by the measuring camera only
  patches.Add(Square(0.012, kFarY));   // its left half behind the near plane from the reference
  patches.Add(Square(0.05, kFarY));    // the far plane both see
  patches.Add(Square(-0.05, kNearY));  // the near plane
  const fovea::ReferenceCheckOptions check{0.5, 4};
  // Bits 2 v + u: the left quarters are bits 0 and 2.
  CHECK(fovea::HiddenQuarters(patches, measured, reference, check) ==
        std::vector<std::uint8_t>{15, 5, 0, 0});
  // The check off: nothing is hidden.
  CHECK(fovea::HiddenQuarters(patches, measured, reference, {0, 4}) ==
        std::vector<std::uint8_t>(4, 0));
  // Marked: a patch with a hidden quarter stays in the map and leaves its
  // reference view.
  fovea::PatchMap marked = patches;
  CHECK(fovea::MarkHiddenFromReference(&marked, measured, reference, check) == 2);
  REQUIRE(marked.size() == 4);
  for (int i = 0; i < 4; ++i) CHECK(marked[i].hidden_in_reference == (i < 2));
  const fovea::PatchMap seen = fovea::ReferenceMap(marked);
  REQUIRE(seen.size() == 2);
  CHECK(seen[0].Centre().isApprox(patches[2].Centre()));
  CHECK(seen[1].Centre().isApprox(patches[3].Centre()));
  // A patch at a wrong depth samples another stretch of texture in the
  // reference image: 30 cm in front of the far plane, 7 px of parallax (15
  // mm, four texture cells, on the plane).
  fovea::PatchMap wrong;
  wrong.Add(Square(0.05, kFarY - 0.3));
  CHECK(fovea::HiddenQuarters(wrong, measured, reference, check) == std::vector<std::uint8_t>{15});
}

TEST_CASE(
    "a patch without texture in both images is not judged; without texture where it was "
    "measured but with texture in the reference image, it is",
    "[fovea][visibility]") {
  rig::CameraView measured = Camera(0.04), reference = Camera(-0.01);
  measured.gray.setTo(100);
  fovea::PatchMap patches;
  patches.Add(Square(-0.025, kFarY));  // behind the near plane from the reference camera
  patches.Add(Square(0.05, kFarY));    // the far plane both see
  // The reference camera sees the near plane's texture where the first
  // patch lies, and the far plane's where the second does: both are
  // judged and do not correlate with the flat measuring image.
  CHECK(fovea::HiddenQuarters(patches, measured, reference, {0.5, 4}) ==
        std::vector<std::uint8_t>{15, 15});
  // Flat in both: nothing to judge.
  reference.gray.setTo(100);
  CHECK(fovea::HiddenQuarters(patches, measured, reference, {0.5, 4}) ==
        std::vector<std::uint8_t>{0, 0});
  // A faint farther surface (a tenth of its contrast, about 5 grey levels)
  // measured past the nearer one's edge: its quarters vary too little to be
  // judged from the measuring image, but the reference image shows the
  // nearer surface's texture there, so they are judged and hidden; where
  // the reference camera sees the faint surface itself, the samples vary
  // little in both and pass.
  const rig::CameraView faint_measured = Camera(0.04, 0.1), faint_reference = Camera(-0.01, 0.1);
  CHECK(fovea::HiddenQuarters(patches, faint_measured, faint_reference, {0.5, 8}) ==
        std::vector<std::uint8_t>{15, 0});
}

TEST_CASE(
    "a patch is hidden by its left or right half, or three quarters, not by a top, bottom or "
    "lone quarter",
    "[fovea][visibility]") {
  // Bits 2 v + u: 1 top-left, 2 top-right, 4 bottom-left, 8 bottom-right.
  for (const int q : {5, 10, 7, 11, 13, 14, 15}) {
    CAPTURE(q);
    CHECK(fovea::HiddenSide(static_cast<std::uint8_t>(q)));
  }
  for (const int q : {0, 1, 2, 4, 8, 3, 12, 6, 9}) {
    CAPTURE(q);
    CHECK_FALSE(fovea::HiddenSide(static_cast<std::uint8_t>(q)));
  }
}

TEST_CASE(
    "on a faint texture, too faint for a quarter to be judged, the pooled samples of a half or "
    "of the whole patch judge it",
    "[fovea][visibility]") {
  // The scene's contrast cut to 8.5% and sensor noise of 2 grey levels
  // added (independent per camera): each quarter's samples vary by less
  // than 4 grey levels and go unjudged (the near plane's by about 3.6, the
  // far plane's coarser texture by 2.6). Pooled over a half or the whole
  // patch, with the pooled threshold at 2.3 grey levels so that the far
  // plane's patches are judged too, the hidden first patch and the hidden
  // half of the second correlate at -0.09 to 0.15, what the reference
  // camera sees at 0.67 to 0.83, and the second patch as a whole at 0.35.
  auto faint = [](rig::CameraView view, std::uint64_t seed) {
    cv::Mat noise(view.gray.size(), CV_32F);
    cv::RNG rng(seed);
    rng.fill(noise, cv::RNG::NORMAL, 0, 2);
    cv::Mat f;
    view.gray.convertTo(f, CV_32F, 0.085, 128 - 0.085 * 128);
    f += noise;
    f.convertTo(view.gray, CV_8U);
    return view;
  };
  const rig::CameraView measured = faint(Camera(0.04), 1), reference = faint(Camera(-0.01), 2);
  fovea::PatchMap patches;
  patches.Add(Square(-0.025, kFarY));  // seen past the edge by the measuring camera only
  patches.Add(Square(0.012, kFarY));   // its left half behind the near plane from the reference
  patches.Add(Square(0.05, kFarY));    // the far plane both see
  patches.Add(Square(-0.05, kNearY));  // the near plane
  fovea::ReferenceCheckOptions check{0.5, 4};
  // Quarters only: none can be judged.
  CHECK(fovea::HiddenQuarters(patches, measured, reference, check) ==
        std::vector<std::uint8_t>(4, 0));
  check.pooled_min_ncc = 0.2;
  check.pooled_min_texture_dn = 2.3;
  CHECK(fovea::HiddenQuarters(patches, measured, reference, check) ==
        std::vector<std::uint8_t>{15, 5, 0, 0});
  // Without texture in the measuring image, the reference image's faint
  // texture judges the pooled samples: nothing of it correlates.
  rig::CameraView flat = measured;
  flat.gray.setTo(100);
  CHECK(fovea::HiddenQuarters(patches, flat, reference, check) == std::vector<std::uint8_t>(4, 15));
  // Without texture in either image they are not judged.
  rig::CameraView flat_reference = reference;
  flat_reference.gray.setTo(100);
  CHECK(fovea::HiddenQuarters(patches, flat, flat_reference, check) ==
        std::vector<std::uint8_t>(4, 0));
}

TEST_CASE(
    "the strip of a patch's side that the reference camera does not see is cut from its part in "
    "the reference view; on a faint farther surface the whole patch is hidden",
    "[fovea][visibility]") {
  // The reference camera at X = -1 cm sees the far plane for X > 11.7 mm;
  // the patch spans X = 7.7 to 31.7 mm of it, so its left 4 mm (a sixth of
  // its width, about 2 px) lie behind the near plane's edge from there.
  fovea::PatchMap patches;
  patches.Add(Square(0.0197, kFarY));  // its left strip hidden from the reference
  patches.Add(Square(0.05, kFarY));    // the far plane both see
  patches.Add(Square(-0.05, kNearY));  // the near plane
  fovea::ReferenceCheckOptions check{0.5, 4};
  check.side_px = 2;
  {
    // A faint far plane (5% of its contrast, under 4 grey levels): its
    // quarters could not be judged from the measuring image, but the left
    // ones are from the reference image, where a third of each shows the
    // near plane's texture; they do not correlate, and the patch is hidden
    // whole rather than cut (judged from the measuring image alone, it
    // passed, and only its strip was cut). The others pass.
    const rig::CameraView measured = Camera(0.04, 0.05), reference = Camera(-0.01, 0.05);
    const std::vector<fovea::ReferenceSight> sight =
        fovea::JudgeReference(patches, measured, reference, check);
    REQUIRE(sight.size() == 3);
    CHECK(sight[0].hidden_quarters == 5);
    CHECK_FALSE(fovea::HiddenSide(sight[1].hidden_quarters));
    CHECK_FALSE(fovea::HiddenSide(sight[2].hidden_quarters));
  }
  {
    const rig::CameraView measured = Camera(0.04), reference = Camera(-0.01);
    const std::vector<fovea::ReferenceSight> sight =
        fovea::JudgeReference(patches, measured, reference, check);
    REQUIRE(sight.size() == 3);
    // No patch has a hidden side.
    for (const fovea::ReferenceSight& s : sight) CHECK_FALSE(fovea::HiddenSide(s.hidden_quarters));
    // The outer strip (2 px, 1/6 of the patch) is cut, the next one kept.
    const fovea::Patch::Part& cut = sight[0].part;
    CHECK(cut.s0 == Approx(1.0 / 6));
    CHECK(cut.s1 == 1);
    CHECK(cut.t0 == 0);
    CHECK(cut.t1 == 1);
    CHECK(sight[1].part.Whole());
    CHECK(sight[2].part.Whole());
    // Without strips the patch is whole.
    check.side_px = 0;
    CHECK(fovea::JudgeReference(patches, measured, reference, check)[0].part.Whole());
    // Marked, the reference view shows the patch from X = 11.7 mm on, on its
    // plane.
    check.side_px = 2;
    fovea::PatchMap marked = patches;
    CHECK(fovea::MarkHiddenFromReference(&marked, measured, reference, check) == 0);
    const fovea::PatchMap seen = fovea::ReferenceMap(marked);
    REQUIRE(seen.size() == 3);
    for (const Eigen::Vector3d& c : seen[0].corners_W) {
      CHECK(c.y() == Approx(kFarY));
      CHECK(std::abs(c.z()) == Approx(0.012));
    }
    CHECK(seen[0].corners_W[0].x() == Approx(0.0117).margin(1e-6));
    CHECK(seen[0].corners_W[3].x() == Approx(0.0117).margin(1e-6));
    CHECK(seen[0].corners_W[1].x() == Approx(0.0317).margin(1e-6));
    CHECK(seen[1].corners_W == patches[1].corners_W);
    // A patch with every side cut is left out of the reference view.
    marked.SetReferencePart(1, {0.5, 0.5, 0, 1});
    CHECK(marked[1].reference_part.Empty());
    CHECK_FALSE(marked[0].reference_part.Empty());
    const fovea::PatchMap rest = fovea::ReferenceMap(marked);
    REQUIRE(rest.size() == 2);
    CHECK(rest[1].corners_W == patches[2].corners_W);
  }
}

TEST_CASE("the reading rule leaves out a farther surface's pixels beside a nearer mapped one",
          "[visibility]") {
  // One row of 40 pixels: a near surface at 1 m over [0, 10), an unmapped
  // strip [10, 12) (its edge left out), a far surface at 2 m over [12, 30)
  // showing through it, unmapped [30, 40).
  cv::Mat depth(3, 40, CV_32F, cv::Scalar(0));
  depth.colRange(0, 10).setTo(1.0);
  depth.colRange(12, 30).setTo(2.0);
  cv::Mat ids(depth.size(), CV_32S, cv::Scalar(-1));
  ids.colRange(0, 10).setTo(0);
  ids.colRange(12, 30).setTo(1);
  const cv::Mat given = depth.clone(), given_ids = ids.clone();

  SECTION("pixels within flank_px of the nearer one are cleared, the rest kept") {
    fovea::ClearFlankedFarther(4, &depth, &ids);
    for (int y = 0; y < depth.rows; ++y)
      for (int x = 0; x < depth.cols; ++x) {
        CAPTURE(x, y);
        // Column 9 is the last near one: 12 and 13 lie 3 and 4 px from it.
        const bool cleared = x == 12 || x == 13;
        CHECK(depth.at<float>(y, x) == (cleared ? 0.f : given.at<float>(y, x)));
        CHECK(ids.at<int>(y, x) == (cleared ? -1 : given_ids.at<int>(y, x)));
      }
  }
  SECTION("a wider flank reaches farther; the near surface is never cleared") {
    fovea::ClearFlankedFarther(8, &depth);
    CHECK(cv::countNonZero(depth.colRange(0, 10)) == 30);
    CHECK(cv::countNonZero(depth.colRange(12, 18)) == 0);
    CHECK(cv::countNonZero(depth.colRange(18, 30)) == 36);
  }
  SECTION("0 leaves the image as it is") {
    fovea::ClearFlankedFarther(0, &depth, &ids);
    CHECK(cv::countNonZero(depth != given) == 0);
    CHECK(cv::countNonZero(ids != given_ids) == 0);
  }
  SECTION("a step of less than 2% of depth is a slope, not an edge") {
    depth.colRange(12, 30).setTo(1.015);
    const cv::Mat slope = depth.clone();
    fovea::ClearFlankedFarther(4, &depth);
    CHECK(cv::countNonZero(depth != slope) == 0);
  }
  SECTION("columns only: a nearer pixel above or below does not flank") {
    cv::Mat column(40, 3, CV_32F, cv::Scalar(0));
    column.rowRange(0, 10).setTo(1.0);
    column.rowRange(12, 30).setTo(2.0);
    const cv::Mat before = column.clone();
    fovea::ClearFlankedFarther(4, &column);
    CHECK(cv::countNonZero(column != before) == 0);
  }
}
