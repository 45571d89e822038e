// Evaluation metrics as in Outram's evaluation code and the paper's Tables II and IV: success means
// translation error < 5 m and rotation error < 10 deg, with errors from dT = T_est^-1 * T_gt; ATE/ARE are
// means over successes; times are per query. A query is *answered* (acted on) under the library's decision
// rule: status Ok and LocalizeResult::confident (confidence >= config.confidence.min_probability). From
// that: precision (right among answered), share answered, wrong answers and declined right ones; the
// precision curve swept over confidence thresholds; and the confidence's calibration (reliability bins,
// expected calibration error, Brier score).
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "gsf/localizer.h"

namespace gsf::cli {

struct PoseError {
  double translation_m = 0;
  double rotation_deg = 0;
};
PoseError pose_error(const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& ground_truth);

constexpr double kSuccessTranslation = 5.0;
constexpr double kSuccessRotationDeg = 10.0;
inline bool is_success(const PoseError& e) {
  return e.translation_m < kSuccessTranslation && e.rotation_deg < kSuccessRotationDeg;
}

struct StageMs {  // per-stage wall time of one query, milliseconds
  double voxel = 0, cluster = 0, field = 0, triangle = 0, match = 0, gsf = 0, clique = 0, pose = 0, confidence = 0,
         refine = 0;
};

struct QueryRecord {
  uint32_t index = 0;      // position in the query sequence
  uint32_t frame = 0;      // file number
  std::string status;      // gsf::to_string of the localize status
  bool has_pose = false;   // status Ok: a pose came back (judged for success whether answered or not)
  bool answered = false;   // the decision rule: has_pose and confident (the caller would act on the pose)
  bool success = false;    // has_pose and the pose is right (t < 5 m, r < 10 deg)
  bool in_zone = false;    // in the simulator's repetitive zone
  bool near_zone = false;  // within 60 m of it (not inside)
  PoseError error;
  double time_ms = 0;
  StageMs stages;
  double confidence = 0.0;  // the localizer's probability that the pose is right; 0 without a pose
  uint32_t inliers = 0;
  // Poses in the dataset's frame (= the map's frame, georeference.h): errors are measured there.
  Eigen::Isometry3d estimate = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d truth = Eigen::Isometry3d::Identity();
  // The truth in the map-local frame (relative to the map origin), where the map's own coordinates are:
  // for the diagnostics that compare with map instances, hypotheses and the pictures.
  Eigen::Isometry3d truth_local = Eigen::Isometry3d::Identity();
  LocalizeResult result;                     // the library's own counts for this query (diagnostics)
  uint32_t repeatable_instances = 0;         // query instances with a same-label map instance < 2 m under the truth
  uint32_t answer_repeatable_instances = 0;  // the same under the answer's pose (0 without a pose)
  uint32_t answer_layer_instances = 0;       // under the answer, on (or beside) a layer cell holding their class
  uint32_t true_correspondences = 0;         // selected correspondences the ground truth agrees with (< 2 m)
  double truth_verified_score = 0;           // the ground-truth pose's whole-scan verification score
  // Of the sampled voxels at the ground-truth pose, the share on cells the map's semantic layer holds:
  // near 0 when the vehicle is outside the map (every answer is then wrong, however good it looks).
  double truth_known_share = 0;
  // Per true correspondence: its GSF weight (best omega) and its query instance's range in m (the gate's
  // evidence, bench/true_pair_omega.py).
  std::vector<std::array<float, 2>> true_pairs;
};

struct CurvePoint {
  double threshold;  // answer only if the query has a pose and confidence >= threshold
  double answered;   // share of all queries answered
  double precision;  // successes among answered (1 when none is answered)
};

// Reliability of the confidence: kReliabilityBins equal bins [0,0.1) ... [0.9,1.0] over ALL queries, a
// query without a pose counting as confidence 0 and a failure (the caller gets no pose to act on).
constexpr int kReliabilityBins = 10;
struct ReliabilityBin {
  double lo = 0, hi = 0;
  uint32_t count = 0;
  double mean_confidence = 0;  // NaN (JSON null) for an empty bin
  double success_rate = 0;     // observed; NaN for an empty bin
};
struct Calibration {
  std::array<ReliabilityBin, kReliabilityBins> bins;
  uint32_t queries = 0;
  double ece = 0;    // expected calibration error: sum over bins of count/N * |success_rate - mean_confidence|
  double brier = 0;  // mean over queries of (confidence - success)^2
};
struct Outcome {
  double confidence;  // 0 without a pose
  bool success;
};
// The bin of a confidence: the largest k with confidence >= k / 10 (0 below 0.1, 9 from 0.9 up).
int reliability_bin(double confidence);
Calibration calibrate(const std::vector<Outcome>& outcomes);

// The decision rule's outcome over a set of queries.
struct RuleOutcome {
  uint32_t answered = 0;        // has a pose and confident
  uint32_t wrong = 0;           // answered, not a success ("confident and wrong")
  uint32_t declined_right = 0;  // a success, not answered ("not confident but right")
  double answered_share = 0;    // answered / queries
  double precision = 1;         // (answered - wrong) / answered; 1 when none is answered
};
RuleOutcome rule_outcome(const std::vector<QueryRecord>& records);

struct ModeSummary {
  std::string mode;
  uint32_t queries = 0, with_pose = 0, successes = 0;
  double success_rate = 0;  // successes / queries
  uint32_t zone_queries = 0, zone_successes = 0;
  double zone_success_rate = 0;
  uint32_t near_zone_queries = 0, near_zone_successes = 0;  // near the zone, not inside
  double near_zone_success_rate = 0;
  uint32_t elsewhere_queries = 0, elsewhere_successes = 0;  // neither in nor near the zone
  double elsewhere_success_rate = 0;
  double ate_m = 0, are_deg = 0;  // mean over successes
  double median_ms = 0, p95_ms = 0, mean_ms = 0;
  StageMs median_stage;
  double time_ratio_to_gsf_off = 0;  // filled by the caller when an instance-only row exists
  uint64_t workspace_bytes = 0;
  double min_confidence = 0;  // the decision rule's threshold (config.confidence.min_probability)
  RuleOutcome rule;           // at the decision rule (the records' `answered`)
  Calibration calibration;
  std::vector<CurvePoint> curve;  // over confidence thresholds, ascending (answered falls)
};

// `min_confidence` is recorded as the rule's threshold; `answered` comes from the records.
ModeSummary summarize(const std::string& mode, const std::vector<QueryRecord>& records, double min_confidence);

double percentile(std::vector<double> v, double p);

}  // namespace gsf::cli
