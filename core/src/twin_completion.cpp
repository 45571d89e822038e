#include "gsf/detail/twin_completion.h"

#include <algorithm>
#include <cmath>

#include "gsf/detail/angles.h"
#include "gsf/detail/pose_distance.h"
#include "gsf/detail/pose_solver.h"

namespace gsf {

namespace {

// Heading difference of two poses, wrapped to [0, pi].
double heading_gap(const PlanarPose& a, const PlanarPose& b) {
  const double d = std::fabs(b.yaw - a.yaw);
  return d > kPi ? 2.0 * kPi - d : d;
}

}  // namespace

PlanarPose planar_of(const Eigen::Isometry3d& pose) {
  return PlanarPose{pose.translation().x(), pose.translation().y(), yaw_of(pose), 0};
}

uint32_t propose_twin_poses(const PlanarPose* ranked, uint32_t n, uint32_t answer, float same_pose_m,
                            float same_pose_deg, PlanarPose* out, uint32_t max_out) {
  if (ranked == nullptr || out == nullptr || answer >= n) return 0;
  const double same_rad = double(same_pose_deg) / kDegPerRad, same_m = double(same_pose_m);
  const PlanarPose& a = ranked[answer];
  double period_x[TwinLimits::kMaxPeriods], period_y[TwinLimits::kMaxPeriods];
  uint32_t periods = 0;
  uint32_t heads[TwinLimits::kMaxHeads];
  uint32_t nh = 0;
  for (uint32_t k = 0; k < n; ++k) {
    if (k == answer) continue;
    const double dx = ranked[k].x - a.x, dy = ranked[k].y - a.y;
    if (heading_gap(a, ranked[k]) <= same_rad) {
      if (std::sqrt(dx * dx + dy * dy) >= same_m && periods < TwinLimits::kMaxPeriods) {
        period_x[periods] = dx;
        period_y[periods++] = dy;
      }
    } else if (nh < TwinLimits::kMaxHeads) {
      heads[nh++] = k;
    }
  }
  if (periods == 0 || nh == 0) return 0;
  uint32_t count = 0;
  auto propose = [&](const PlanarPose& p) {
    for (uint32_t j = 0; j < count; ++j) {
      const double dx = p.x - out[j].x, dy = p.y - out[j].y;
      if (std::sqrt(dx * dx + dy * dy) <= same_m && heading_gap(p, out[j]) <= same_rad) return;
    }
    if (count < max_out) out[count++] = p;
  };
  for (uint32_t h = 0; h < nh; ++h) {
    const PlanarPose& g = ranked[heads[h]];
    propose(PlanarPose{g.x, g.y, g.yaw, heads[h]});
    for (uint32_t k = 0; k < periods; ++k)
      for (double sign : {1.0, -1.0})
        propose(PlanarPose{g.x + sign * period_x[k], g.y + sign * period_y[k], g.yaw, heads[h]});
  }
  return count;
}

InstanceBox instances_at(const float* centroids, uint32_t n, const Eigen::Isometry3d& pose, float pad,
                         float* moved_xy) {
  const Eigen::Matrix3f R = pose.linear().cast<float>();
  const Eigen::Vector3f t = pose.translation().cast<float>();
  InstanceBox box{INFINITY, INFINITY, -INFINITY, -INFINITY};
  for (uint32_t q = 0; q < n; ++q) {
    const Eigen::Vector3f p = R * Eigen::Vector3f(centroids[3 * q], centroids[3 * q + 1], centroids[3 * q + 2]) + t;
    moved_xy[2 * q] = p.x();
    moved_xy[2 * q + 1] = p.y();
    box.x0 = std::min(box.x0, p.x() - pad), box.x1 = std::max(box.x1, p.x() + pad);
    box.y0 = std::min(box.y0, p.y() - pad), box.y1 = std::max(box.y1, p.y() + pad);
  }
  return box;
}

size_t InstanceSnap::required_bytes(uint32_t max_instances) { return counted_bytes<InstanceSnap>(max_instances); }

Status InstanceSnap::bind(Arena& arena, uint32_t max_instances) {
  capacity_ = max_instances;
  moved_ = arena.allocate<float>(size_t(max_instances) * 2);
  nearest_ = arena.allocate<float>(max_instances);
  match_ = arena.allocate<int32_t>(max_instances);
  a_ = arena.allocate<float>(size_t(max_instances) * 3);
  b_ = arena.allocate<float>(size_t(max_instances) * 3);
  w_ = arena.allocate<float>(max_instances);
  return arena.overflowed() ? Status::BufferTooSmall : Status::Ok;
}

bool InstanceSnap::snap(const float* centroids, const uint8_t* labels, uint32_t n, const MapInstance* map, uint32_t m,
                        const Eigen::Isometry3d& start, float radius, uint32_t min_pairs,
                        Eigen::Isometry3d* snapped) const {
  n = std::min(n, capacity_);
  if (n == 0 || n < min_pairs || map == nullptr || m == 0 || !(radius > 0.0f) || w_ == nullptr) return false;
  Eigen::Isometry3d pose = start;
  for (uint32_t round = 0; round < kSnapRounds; ++round) {
    const float r = round == 0 ? 2.0f * radius : radius;
    // One pass over the map's instances with a box test, the nearest search only for those inside.
    const InstanceBox box = instances_at(centroids, n, pose, r, moved_);
    std::fill(nearest_, nearest_ + n, r * r);
    std::fill(match_, match_ + n, -1);
    for (uint32_t k = 0; k < m; ++k) {
      if (!box.contains(map[k].centroid)) continue;
      const float* c = map[k].centroid;
      for (uint32_t q = 0; q < n; ++q) {
        if (labels[q] != map[k].label) continue;
        const float dx = c[0] - moved_[2 * q], dy = c[1] - moved_[2 * q + 1], d = dx * dx + dy * dy;
        if (d <= nearest_[q]) {
          nearest_[q] = d;
          match_[q] = static_cast<int32_t>(k);
        }
      }
    }
    uint32_t pairs = 0;
    for (uint32_t q = 0; q < n; ++q) {
      if (match_[q] < 0) continue;
      for (int j = 0; j < 3; ++j) {
        a_[3 * pairs + j] = centroids[3 * q + j];
        b_[3 * pairs + j] = map[match_[q]].centroid[j];
      }
      w_[pairs++] = 1.0f;
    }
    if (pairs < min_pairs) return false;
    Eigen::Isometry3d fitted;
    if (fit_upright(a_, b_, w_, nullptr, pairs, &fitted) != Status::Ok || !fitted.matrix().allFinite()) return false;
    pose = fitted;
  }
  *snapped = pose;
  return true;
}

}  // namespace gsf
