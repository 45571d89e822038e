#include "result_json.h"

#include <cmath>

namespace gsf::cli {
namespace {

double ms(uint64_t ns) { return double(ns) / 1e6; }

}  // namespace

StageMs stage_ms(const StageTimes& t) {
  return StageMs{ms(t.voxel), ms(t.cluster), ms(t.field), ms(t.triangle),   ms(t.match),
                 ms(t.gsf),   ms(t.clique),  ms(t.pose),  ms(t.confidence), ms(t.refine)};
}

void write_stage_ms(JsonWriter& j, const char* key, const StageMs& t) {
  j.key(key);
  j.begin_object();
  j.field("voxel", t.voxel);
  j.field("cluster", t.cluster);
  j.field("field", t.field);
  j.field("triangle", t.triangle);
  j.field("match", t.match);
  j.field("gsf", t.gsf);
  j.field("clique", t.clique);
  j.field("pose", t.pose);
  j.field("confidence", t.confidence);
  j.field("refine", t.refine);
  j.end_object();
}

void write_pose(JsonWriter& j, const char* key, const Eigen::Isometry3d& pose) {
  j.key(key);
  j.begin_array();
  for (int row = 0; row < 3; ++row)
    for (int c = 0; c < 4; ++c) j.exact(pose.matrix()(row, c));
  j.end_array();
}

namespace {

// The stage counters of one result.
void write_stage_counts(JsonWriter& j, const LocalizeResult& x) {
  j.field("scan_voxels", x.scan_voxels);
  j.field("instances", x.query_instances);
  j.field("pole_instances", x.pole_instances);
  j.field("pole_instances_dropped", x.pole_instances_dropped);
  j.field("triangles", x.query_triangles);
  j.field("match_candidates", x.match_candidates);
  j.field("match_dropped", x.match_dropped);
  j.field("sparse_rematch", x.sparse_rematch);
  j.field("tie_ordered_triangles", x.tie_ordered_triangles);
  j.field("headings_kept", x.headings_kept);
  j.field("heading_dropped", x.heading_dropped);
  j.field("triangle_matches", x.triangle_matches);
  j.field("gsf_survivors", x.gsf_survivors);
  j.field("candidate_pairs", x.candidate_pairs);
  j.field("below_gate_matches", x.below_gate_matches);
  j.field("candidate_pairs_dropped", x.candidate_pairs_dropped);
  j.field("correspondences", x.correspondences);
  j.field("correspondences_dropped", x.correspondences_dropped);
  j.field("mirrored_matches", x.mirrored_matches);
  j.field("vote_pairs", x.vote_pairs);
  j.field("vote_pairs_dropped", x.vote_pairs_dropped);
  j.field("clique_size", x.clique_size);
  j.field("clique_searches", x.clique_searches);
  j.field("clique_nodes", static_cast<unsigned long long>(x.clique_nodes));
  j.field("budget_exhausted", x.budget_exhausted);
  j.field("capacity_truncated", x.capacity_truncated);
  j.field("field_probes", x.field_probes);
  j.field("field_comparisons", x.field_comparisons);
  j.field("verified", x.verified);
  j.field("other_class_weight", x.other_class_weight);
  j.field("chosen_hypothesis", x.chosen_hypothesis);
  j.field("height_votes", x.height_votes);
  j.field("twins_proposed", x.twins_proposed);
  j.field("twins_found", x.twins_found);
  if (x.prior_used) {  // a position prior (docs/vehicle-modes.md)
    j.field("prior_outside_matches", x.prior_outside_matches);
    j.field("prior_dropped_hypotheses", x.prior_dropped_hypotheses);
    j.field("prior_dropped_best_inliers", x.prior_dropped_best_inliers);
    j.field("prior_confident_before_check", x.prior_confident_before_check);
    j.field("prior_trigger_z_rival", x.prior_trigger_z_rival);
    j.field("prior_global_check", x.prior_global_check);
    j.field("prior_contradicted", x.prior_contradicted);
    j.field("prior_asked_one_shot", x.prior_asked_one_shot);
    j.field("prior_one_shot_vouched", x.prior_one_shot_vouched);
  }
  if (x.tracked) j.field("tracked", true);
}

// What the confidence is computed from (confidence.h).
void write_confidence_evidence(JsonWriter& j, const ConfidenceEvidence& e) {
  j.key("confidence_evidence");
  j.begin_object();
  j.field("z_rival", e.z_rival);
  j.field("z_shift", e.z_shift);
  j.field("z_shift_far", e.z_shift_far);
  j.field("z_turn", e.z_turn);
  j.field("rivals", e.rivals);
  j.field("samples", e.samples);
  j.field("blocks", e.blocks);
  j.field("inliers", e.inliers);
  j.field("inlier_share", e.inlier_share);
  j.field("known_share", e.known_share);
  j.field("agreement", e.agreement);
  j.field("rival_margin", e.rival_margin);
  j.end_object();
}

// What the ground truth says of the correspondences.
void write_truth(JsonWriter& j, const QueryTruth& truth) {
  j.field("true_correspondences", truth.true_correspondences);
  j.field("repeatable_instances", truth.repeatable_instances);
  j.field("answer_repeatable_instances", truth.answer_repeatable_instances);
  j.field("answer_layer_instances", truth.answer_layer_instances);
  j.field("truth_verified_score", truth.truth_verified_score);
  j.field("truth_known_share", truth.truth_known_share);
  if (truth.true_pairs) {
    j.key("true_pairs");  // [GSF weight, query instance range m] of each true selected correspondence
    j.begin_array();
    for (const auto& p : *truth.true_pairs) {
      j.begin_array();
      j.value(double(p[0]));
      j.value(double(p[1]));
      j.end_array();
    }
    j.end_array();
  }
}

// The reported hypotheses, best verified first, with their distance from the truth when known.
void write_hypotheses(JsonWriter& j, const LocalizeResult& x, const QueryTruth* truth) {
  j.key("hypotheses");
  j.begin_array();
  for (uint32_t h = 0; h < x.hypotheses && h < kMaxReportedHypotheses; ++h) {  // best verified first
    const HypothesisReport& p = x.hypothesis[h];
    j.begin_object();
    j.field("index", p.index);  // as chosen_hypothesis counts: the answer's report has index == it
    j.field("x", p.x);
    j.field("y", p.y);
    j.field("yaw_deg", p.yaw_deg);
    j.field("clique_size", p.clique_size);
    j.field("inliers", p.inliers);
    j.field("support", p.support);
    j.field("verified_score", p.verified_score);
    j.field("verified_voxels", p.verified_voxels);
    j.field("verified_agree", p.verified_agree);
    j.field("verified_disagree", p.verified_disagree);
    j.field("verified_unknown", p.verified_unknown);
    j.field("fully_verified", p.fully_verified);
    if (truth) {
      const double dx = p.x - truth->truth.translation().x(), dy = p.y - truth->truth.translation().y();
      j.field("distance_to_truth_m", std::sqrt(dx * dx + dy * dy));
      const Eigen::Matrix3d Rt = truth->truth.linear();
      double dyaw = p.yaw_deg - std::atan2(Rt(1, 0), Rt(0, 0)) * 57.29577951308232;
      while (dyaw > 180) dyaw -= 360;
      while (dyaw < -180) dyaw += 360;
      j.field("yaw_error_deg", dyaw);
    }
    j.end_object();
  }
  j.end_array();
}

}  // namespace

void write_result_diagnostics(JsonWriter& j, const LocalizeResult& x, const QueryTruth* truth) {
  j.key("diagnostics");
  j.begin_object();
  write_stage_counts(j, x);
  write_confidence_evidence(j, x.confidence_evidence);
  if (truth) write_truth(j, *truth);
  write_stage_ms(j, "stage_ms", stage_ms(x.times));
  write_hypotheses(j, x, truth);
  j.end_object();
}

}  // namespace gsf::cli
