// Internal (gsf/detail): a pipeline stage or building block, not part of the stable interface; it may
// change between versions.
// What an above-ground voxel on a cell of another above-ground class costs in this scan's verification
// (DisagreeWeights::other_class), estimated from the scan and the map themselves.
//
// Such a voxel is either at a wrong pose or wrongly labelled (the scan's network confused it, or the
// map's). Under little label noise it is nearly as strong a sign of a wrong pose as a voxel in space the
// map saw empty; when whole objects take the wrong class it is common at the true pose too, and the full
// penalty then throws away the one thing that tells a repeated place from its twin: that the true pose
// puts the scan's objects where the map has objects. So the penalty is a log-likelihood ratio measured
// on this scan: with rates over the above-ground voxels on observed cells (counted with one extra of
// each verdict, so no rate is 0),
//   other_class = contradicted x log(p_other / q_other) / log(p_contradicted / q_contradicted),
// p at the best pose after the coarse pass, q pooled over its competitors (the best coarse hypotheses at
// another place or heading; without any, the probes 8 m along each axis and turned 180 deg), clipped to
// [0, contradicted]. The competitors, not generic probes, are what the best pose must be told apart
// from: at a mirror-image twin the voxels land on the other side's objects (other class: the ratio is
// large and the full penalty stays); at a lattice shift they land on the same repeated objects at both
// (the ratio is near 1 and the penalty falls). When the best pose is not told apart from its competitors
// even by contradictions (log p_c / q_c > -kMinSeparation) there is nothing to measure against, and the
// full penalty stays.
#pragma once
#include <cstdint>

#include <Eigen/Geometry>

#include "gsf/detail/semantic_grid.h"

namespace gsf {

constexpr double kMinSeparation = 0.3;  // log-rate of contradictions, best pose over its competitors
constexpr double kProbeShiftM = 8.0;    // the fallback probes' shift

// The weights from counts at the best pose and pooled over its competitors; disagree_weight: the
// configured penalty (VerifyConfig::disagree_weight), kept for contradictions.
DisagreeWeights estimate_disagree_weights(const VerdictCounts& best, const VerdictCounts& competitors,
                                          float disagree_weight);

// The same, counting over the strided sample of the n compact points verification scores (max_points):
// at `best` and at competitors[0, count) (the probes when count is 0).
DisagreeWeights scan_disagree_weights(const VerifyPoint* points, uint32_t n, const SemanticGridView& grid,
                                      const Eigen::Isometry3d& best, const Eigen::Isometry3d* competitors,
                                      uint32_t count, uint32_t max_points, float disagree_weight);

}  // namespace gsf
