// The Localizer facade: init(config, map, buffer) once, then localize(scan) -> LocalizeResult, with no
// heap use, no exceptions and bounded work per call. Stages (one file each) run in a fixed order:
//   voxel layer -> instances -> query fields -> triangles -> index matches -> GSF filter ->
//   correspondences -> consistency graph -> max clique -> robust pose
#pragma once
#include <cstddef>
#include <cstdint>

#include <Eigen/Geometry>

#include "gsf/arena.h"
#include "gsf/config.h"
#include "gsf/map_format.h"
#include "gsf/platform.h"
#include "gsf/scan.h"
#include "gsf/status.h"

namespace gsf {

struct StageTimes {  // nanoseconds from the Clock given at init (all zero without one)
  uint64_t voxel = 0, cluster = 0, field = 0, triangle = 0, match = 0, gsf = 0, clique = 0, pose = 0, refine = 0, total = 0;
};

struct LocalizeResult {
  Status status = Status::NotInitialized;
  Eigen::Isometry3d map_T_scan = Eigen::Isometry3d::Identity();  // maps scan points into the map frame
  uint32_t inliers = 0;          // correspondences agreeing with the pose (after TLS)
  uint32_t clique_size = 0;
  double score = 0.0;            // sum of inlier weights
  // Best / second-best hypothesis: score of the largest clique that disagrees with the answer, divided by
  // the answer's score, and at least min_inliers / inliers (weak support). 0 = unambiguous, 1 = a
  // different pose is as well supported, or the answer rests on the bare minimum (decline to answer).
  double ambiguity = 1.0;
  uint32_t query_instances = 0, query_triangles = 0, triangle_matches = 0, gsf_survivors = 0, correspondences = 0;
  uint64_t clique_nodes = 0;
  uint32_t field_probes = 0;       // query-field probes computed by the GSF filter (cost driver)
  uint32_t field_comparisons = 0;  // (query instance, map instance, yaw bin) similarities computed
  bool refined = false;            // refinement ran and its result was accepted
  bool budget_exhausted = false;   // max clique ran out of nodes; the best clique found is used
  bool capacity_truncated = false; // some stage hit a Config capacity and kept a deterministic subset
  StageTimes times;
};

class Localizer {
 public:
  // Bytes of the caller buffer init() needs for this config (independent of the map).
  static size_t required_bytes(const LocalizerConfig& config);

  // The same total broken down by stage (for memory budgets; sums to required_bytes).
  struct Budget {
    size_t voxel, cluster, field, triangle, match, gsf_cache, correspondence, clique, refine, other, total;
  };
  static Budget budget(const LocalizerConfig& config);

  // `map` must stay valid (and its blob unchanged) for the Localizer's lifetime. The map's build
  // parameters must agree with config (field, grid, triangles): otherwise ConfigMismatch.
  Status init(const LocalizerConfig& config, const MapView& map, void* buffer, size_t bytes, Clock* clock = nullptr);

  // One-shot global localization of one scan. Always fills `out` (status inside as well as returned).
  Status localize(const ScanView& scan, LocalizeResult* out);

  // The correspondences the last localize() passed to the max clique (for pictures and debugging):
  // copies up to `max` into `out`, returns how many there were.
  struct Correspondence {
    uint32_t query_instance, map_instance;
    float query_xyz[3];
    float weight;
    bool in_clique;
  };
  uint32_t last_correspondences(Correspondence* out, uint32_t max) const;

  bool initialized() const { return initialized_; }
  const LocalizerConfig& config() const { return config_; }
  size_t workspace_bytes() const { return arena_.used(); }
  // Switch the GSF filter without re-init (ablation: off = instance-only Outram behaviour).
  void set_use_gsf(bool on) { config_.match.use_gsf = on; }

  struct Impl;  // stage objects, bound into the arena

 private:
  LocalizerConfig config_{};
  MapView map_{};
  Arena arena_;
  Impl* impl_ = nullptr;
  Clock* clock_ = nullptr;
  bool initialized_ = false;
};

}  // namespace gsf
