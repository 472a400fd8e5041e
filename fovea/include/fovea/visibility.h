// Whether the reference camera sees what a patch measured (beyond the paper).
//
// A fixation's cameras stand centimetres away from the reference view's (the
// left camera at the home pose, where the map is read). Past a nearer
// surface's edge they see parts of a farther surface that the reference
// view cannot: those patches are true in 3D, but wherever the nearer
// surface is not mapped (the strip erosion and the block fits leave along
// its edge, or a whole surface no fixation has visited yet) they show
// through in the reference view with the farther depth. Geometry cannot
// tell them apart while the nearer surface is missing from the map; the
// reference camera's image can: sampled on the patch's plane, it shows the
// patch's texture only if it sees the patch.
#pragma once

#include <cstdint>
#include <vector>

#include "fovea/patch.h"
#include "rig/types.h"

namespace fovea {

struct ReferenceCheckOptions {
  /// A quarter of a patch is hidden from the reference view when the
  /// normalized cross-correlation between its texture in the image it was
  /// measured in and in the reference image (both sampled at the same points
  /// of its plane) is below this. 0: no check.
  double min_ncc = 0;
  /// A quarter whose samples vary less than this (standard deviation, grey
  /// levels) in both images cannot be judged and passes. Where only the
  /// reference image's vary, the reference camera sees another surface (a
  /// faint farther one hidden behind a textured nearer one) and the quarter
  /// is judged.
  double min_texture_dn = 4;
  /// Beyond the quarters: the samples of each half across the patch (its
  /// left and its right column of quarters) and of the whole patch, pooled,
  /// are judged alike where they vary by at least `pooled_min_texture_dn`
  /// and number at least kMinPooledSamples: all the group's quarters are
  /// hidden when their normalized cross-correlation is below this. A faint
  /// texture (sensor noise a large part of its variation) leaves each
  /// quarter's few samples unjudged, and the occluded strip beside a box
  /// goes unnoticed; pooled, the samples judge it. 0: quarters only.
  double pooled_min_ncc = 0;
  double pooled_min_texture_dn = 3;
  static constexpr int kMinPooledSamples = 32;
  /// Beyond the quarters: the strips along each side of a patch, this many
  /// pixels of the measuring image wide (two per side, one inside the
  /// other), are judged like a quarter; the outer strip, or both, that the
  /// reference camera does not see are cut from the patch's part in the
  /// reference view (Patch::reference_part). A quarter is too coarse for
  /// the few pixels of a farther surface beside a nearer one's edge. 0: no
  /// strips.
  double side_px = 0;
  /// Samples a strip needs to be judged.
  static constexpr int kMinSideSamples = 12;
};

/// What the reference camera sees of one patch (JudgeReference).
struct ReferenceSight {
  std::uint8_t hidden_quarters = 0;  ///< as HiddenQuarters
  Patch::Part part;                  ///< the part its side strips leave
};

/// Per patch of `patches` (in order), its hidden quarters (HiddenQuarters)
/// and, with ReferenceCheckOptions::side_px, the part of it left once the
/// side strips the reference camera does not see are cut off, from one set
/// of samples. Cost: O(samples).
std::vector<ReferenceSight> JudgeReference(const PatchMap& patches, const rig::CameraView& measured,
                                           const rig::CameraView& reference,
                                           const ReferenceCheckOptions& options);

/// Per patch of `patches` (in order), a bit per quarter (bit 2 v + u for
/// the quarter u, v in {0, 1} across and down its corners' order) set where
/// the reference camera `reference` does not see that quarter by
/// ReferenceCheckOptions, its texture sampled on the patch's plane in
/// `measured` (the image its footprint was matched in) and in `reference`.
/// A quarter is judged where at least 3/4 of its samples fall inside both
/// images, else it passes; then the pooled groups (pooled_min_ncc). Samples
/// per patch: its size in `measured` in pixels, squared (4 to 32 per side).
/// Cost: O(samples).
std::vector<std::uint8_t> HiddenQuarters(const PatchMap& patches, const rig::CameraView& measured,
                                         const rig::CameraView& reference,
                                         const ReferenceCheckOptions& options);

/// Whether the quarters HiddenQuarters marks make a patch hidden: its left
/// or its right half, or three quarters or more. The cameras move along the
/// rail, so the reference view loses sight of a surface past a nearer
/// one's edge across it, beside an edge that runs up and down the image; a
/// lone quarter, or a top or bottom half, is a texture that decorrelates
/// (a grazing surface's fine stripes under a slightly wrong plane, noise on
/// a faint texture) rather than an occluder.
bool HiddenSide(std::uint8_t quarters);

/// Sets Patch::hidden_in_reference on the patches HiddenSide judges hidden
/// by HiddenQuarters or whose every side is cut (an empty
/// Patch::reference_part), and Patch::reference_part on every patch
/// (JudgeReference); returns how many are hidden.
int MarkHiddenFromReference(PatchMap* patches, const rig::CameraView& measured,
                            const rig::CameraView& reference, const ReferenceCheckOptions& options);

/// The map as the reference view shows it: its patches but those the
/// reference camera does not see (Patch::hidden_in_reference), each cut to
/// its Patch::reference_part.
PatchMap ReferenceMap(const PatchMap& map);

/// Leaves out of a depth image of a map (0: unmapped) each pixel with a
/// mapped pixel more than 2% nearer (kFlankNearerShare) within `flank_px`
/// along its row, either side; `ids`, if given (the patch ids of the same
/// render), gets -1 there. The reading rule of the map's depth in the
/// reference view (IntegrationOptions::reference_flank_px): where a nearer
/// surface's edge is left unmapped (the strips ReferenceSides cuts, the
/// blocks whose fit fails across the step), a farther surface's patch
/// measured from another viewpoint shows through it, far off the true depth;
/// its pixels beside the nearer mapped one are the ones left out. The rig
/// moves along its rail, so those strips run up and down the image: the
/// rule reads along rows. Every pixel is judged against the image as given.
/// flank_px <= 0 leaves the image as it is. Cost: O(pixels x flank_px).
void ClearFlankedFarther(int flank_px, cv::Mat* depth, cv::Mat* ids = nullptr);

/// How much nearer a flanking pixel must be, a share of the pixel's depth:
/// a step between surfaces, not a slanted surface's own slope over a few
/// pixels.
constexpr double kFlankNearerShare = 0.02;

}  // namespace fovea
