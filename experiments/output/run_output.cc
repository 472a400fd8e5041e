#include "experiments/output/run_output.h"

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "experiments/output/output.h"
#include "fovea/geometry.h"

namespace experiments {

cv::Scalar LevelColor(fovea::PatchLevel level) {
  switch (level) {
    case fovea::PatchLevel::kIdr:
      return {170, 170, 170};
    case fovea::PatchLevel::kPeripheral:
      return {230, 130, 50};
    case fovea::PatchLevel::kFoveal:
      return {40, 110, 240};
  }
  return {255, 255, 255};
}

std::string PatchMapPly(const fovea::PatchMap& map) {
  std::ostringstream out;
  out << "ply\nformat ascii 1.0\ncomment FOVEA patch map: one quad per patch, colour by level "
         "(grey IDR, blue peripheral, orange foveal)\n"
      << "element vertex " << 4 * map.size()
      << "\nproperty float x\nproperty float y\nproperty float z\n"
      << "property uchar red\nproperty uchar green\nproperty uchar blue\n"
      << "element face " << map.size() << "\nproperty list uchar int vertex_indices\nend_header\n";
  char line[160];
  for (const fovea::Patch& p : map.patches()) {
    const cv::Scalar c = LevelColor(p.level);
    for (const Eigen::Vector3d& v : p.corners_W) {
      std::snprintf(line, sizeof line, "%.6f %.6f %.6f %d %d %d\n", v.x(), v.y(), v.z(), int(c[2]),
                    int(c[1]), int(c[0]));
      out << line;
    }
  }
  for (size_t i = 0; i < map.size(); ++i)
    out << "4 " << 4 * i << " " << 4 * i + 1 << " " << 4 * i + 2 << " " << 4 * i + 3 << "\n";
  return out.str();
}

cv::Mat ObliqueView(const fovea::PatchMap& map, const Eigen::Vector3d& target_W, int w, int h) {
  // Eye in front of the scene, to the left and above, looking at the target.
  const double az = 40 * M_PI / 180, el = 30 * M_PI / 180;
  const double dist = 1.1 * std::max(0.5, target_W.norm());
  const Eigen::Vector3d eye =
      target_W + dist * Eigen::Vector3d(-std::sin(az) * std::cos(el), -std::cos(az) * std::cos(el),
                                        std::sin(el));
  const Eigen::Vector3d z = (target_W - eye).normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Isometry3d world_T_camera = Eigen::Isometry3d::Identity();
  world_T_camera.linear() << x, y, z;
  world_T_camera.translation() = eye;
  rig::CameraIntrinsics k;
  k.width_px = w;
  k.height_px = h;
  k.fx_px = k.fy_px = 0.5 * w / std::tan(0.5 * 40 * M_PI / 180);
  k.cx_px = 0.5 * (w - 1);
  k.cy_px = 0.5 * (h - 1);
  cv::Mat ids;
  map.Render(world_T_camera, k, nullptr, &ids);
  cv::Mat img(h, w, CV_8UC3, cv::Scalar(32, 32, 32));
  const Eigen::Vector3d light = (-z + 0.5 * Eigen::Vector3d::UnitZ() - 0.3 * x).normalized();
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) {
      const int id = ids.at<int>(v, u);
      if (id < 0) continue;
      const double shade = 0.35 + 0.65 * std::abs(map[id].Normal().dot(light));
      const cv::Scalar c = LevelColor(map[id].level);
      img.at<cv::Vec3b>(v, u) =
          cv::Vec3b(cv::saturate_cast<uchar>(c[0] * shade), cv::saturate_cast<uchar>(c[1] * shade),
                    cv::saturate_cast<uchar>(c[2] * shade));
    }
  // Patch outlines: draw the edges so that patch sizes show.
  for (int v = 1; v < h; ++v)
    for (int u = 1; u < w; ++u) {
      const int id = ids.at<int>(v, u);
      if (id >= 0 && (id != ids.at<int>(v - 1, u) || id != ids.at<int>(v, u - 1)))
        img.at<cv::Vec3b>(v, u) = img.at<cv::Vec3b>(v, u) * 0.6;
    }
  return img;
}

cv::Mat PatchDepthBesideTruth(const fovea::PatchMap& map, const rig::CameraView& view,
                              const sim::GroundTruth& truth) {
  cv::Mat patch_depth;
  map.Render(view.world_T_camera, view.intrinsics, &patch_depth, nullptr);
  const sim::TrueView true_view = truth.Render(view.world_T_camera, view.intrinsics);
  double lo = 0, hi = 0;
  cv::minMaxLoc(true_view.depth_m, &lo, &hi, nullptr, nullptr, true_view.depth_m > 0);
  cv::Mat side;
  cv::hconcat(ColorizeDepth(patch_depth, lo, hi), ColorizeDepth(true_view.depth_m, lo, hi), side);
  return side;
}

