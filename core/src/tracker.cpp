#include "gsf/detail/tracker.h"
#include "gsf/detail/pose_distance.h"

#include <algorithm>
#include <cmath>
#include "gsf/config.h"

namespace gsf {

// The one-shot model fitted 2026-11 (rival factor on the closest probe's z alone; see tracker.h).
const ConfidenceModel kTrackingConfidenceModel = {-1.817f,  3.540f, 0.0f,    3.391f, 1.827f,
                                                  -10.350f, 3.164f, -3.891f, 27.352f};

double tracking_probability(const ConfidenceEvidence& evidence) {
  ConfidenceEvidence e = evidence;
  e.inlier_share = 1.0f;  // the inlier factor at its ceiling (s(a_i + b_i) = 1 - 6e-11): left out
  return confidence_probability(e, kTrackingConfidenceModel);
}

TrackOutcome track_pose(const TrackScan& scan, const SemanticGridView& grid, const Eigen::Isometry3d& predicted,
                        const TrackConfig& tc, const VerifyConfig& vc, Refiner* refiner, AnswerConfidence& confidence,
                        Clock* clock) {
  TrackOutcome o;
  uint64_t t = clock ? clock->now_ns() : 0;
  auto lap = [&](uint64_t* ns) {
    const uint64_t n = clock ? clock->now_ns() : 0;
    *ns = n - t;
    t = n;
  };
  const float lambda = vc.disagree_weight;
  // 1. Pattern search of the verification score around the prediction (coarse rounds on a sample).
  Eigen::Isometry3d searched = predicted;
  o.verification = verify_pose_refined(scan.points, scan.n, grid, predicted, vc.max_points, scan.weights,
                                       tc.search_rounds, tc.search_step_m, tc.search_step_deg, &searched,
                                       vc.search_divisor, vc.polish_divisor, nullptr, lambda);
  o.map_T_scan = searched;
  lap(&o.search_ns);
  // 2. ICP for the last decimetres. The score is flat within a semantic cell, so the search wanders in
  // it: when it ends within icp_start_m / icp_start_deg of the prediction, ICP starts from the prediction.
  if (refiner != nullptr) {
    Eigen::Isometry3d refined;
    RefineStats rs;
    const Eigen::Isometry3d start =
        within_pose(searched, predicted, tc.icp_start_m, double(tc.icp_start_deg) / 57.29577951308232) ? predicted
                                                                                                       : searched;
    if (refiner->refine(scan.voxels, start, &refined, &rs, tc.icp_points, tc.icp_iterations) == Status::Ok &&
        rs.accepted) {
      o.map_T_scan = refined;
      o.refined = true;
    }
  }
  lap(&o.refine_ns);
  // 3. The probes at the result: is it a peak in position and heading?
  const AnswerConfidence::Answer a{o.map_T_scan, nullptr, 0, 0, 0.0f};
  const uint32_t probe_points = tc.probe_points > 0 ? std::min(tc.probe_points, vc.max_points) : vc.max_points;
  o.evidence = confidence.measure(scan.points, scan.n, grid, scan.weights, lambda, a, probe_points);
  o.confidence = tracking_probability(o.evidence);
  lap(&o.probe_ns);
  return o;
}

}  // namespace gsf
