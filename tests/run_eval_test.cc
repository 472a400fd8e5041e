// Ground-truth scoring's reference view.
#include "experiments/scoring/run_eval.h"

#include <catch2/catch.hpp>

#include "scenes/catalog.h"

TEST_CASE("reference view: the strip past a near left edge is out of every right camera's sight",
          "[experiments][scoring][slow]") {
  auto sim = scenes::LoadScene("three_surfaces", {});
  const experiments::ReferenceView ref = experiments::MakeReferenceView(sim->rig(), *sim);
  REQUIRE(ref.textured_pixels > 0);
  CHECK(cv::countNonZero(ref.stereo_visible & ~ref.textured) == 0);
  const double share = double(ref.stereo_visible_pixels) / ref.textured_pixels;
  INFO("stereo-visible share " << share);
  CHECK(share > 0.85);  // measured 0.936
  CHECK(share < 0.97);

  // Along a row through the left block: the plywood right before the block's
  // first pixel lies in the strip (the home pose's left camera is 5 cm left
  // of the nearest right camera: tens of pixels at 0.5 m against 1.2 m), the
  // plywood at the image's left edge and the block itself do not.
  int block = -1;
  for (int id = 0; id < 64 && block < 0; ++id)
    if (sim->truth().GeomName(id) == "block_1") block = id;
  REQUIRE(block >= 0);
  const int y = ref.geom_ids.rows * 3 / 4;
  int edge = -1;
  for (int x = 0; x < ref.geom_ids.cols && edge < 0; ++x)
    if (ref.geom_ids.at<int>(y, x) == block) edge = x;
  REQUIRE(edge > 30);
  CHECK(ref.stereo_visible.at<uchar>(y, edge - 3) == 0);
  CHECK(ref.stereo_visible.at<uchar>(y, edge - 15) == 0);
  CHECK(ref.stereo_visible.at<uchar>(y, 5) == 255);
  CHECK(ref.stereo_visible.at<uchar>(y, edge + 5) == 255);
}

TEST_CASE("reference view: with no near edge to hide behind, every textured pixel is in sight",
          "[experiments][scoring][slow]") {
  auto sim = scenes::LoadScene("fronto_planes", {});
  const experiments::ReferenceView ref = experiments::MakeReferenceView(sim->rig(), *sim);
  REQUIRE(ref.textured_pixels > 0);
  CHECK(ref.stereo_visible_pixels >= 0.99 * ref.textured_pixels);
}
