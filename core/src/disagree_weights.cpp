#include "gsf/detail/disagree_weights.h"

#include <algorithm>
#include <cmath>

#include "gsf/detail/pose_probes.h"

namespace gsf {

DisagreeWeights estimate_disagree_weights(const VerdictCounts& best, const VerdictCounts& competitors,
                                          float disagree_weight) {
  auto total = [](const VerdictCounts& c) { return double(c.agree) + c.other_class + c.contradicted + 3.0; };
  const double tp = total(best), tq = total(competitors);
  auto log_ratio = [&](uint32_t p, uint32_t q) { return std::log(((p + 1.0) / tp) / ((q + 1.0) / tq)); };
  const double l_contradicted = log_ratio(best.contradicted, competitors.contradicted);
  if (!(l_contradicted < -kMinSeparation)) return DisagreeWeights(disagree_weight);
  const double l_other = log_ratio(best.other_class, competitors.other_class);
  const double w = std::min<double>(disagree_weight, std::max(0.0, disagree_weight * l_other / l_contradicted));
  return DisagreeWeights(disagree_weight, static_cast<float>(w));
}

DisagreeWeights scan_disagree_weights(const VerifyPoint* points, uint32_t n, const SemanticGridView& grid,
                                      const Eigen::Isometry3d& best, const Eigen::Isometry3d* competitors,
                                      uint32_t count, uint32_t max_points, float disagree_weight) {
  const VerdictCounts at_best = count_verdicts(points, n, grid, best, max_points);
  VerdictCounts pooled;
  auto add = [&](const Eigen::Isometry3d& T) {
    const VerdictCounts c = count_verdicts(points, n, grid, T, max_points);
    pooled.agree += c.agree;
    pooled.other_class += c.other_class;
    pooled.contradicted += c.contradicted;
  };
  for (uint32_t k = 0; k < count; ++k) add(competitors[k]);
  if (count == 0) {
    for (double d : {kProbeShiftM, -kProbeShiftM}) {
      add(shifted_pose(best, d, 0.0));
      add(shifted_pose(best, 0.0, d));
    }
    add(turned_pose(best, 180.0));
  }
  return estimate_disagree_weights(at_best, pooled, disagree_weight);
}

}  // namespace gsf
