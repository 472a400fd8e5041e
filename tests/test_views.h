// Test helper: an ideal camera at the world origin looking along +Y (X right,
// Z up), principal point at the image centre.
#pragma once

#include "rig/types.h"

inline rig::CameraView ForwardView(int width_px, int height_px, double f_px) {
  rig::CameraView v;
  v.intrinsics.width_px = width_px;
  v.intrinsics.height_px = height_px;
  v.intrinsics.fx_px = v.intrinsics.fy_px = f_px;
  v.intrinsics.cx_px = 0.5 * (width_px - 1);
  v.intrinsics.cy_px = 0.5 * (height_px - 1);
  v.world_T_camera = Eigen::Isometry3d::Identity();
  v.world_T_camera.linear() << 1, 0, 0, 0, 0, 1, 0, -1, 0;
  return v;
}
