// Internal (gsf/detail): a pipeline stage or building block, not part of the stable interface; it may
// change between versions. The stable interface is localizer.h, config.h, map_format.h, scan.h, status.h,
// platform.h, class_table.h, georeference.h and the C API gsf.h.
// The twin a repetitive zone's hypotheses are missing (Localizer::Impl::complete_twins; docs/confidence.md,
// *The missing twin*). In a hall, lattice, row or avenue the hypotheses come in families, one per
// heading, each a row of twins displaced by the zone's period. The consistency graph holds a bounded
// number of correspondences and every copy of the zone gathers as many triangle matches as the truth, so
// the true pose's own pairs can be left out while its twins' are kept: the answer is then the best of the
// wrong heading's twins, confident against rivals that are all wrong as well (a 180-degree flip; on the
// suite's zone worlds of seeds 11-18, 5 of 7,282 one-shot queries, each 14-127 m off at 0.91-0.997).
// The scene shows where the missing pose lies: the answer's twins give the zone's periods, and the other
// headings' best hypotheses displaced by them are where their own twins would be. Each proposal is moved
// onto the map's instances (InstanceSnap) and verified like any hypothesis.
// Work: at most kMaxHeads x (1 + 2 x kMaxPeriods) proposals, each snapped (kSnapRounds passes over the map's
// instances in a box around the scan) and scored once on verify.max_points.
#pragma once
#include <cstdint>

#include <Eigen/Geometry>

#include "gsf/detail/arena.h"
#include "gsf/map_format.h"
#include "gsf/status.h"

namespace gsf {

struct TwinLimits {
  static constexpr uint32_t kMaxPeriods = 8;  // the answer's twins whose displacements are used
  static constexpr uint32_t kMaxHeads = 2;    // other headings' best hypotheses displaced by them
  static constexpr uint32_t kMaxProposals = kMaxHeads * (1 + 2 * kMaxPeriods);
  // Proposals that outscore the first answer, kept for the second choice: a missing twin and its
  // neighbours' snaps land on it or a few others.
  static constexpr uint32_t kMaxFound = 4;
};

// The scan's instances at a pose, bird's-eye (centroids: n x 3 -> moved_xy: n x 2), and the box around
// them padded by `pad`: a pass over the map's instances tests the box first (InstanceSnap and
// Localizer's inlier recount). n > 0.
struct InstanceBox {
  float x0, y0, x1, y1;
  bool contains(const float* c) const { return !(c[0] < x0 || c[0] > x1 || c[1] < y0 || c[1] > y1); }
};
InstanceBox instances_at(const float* centroids, uint32_t n, const Eigen::Isometry3d& pose, float pad, float* moved_xy);

// A bird's-eye pose (verification's view: horizontal position and heading), 32 bytes where an
// Isometry3d takes 128: the proposals live on the query's stack.
struct PlanarPose {
  double x = 0.0, y = 0.0, yaw = 0.0;  // m, m, rad
  uint32_t from = 0;                   // a proposal: the ranked pose it is moved from (its index there)
};
PlanarPose planar_of(const Eigen::Isometry3d& pose);

// Proposed poses: for each of the best kMaxHeads poses of `ranked` (best first, n of them) whose heading
// is more than same_pose_deg from the answer's (ranked[answer]), that pose and that pose moved by +- each
// displacement from the answer to a twin (a pose within same_pose_deg of its heading, at least
// same_pose_m away; at most kMaxPeriods, best first). None when the answer has no twin or no other
// heading is ranked. Proposals within same_pose_m / same_pose_deg of an earlier one are left out. Each
// carries the index of its head in `ranked` (PlanarPose::from): the caller moves that pose's own
// transform to the proposal's x and y. Returns how many were written to out (at most max_out).
uint32_t propose_twin_poses(const PlanarPose* ranked, uint32_t n, uint32_t answer, float same_pose_m,
                            float same_pose_deg, PlanarPose* out, uint32_t max_out);

// Moves a pose onto the map's instances: each scan instance is paired with the nearest map instance of
// its label (bird's-eye) within a radius, the pose refitted upright on the pairs (yaw and translation,
// pose_solver.h's fit_upright), kSnapRounds times, the first at twice the radius. A proposal 1-2 m and a
// few degrees off its twin comes to it; scan instances with no map instance near fit nothing.
class InstanceSnap {
 public:
  static constexpr uint32_t kSnapRounds = 3;
  static size_t required_bytes(uint32_t max_instances);
  Status bind(Arena& arena, uint32_t max_instances);
  // centroids: n x 3 scan instance centroids, labels: n; map: m instances. False when fewer than
  // min_pairs pairs are found in a round, or the fit fails; *snapped is set only on success.
  bool snap(const float* centroids, const uint8_t* labels, uint32_t n, const MapInstance* map, uint32_t m,
            const Eigen::Isometry3d& start, float radius, uint32_t min_pairs, Eigen::Isometry3d* snapped) const;

 private:
  float* moved_ = nullptr;    // I x 2: scan centroids at the pose
  float* nearest_ = nullptr;  // I: squared distance to the nearest map instance of the label so far
  int32_t* match_ = nullptr;  // I: that map instance (-1: none)
  float* a_ = nullptr;        // I x 3: paired scan centroids
  float* b_ = nullptr;        // I x 3: their map instances' centroids
  float* w_ = nullptr;        // I: unit weights
  uint32_t capacity_ = 0;
};

}  // namespace gsf
