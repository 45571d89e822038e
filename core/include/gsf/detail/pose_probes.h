// Internal (gsf/detail): a pipeline stage or building block, not part of the stable interface; it may
// change between versions.
// Wrong poses near an answer, to compare the answer against: moved along its own axes, or turned about
// the sensor. The confidence (confidence.h) and the per-scan disagree weights (disagree_weights.h) probe
// with them.
#pragma once
#include <Eigen/Geometry>

#include "gsf/detail/angles.h"

namespace gsf {

// T moved `forward` and `left` metres in its own (scan) frame.
inline Eigen::Isometry3d shifted_pose(const Eigen::Isometry3d& T, double forward, double left) {
  Eigen::Isometry3d c = T;
  c.translation() += T.linear() * Eigen::Vector3d(forward, left, 0.0);
  return c;
}

// T turned by `deg` about the sensor (map_T_scan * Rz keeps the scan origin where it is).
inline Eigen::Isometry3d turned_pose(const Eigen::Isometry3d& T, double deg) {
  Eigen::Isometry3d c = T;
  c.linear() = T.linear() * Eigen::AngleAxisd(deg_to_rad(deg), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return c;
}

}  // namespace gsf