// The map's depth against the truth, pixel by pixel: green within 1% of the
// true depth, yellow within 5%, red beyond; dark grey where the truth has a
// surface the map lacks; magenta where the map has depth and the truth none.
cv::Mat ErrorPanel(const cv::Mat& map_depth, const cv::Mat& true_depth) {
  cv::Mat img(map_depth.size(), CV_8UC3, cv::Scalar(0, 0, 0));
  for (int v = 0; v < img.rows; ++v)
    for (int u = 0; u < img.cols; ++u) {
      const float z = map_depth.at<float>(v, u), t = true_depth.at<float>(v, u);
      cv::Vec3b& px = img.at<cv::Vec3b>(v, u);
      if (t <= 0) {
        if (z > 0) px = {255, 0, 255};
      } else if (z <= 0) {
        px = {48, 48, 48};
      } else {
        const float rel = std::abs(z - t) / t;
        px = rel <= 0.01f   ? cv::Vec3b(0, 170, 0)
             : rel <= 0.05f ? cv::Vec3b(0, 220, 255)
                            : cv::Vec3b(0, 0, 255);
      }
    }
  return img;
}

cv::Mat MapSnapshot(const fovea::PatchMap& map, int flank_px, const ReferenceView& ref,
                    const Eigen::Vector3d& target_W, const std::string& caption) {
  const int w = ref.view.intrinsics.width_px, h = ref.view.intrinsics.height_px;
  cv::Mat depth;
  RenderInReference(map, flank_px, ref, &depth);
  double lo = 0, hi = 0;
  cv::minMaxLoc(ref.depth_m, &lo, &hi, nullptr, nullptr, ref.depth_m > 0);
  cv::Mat row;
  cv::hconcat(
      std::vector<cv::Mat>{ObliqueView(map, target_W, w, h), ColorizeDepth(depth, lo, hi),
                           ColorizeDepth(ref.depth_m, lo, hi), ErrorPanel(depth, ref.depth_m)},
      row);
  cv::Mat out(row.rows + 28, row.cols, CV_8UC3, cv::Scalar(255, 255, 255));
  row.copyTo(out(cv::Rect(0, 28, row.cols, row.rows)));
  cv::putText(out, caption, {8, 20}, cv::FONT_HERSHEY_SIMPLEX, 0.6, {0, 0, 0}, 1, cv::LINE_AA);
  const char* labels[4] = {"patches, oblique view (grey IDR, blue peripheral, orange foveal)",
                           "map depth, reference view", "true depth",
                           "error: green <1%, yellow <5%, red more, grey unmapped"};
  for (int i = 0; i < 4; ++i)
    cv::putText(out, labels[i], {i * w + 8, 28 + h - 10}, cv::FONT_HERSHEY_SIMPLEX, 0.45,
                {255, 255, 255}, 1, cv::LINE_AA);
  return out;
}

cv::Mat FixationPath(const ReferenceView& ref, const std::vector<Eigen::Vector3d>& fixations_W,
                     const std::vector<Eigen::Vector3d>& refused_W) {
  cv::Mat img;
  cv::cvtColor(ref.view.gray, img, cv::COLOR_GRAY2BGR);
  auto project = [&](const Eigen::Vector3d& p) -> std::optional<cv::Point> {
    const auto uv = fovea::ProjectWorldPoint(ref.view.world_T_camera, ref.view.intrinsics, p);
    if (!uv) return std::nullopt;
    return cv::Point(static_cast<int>(std::lround(uv->x())),
                     static_cast<int>(std::lround(uv->y())));
  };
  std::optional<cv::Point> prev;
  const int n = static_cast<int>(fixations_W.size());
  for (int i = 0; i < n; ++i) {
    const auto p = project(fixations_W[i]);
    if (!p) continue;
    cv::Mat t(1, 1, CV_8U, cv::Scalar(n > 1 ? 255 * i / (n - 1) : 0));
    cv::Mat c;
    cv::applyColorMap(t, c, cv::COLORMAP_TURBO);
    const cv::Scalar colour(c.at<cv::Vec3b>(0, 0));
    if (prev) cv::line(img, *prev, *p, colour, 2, cv::LINE_AA);
    prev = p;
  }
  for (int i = 0; i < n; ++i) {
    const auto p = project(fixations_W[i]);
    if (!p) continue;
    cv::circle(img, *p, 5, {0, 0, 0}, cv::FILLED, cv::LINE_AA);
    cv::circle(img, *p, 4, {0, 255, 255}, cv::FILLED, cv::LINE_AA);
    cv::putText(img, std::to_string(i + 1), *p + cv::Point(6, -6), cv::FONT_HERSHEY_SIMPLEX, 0.45,
                {0, 0, 0}, 3, cv::LINE_AA);
    cv::putText(img, std::to_string(i + 1), *p + cv::Point(6, -6), cv::FONT_HERSHEY_SIMPLEX, 0.45,
                {255, 255, 255}, 1, cv::LINE_AA);
  }
  for (const Eigen::Vector3d& r : refused_W) {
    const auto p = project(r);
    if (!p) continue;
    cv::drawMarker(img, *p, {0, 0, 255}, cv::MARKER_TILTED_CROSS, 10, 2);
  }
  return img;
}

}  // namespace experiments
