// Evaluation metrics as in Outram's evaluation code and the paper's Tables II and IV: success means
// translation error < 5 m and rotation error < 10 deg, with errors from dT = T_est^-1 * T_gt; ATE/ARE are
// means over successes; times are per query. Also the declining curve: precision (correct among
// answered) against the share answered, when answers are ranked by the localizer's ambiguity.
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
  double voxel = 0, cluster = 0, field = 0, triangle = 0, match = 0, gsf = 0, clique = 0, pose = 0, refine = 0;
};

struct QueryRecord {
  uint32_t index = 0;  // position in the query sequence
  uint32_t frame = 0;  // file number
  std::string status;  // gsf::to_string of the localize status ("Ok" = answered)
  bool answered = false;
  bool success = false;
  bool in_zone = false;    // in the simulator's repetitive zone
  bool near_zone = false;  // within 60 m of it (not inside)
  PoseError error;
  double time_ms = 0;
  StageMs stages;
  double ambiguity = 1.0;  // lower = more confident
  uint32_t inliers = 0;
  // Poses in the dataset's frame (= the map's frame, georeference.h): errors are measured there.
  Eigen::Isometry3d estimate = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d truth = Eigen::Isometry3d::Identity();
  // The truth in the map-local frame (relative to the map origin), where the map's own coordinates are:
  // for the diagnostics that compare with map instances, hypotheses and the pictures.
  Eigen::Isometry3d truth_local = Eigen::Isometry3d::Identity();
  LocalizeResult result;              // the library's own counts for this query (diagnostics)
  uint32_t repeatable_instances = 0;  // query instances with a same-label map instance < 2 m under the truth
  uint32_t true_correspondences = 0;  // selected correspondences the ground truth agrees with (< 2 m)
  double truth_verified_score = 0;    // the ground-truth pose's whole-scan verification score
  // Per true correspondence: its GSF weight (best omega) and its query instance's range in m (the gate's
  // evidence, bench/true_pair_omega.py).
  std::vector<std::array<float, 2>> true_pairs;
};

struct CurvePoint {
  double threshold;  // answer only if ambiguity <= threshold
  double answered;   // share of all queries answered
  double precision;  // successes among answered
};

struct ModeSummary {
  std::string mode;
  uint32_t queries = 0, answered = 0, successes = 0;
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
  double default_threshold = 0;  // ambiguity threshold used for "answered at default"
  double precision_at_default = 0, answered_at_default = 0;
  double wrong_answers_at_default = 0;  // share of all queries answered wrongly at the default threshold
  std::vector<CurvePoint> curve;
};

ModeSummary summarize(const std::string& mode, const std::vector<QueryRecord>& records, double default_threshold);

double percentile(std::vector<double> v, double p);

}  // namespace gsf::cli
