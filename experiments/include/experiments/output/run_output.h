// Pictures and files of a FOVEA run: the patch map as PLY, an oblique 3D view
// of the patches, the map's depth in the reference view, the fixation path.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "experiments/scoring/run_eval.h"
#include "fovea/patch.h"

namespace experiments {

/// BGR colour of a patch level: IDR grey, peripheral blue, foveal orange.
cv::Scalar LevelColor(fovea::PatchLevel level);

/// The map as an ASCII PLY mesh (a quad per patch, vertex colours by level).
std::string PatchMapPly(const fovea::PatchMap& map);

/// The patches rendered from an oblique virtual camera that looks at
/// `target_W` from the front left and above, shaded by their normals and
/// coloured by level.
cv::Mat ObliqueView(const fovea::PatchMap& map, const Eigen::Vector3d& target_W, int width_px,
                    int height_px);

/// The map's depth seen by `view` beside the true depth there, one colour
/// scale (the true depth's range).
cv::Mat PatchDepthBesideTruth(const fovea::PatchMap& map, const rig::CameraView& view,
                              const sim::GroundTruth& truth);

/// The map after a fixation as the paper shows it: the oblique view, the
/// map's depth in the reference view (read with `flank_px`,
/// RenderInReference) and the true depth (same colours), with a caption.
cv::Mat MapSnapshot(const fovea::PatchMap& map, int flank_px, const ReferenceView& ref,
                    const Eigen::Vector3d& target_W, const std::string& caption);

/// The reference image with the fixation points, numbered and joined in
/// order (refused points as crosses).
cv::Mat FixationPath(const ReferenceView& ref, const std::vector<Eigen::Vector3d>& fixations_W,
                     const std::vector<Eigen::Vector3d>& refused_W);

}  // namespace experiments
