// Test helper: the TAVT's kinematics as the simulator sets them up by default
// (optical centres 3 cm ahead of and 1 cm above the pan/tilt axes; carriages
// 0.5 mm to 0.3 m either side of the rail centre; pan +-60, tilt +-30 degrees).
#pragma once

#include <cmath>

#include "rig/kinematics.h"
#include "rig/types.h"

inline rig::RigGeometry TestGeometry() {
  rig::RigGeometry g;
  g.left.optical_centre_H = g.right.optical_centre_H = {0.0, 0.03, 0.01};
  return g;
}

inline rig::RigLimits TestLimits() {
  rig::RigLimits l;
  const double ang = 6400 * 180 / M_PI;
  l[rig::Axis::kLeftBaseline] = {-0.3, -0.0005, 400e3};
  l[rig::Axis::kRightBaseline] = {0.0005, 0.3, 400e3};
  for (auto a : {rig::Axis::kLeftPan, rig::Axis::kRightPan}) l[a] = {-M_PI / 3, M_PI / 3, ang};
  for (auto a : {rig::Axis::kLeftTilt, rig::Axis::kRightTilt}) l[a] = {-M_PI / 6, M_PI / 6, ang};
  return l;
}
