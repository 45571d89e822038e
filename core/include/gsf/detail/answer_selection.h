// Internal (gsf/detail): a pipeline stage or building block, not part of the stable interface; it may
// change between versions. The stable interface is localizer.h, config.h, map_format.h, scan.h, status.h,
// platform.h, class_table.h, georeference.h, stage_configs.h, stage_results.h and the C API gsf.h.
// Choosing the answer among the pose hypotheses (after the max clique): whole-scan verification
// against the map's semantic layer ranks them (coarse for all, full for the best, pattern-refined for
// the leaders: each step ranks, then caps). It keeps what the confidence (confidence.h) compares: the
// answer at the pose it was scored at and its best rivals at another place or heading.
#pragma once
#include <cstdint>

#include <Eigen/Geometry>

#include "gsf/detail/arena.h"
#include "gsf/detail/pose_hypotheses.h"
#include "gsf/detail/semantic_grid.h"
#include "gsf/detail/voxel_layer.h"
#include "gsf/stage_configs.h"
#include "gsf/status.h"

namespace gsf {

// What choose() decided; the localizer copies it into LocalizeResult.
struct AnswerChoice {
  static constexpr uint32_t kMaxRanked = 16;  // hypotheses ranked for the report (LocalizeResult::hypothesis)
  uint32_t index = 0;                         // the answer among the hypotheses (0: the maximum clique's)
  PoseHypothesis answer;                      // its pose, clique size, inliers and support
  bool verified = false;                      // chosen by whole-scan verification
  // The best hypotheses by verified score, best first (without verification the first ones, in the
  // order found), and whether each was scored on verify.max_points (else on the coarse sample only).
  uint32_t ranked = 0;
  uint32_t rank[kMaxRanked] = {};
  bool fully_verified[kMaxRanked] = {};
};

// Verification weights for one scan: `base` (stability weights), each class scaled by (its share of
// every stride-th voxel, max_points sampled)^-exponent, then all rescaled to keep the total weight, so
// the few voxels of rare classes (the cues beside repeated objects) count for more than the road and
// rows that agree at every lattice shift. exponent 0: out = base.
void rarity_weights(const VoxelLayer& voxels, const float* base, float exponent, uint32_t max_points, float* out);

// The pattern search's largest sample: max_points / the smaller of its two divisors (at least 1).
uint32_t search_sample_points(const VerifyConfig& vc);

class AnswerSelector {
 public:
  // refine_slots: pattern searches at most (VerifyConfig refine_top + refine_turned); max_voxels: the
  // voxel layer's capacity (the compact copy verification reads holds that many); search_points: the
  // pattern search's largest sample, search_sample_points(VerifyConfig) (its SearchMemo holds that many).
  static size_t required_bytes(uint32_t refine_slots, uint32_t max_voxels, uint32_t search_points);
  Status bind(Arena& arena, uint32_t refine_slots, uint32_t max_voxels, uint32_t search_points);

  // Verifies `hyps` (when verification is on and the map has a semantic layer) and chooses the answer.
  // `weights`: the stability weights.
  AnswerChoice choose(PoseHypotheses& hyps, const VoxelLayer& voxels, const SemanticGridView& semantic,
                      const float* weights, const HypothesisConfig& hypothesis_config,
                      const VerifyConfig& verify_config);
  uint32_t chosen() const { return chosen_; }
  void forget() { chosen_ = UINT32_MAX; }
  // The verification weights of the last choose() (the stability weights given here before any).
  const float* verify_weights() const { return verify_weights_; }
  void set_verify_weights(const float* weights);
  // For poses scored outside choose() (tracking): this scan's verification weights and the voxels'
  // compact copy, as choose() prepares them. Returns whether the copy was made.
  bool prepare(const VoxelLayer& voxels, const float* weights, const VerifyConfig& vc) {
    chosen_ = UINT32_MAX;
    return prepare_scoring(voxels, weights, vc, true);
  }
  // After choose() with verification: the answer at the pose verification scored it (its pattern-refined
  // pose when it was refined), its rivals (best first, fully scored, at another place or heading) at
  // theirs, and the compact points verification read (0 when it read the voxels).
  static constexpr uint32_t kMaxRivals = 4;
  const Eigen::Isometry3d& answer_pose() const { return answer_pose_; }
  const Eigen::Isometry3d* rival_poses() const { return rival_pose_; }
  uint32_t rival_count() const { return rival_count_; }
  // The disagree weights verification scored with (disagree_weights.h): estimated for this scan by
  // choose(), the configured weight for every disagreement after prepare().
  const DisagreeWeights& disagree_weights() const { return disagree_; }
  const VerifyPoint* compact_points() const { return points_; }
  // The pattern search's record (semantic_grid.h), for searches outside choose() (tracking).
  SearchMemo* search_memo() { return &memo_; }
  uint32_t compact_point_count() const { return compact_points_; }

 private:
  struct PoseScorer;  // verify_pose and its pattern search, over the compact copy when there is one
  // The verification's steps, in order (each ranks, then caps).
  bool prepare_scoring(const VoxelLayer& voxels, const float* weights, const VerifyConfig& vc, bool verify);
  uint32_t verify_hypotheses(PoseHypotheses& hyps, const PoseScorer& scorer, const VerifyConfig& vc,
                             const HypothesisConfig& hc, uint8_t* full_scored);
  DisagreeWeights weigh_disagreements(const PoseHypotheses& hyps, const PoseScorer& scorer, const HypothesisConfig& hc,
                                      const uint32_t* top, uint32_t n) const;
  uint32_t distinct_of(const PoseHypotheses& hyps, const HypothesisConfig& hc, uint32_t* top, uint32_t n) const;
  uint32_t add_turned(const PoseHypotheses& hyps, const HypothesisConfig& hc, const uint8_t* full_scored,
                      uint32_t turned, uint32_t cap, uint32_t* top, uint32_t n) const;
  uint32_t pick_answer_and_rivals(const PoseHypotheses& hyps, const uint8_t* full_scored, const HypothesisConfig& hc,
                                  uint32_t refined_count);
  static void rank_for_report(const PoseHypotheses& hyps, bool verify, const uint8_t* full_scored,
                              AnswerChoice* choice);
  Eigen::Isometry3d* refined_pose_ = nullptr;  // refine_slots: poses the pattern search chose
  uint32_t* refined_id_ = nullptr;             // refine_slots: their hypotheses
  VerifyPoint* points_ = nullptr;              // max_voxels: the query voxels' bird's-eye copy (fill_verify_points)
  uint32_t point_capacity_ = 0;                // max_voxels
  SearchMemo memo_;                            // min(search_points, max_voxels) samples a slot
  uint32_t refine_slots_ = 0;
  uint32_t chosen_ = UINT32_MAX;
  float verify_weights_[kNumClasses] = {};
  DisagreeWeights disagree_;
  Eigen::Isometry3d scoring_pose_of(uint32_t h, uint32_t refined_count) const;
  const PoseHypotheses* hyps_ = nullptr;
  Eigen::Isometry3d answer_pose_ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d rival_pose_[kMaxRivals];
  uint32_t rival_count_ = 0;
  uint32_t compact_points_ = 0;
};

}  // namespace gsf
