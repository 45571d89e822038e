// Internal (gsf/detail): a pipeline stage or building block, not part of the stable interface; it may
// change between versions.
// How far apart two poses are in the bird's-eye view whole-scan verification sees (horizontal
// translation and heading): one answer or two (hypothesis twins, window candidates, tracking's start).
#pragma once
#include <cmath>

#include <Eigen/Geometry>

#include "gsf/detail/angles.h"

namespace gsf {

// The heading (yaw about z) of a pose's rotation.
inline double yaw_of(const Eigen::Isometry3d& T) { return std::atan2(T.linear()(1, 0), T.linear()(0, 0)); }

// a and b within max_m metres horizontally and max_rad radians of heading (wrapped to [0, pi]).
inline bool within_pose(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, double max_m, double max_rad) {
  const double dx = b.translation().x() - a.translation().x(), dy = b.translation().y() - a.translation().y();
  double dyaw = std::fabs(yaw_of(b) - yaw_of(a));
  if (dyaw > kPi) dyaw = 2.0 * kPi - dyaw;
  return std::sqrt(dx * dx + dy * dy) <= max_m && dyaw <= max_rad;
}

}  // namespace gsf
