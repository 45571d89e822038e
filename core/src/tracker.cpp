#include "gsf/detail/tracker.h"
#include "gsf/detail/angles.h"
#include "gsf/detail/pose_distance.h"

#include <algorithm>
#include <cmath>
#include "gsf/config.h"

namespace gsf {

// The one-shot model of 2026-11's rival and shift factors, and a turn factor fitted on tracking attempts
// (2026-12-06, bench/fit_tracking.py; see tracker.h).
const TrackingConfidenceModel kTrackingConfidenceModel = {-1.817f, 3.540f, 3.391f, 1.827f, -9.125f, 3.790f};

double tracking_probability(const ConfidenceEvidence& e) {
  if (e.samples == 0) return 0.0;
  const TrackingConfidenceModel& m = kTrackingConfidenceModel;
  return z_factor(m.rival_offset, m.rival_slope, e.z_rival) * z_factor(m.shift_offset, m.shift_slope, e.z_shift) *
         z_factor(m.turn_offset, m.turn_slope, e.z_turn);
}

namespace {

// ICP from `start`; true with the accepted result in *refined.
bool icp_from(Refiner* refiner, const TrackScan& scan, const Eigen::Isometry3d& start, const TrackConfig& tc,
              Eigen::Isometry3d* refined) {
  RefineStats rs;
  return refiner != nullptr &&
         refiner->refine(scan.voxels, start, refined, &rs, tc.icp_points, tc.icp_iterations) == Status::Ok &&
         rs.accepted;
}

bool within_icp_start(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, const TrackConfig& tc) {
  return within_pose(a, b, tc.icp_start_m, double(tc.icp_start_deg) / kDegPerRad);
}

// What the pattern search can reach from the prediction, in first steps: its steps halve each round and
// a round moves at most kPatternSearchPassesPerRound steps along each axis and in heading, so it moves at
// most passes x step x (2 - 2^(1 - rounds)) along each: 3.75 m and 7.5 deg by default. (Before
// 2026-12-06 this left out the passes and bounded a tracked pose at half the search's reach, 1.875 m.)
double search_reach(const TrackConfig& tc) {
  return double(kPatternSearchPassesPerRound) * (2.0 - std::ldexp(1.0, 1 - int(tc.search_rounds)));
}

// Step 0's bound: ICP from the prediction is taken without a search when it ends within one pass of the
// search's reach of the prediction (1.875 m / 3.75 deg), where ICP alone converges well. Farther (up
// to the whole reach), ICP from the prediction ended 0.3-0.8 m and 1-2.5 deg off on 5 of 1,023 scans
// at odometry noise 0.3 (bench/track_ab.sh), and the search then starts ICP nearer the truth.
bool within_one_pass_of_prediction(const Eigen::Isometry3d& pose, const Eigen::Isometry3d& predicted,
                                   const TrackConfig& tc) {
  const double reach = search_reach(tc) / double(kPatternSearchPassesPerRound);
  return within_pose(pose, predicted, reach * tc.search_step_m, reach * double(tc.search_step_deg) / kDegPerRad);
}

// Within the search's reach of the prediction in position alone (a right pose under a poor odometry can
// end further in heading: ICP turns it on where the search stopped).
bool within_search_reach_m(const Eigen::Isometry3d& pose, const Eigen::Isometry3d& predicted, const TrackConfig& tc) {
  return (pose.translation() - predicted.translation()).norm() <= search_reach(tc) * tc.search_step_m;
}

}  // namespace

TrackOutcome track_pose(const TrackScan& scan, const SemanticGridView& grid, const Eigen::Isometry3d& predicted,
                        const TrackConfig& tc, const VerifyConfig& vc, double min_probability, Refiner* refiner,
                        AnswerConfidence& confidence, Clock* clock) {
  TrackOutcome o;
  uint64_t t = clock ? clock->now_ns() : 0;
  auto lap = [&](uint64_t* ns) {
    const uint64_t n = clock ? clock->now_ns() : 0;
    *ns += n - t;
    t = n;
  };
  const float lambda = vc.disagree_weight;
  const uint32_t probe_points = tc.probe_points > 0 ? std::min(tc.probe_points, vc.max_points) : vc.max_points;
  auto probe = [&](const Eigen::Isometry3d& pose) {
    const AnswerConfidence::Answer a{pose, nullptr, 0, 0, 0.0f, /*flip_only_if_ahead=*/true};
    o.evidence = confidence.measure(scan.points, scan.n, grid, scan.weights, lambda, a, probe_points);
    o.confidence = tracking_probability(o.evidence);
    lap(&o.probe_ns);
  };
  // 0. A good prediction needs no search: ICP from it, and when ICP ends within one pass of the search's
  // reach of it and the probes vouch for the result, that is the answer.
  Eigen::Isometry3d refined;
  const bool icp_ok = icp_from(refiner, scan, predicted, tc, &refined);
  const bool icp_first = icp_ok && within_one_pass_of_prediction(refined, predicted, tc);
  lap(&o.refine_ns);
  if (icp_first) {
    probe(refined);
    if (o.confidence >= min_probability) {
      o.map_T_scan = refined;
      o.refined = true;
      return o;
    }
  }
  // 1. Pattern search of the verification score around the prediction (coarse rounds on a sample).
  Eigen::Isometry3d searched = predicted;
  verify_pose_refined(scan.points, scan.n, grid, predicted, vc.max_points, scan.weights, tc.search_rounds,
                      tc.search_step_m, tc.search_step_deg, &searched, vc.search_divisor, vc.polish_divisor, nullptr,
                      lambda, scan.memo);
  o.map_T_scan = searched;
  lap(&o.search_ns);
  // 2. ICP for the last decimetres. The score is flat within a semantic cell, so the search wanders in
  // it: when it ends near the prediction, ICP starts from the prediction (step 0 already ran it).
  const bool reuse_step0 = within_icp_start(searched, predicted, tc);
  if (reuse_step0 ? icp_ok : icp_from(refiner, scan, searched, tc, &refined)) {
    o.map_T_scan = refined;
    o.refined = true;
  }
  lap(&o.refine_ns);
  // 3. The probes at the result: is it a peak in position and heading?
  if (!(icp_first && reuse_step0)) probe(o.map_T_scan);  // else step 0 probed this very pose
  // Tracking refines near the prediction: a result beyond the search's reach of it in position (ICP slid
  // on from the searched pose) says the prediction was not near the truth, whatever the probes there say
  // (on ARM64 a tiny-world prediction turned 180 deg slid 4.5 m to a pose the flipped scan fits, at
  // confidence 0.99: tests/test_tracker.cpp). A loss then; one-shot answers instead.
  if (!within_search_reach_m(o.map_T_scan, predicted, tc)) o.confidence = 0.0;
  return o;
}

}  // namespace gsf
