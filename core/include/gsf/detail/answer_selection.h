// Internal (gsf/detail): a pipeline stage or building block, not part of the stable interface; it may
// change between versions. The stable interface is localizer.h, config.h, map_format.h, scan.h, status.h,
// platform.h, class_table.h, georeference.h and the C API gsf.h.
// Choosing the answer among the pose hypotheses (after the max clique): whole-scan verification
// against the map's semantic layer ranks them (coarse for all, full for the best, pattern-refined for
// the leaders: each step ranks, then caps). It keeps what the confidence (confidence.h) compares: the
// answer at the pose it was scored at and its best rivals at another place or heading.
#pragma once
#include <cstdint>

#include <Eigen/Geometry>

#include "gsf/config.h"
#include "gsf/detail/arena.h"
#include "gsf/detail/pose_hypotheses.h"
#include "gsf/detail/semantic_grid.h"
#include "gsf/detail/voxel_layer.h"
#include "gsf/status.h"

namespace gsf {

struct LocalizeResult;

// Verification weights for one scan: `base` (stability weights), each class scaled by (its share of
// every stride-th voxel, max_points sampled)^-exponent, then all rescaled to keep the total weight, so
// the few voxels of rare classes (the cues beside repeated objects) count for more than the road and
// rows that agree at every lattice shift. exponent 0: out = base.
void rarity_weights(const VoxelLayer& voxels, const float* base, float exponent, uint32_t max_points, float* out);

class AnswerSelector {
 public:
  // max_voxels: the voxel layer's capacity (the compact copy verification reads holds that many).
  static size_t required_bytes(uint32_t refine_top, uint32_t max_voxels);
  Status bind(Arena& arena, uint32_t refine_top, uint32_t max_voxels);

  // Verifies `hyps` (when verification is on and the map has a semantic layer), chooses the answer and
  // fills out's pose, inliers and hypothesis reports. `weights`: the stability weights.
  void choose(PoseHypotheses& hyps, const VoxelLayer& voxels, const SemanticGridView& semantic, const float* weights,
              const HypothesisConfig& hypothesis_config, const VerifyConfig& verify_config, LocalizeResult& out);
  uint32_t chosen() const { return chosen_; }
  void forget() { chosen_ = UINT32_MAX; }
  // The verification weights of the last choose() (the stability weights given here before any).
  const float* verify_weights() const { return verify_weights_; }
  void set_verify_weights(const float* weights);
  // After choose() with verification: the answer at the pose verification scored it (its pattern-refined
  // pose when it was refined), its rivals (best first, fully scored, at another place or heading) at
  // theirs, and the compact points verification read (0 when it read the voxels).
  static constexpr uint32_t kMaxRivals = 4;
  const Eigen::Isometry3d& answer_pose() const { return answer_pose_; }
  const Eigen::Isometry3d* rival_poses() const { return rival_pose_; }
  uint32_t rival_count() const { return rival_count_; }
  const VerifyPoint* compact_points() const { return points_; }
  uint32_t compact_point_count() const { return compact_points_; }

 private:
  Eigen::Isometry3d* refined_pose_ = nullptr;  // refine_top: poses the pattern search chose
  uint32_t* refined_id_ = nullptr;             // refine_top: their hypotheses
  VerifyPoint* points_ = nullptr;              // max_voxels: the query voxels' bird's-eye copy (fill_verify_points)
  uint32_t point_capacity_ = 0;                // max_voxels
  uint32_t refine_top_ = 0;
  uint32_t chosen_ = UINT32_MAX;
  float verify_weights_[kNumClasses] = {};
  Eigen::Isometry3d scoring_pose_of(uint32_t h, uint32_t refined_count) const;
  const PoseHypotheses* hyps_ = nullptr;
  Eigen::Isometry3d answer_pose_ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d rival_pose_[kMaxRivals];
  uint32_t rival_count_ = 0;
  uint32_t compact_points_ = 0;
};

}  // namespace gsf
