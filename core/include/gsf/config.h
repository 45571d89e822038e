// LocalizerConfig: every capacity and tuning value of the query pipeline, one sub-struct per stage.
// Defaults are the evaluated settings (docs/results.md); units in comments. The map builder records the
// values that must agree between map and localizer in MapParams (map_params_from).
#pragma once
#include <cstdint>

#include "gsf/gaussian_field.h"
#include "gsf/instance_clustering.h"
#include "gsf/map_format.h"
#include "gsf/refine.h"
#include "gsf/status.h"
#include "gsf/triangle.h"
#include "gsf/voxel_layer.h"

namespace gsf {

struct MatchConfig {
  bool use_gsf = true;                    // false: instance-only Outram behaviour (ablation)
  uint32_t max_matches_per_triangle = 64; // map triangles accepted per query triangle
  uint32_t max_triangle_matches = 24000;  // total per query (capacity)
  uint32_t yaw_bins = 36;                 // rotation hypotheses are binned for probe caching (10 deg)
  uint32_t probe_cache_slots = 1024;      // cached query-field probes (instance, yaw bin)
  uint32_t similarity_cache_slots = 8192; // cached omega per (query instance, map instance, yaw bin)
  float observed_variance = 0.6f;         // grid points where the query field's variance exceeds this
                                          // fraction of the prior are unobserved and not compared
  float normalize_mass = 0.0f;            // >0: compare per-point class distributions (wasserstein.h)
  // Weight of the W2 covariance term in the per-match similarity. The posterior covariance depends only
  // on where data lies (a sparse scan vs the dense map), not on semantics; measured on the simulator it
  // halves the true/false separation, so the filter uses the mean term (0). 1 = the paper's W2.
  float covariance_weight = 0.0f;
  float tau = 0.2f;                       // omega = exp(-w2 / tau), w2 per compared grid point
  float min_similarity = 0.3f;            // a triangle match survives if all three omegas reach this
  uint32_t max_correspondences = 256;     // vertices of the consistency graph (capacity)
  uint32_t max_field_points = 4096;       // semantic points gathered per query instance field
};

struct CliqueConfig {
  float consistency_eps = 1.0f;   // m; | |a_i-a_j| - |b_i-b_j| | <= eps (Outram: 1.0 m)
  uint64_t node_budget = 200000;  // branch-and-bound nodes per search; then best-so-far is used
  uint64_t second_budget = 50000; // nodes for the second-best (ambiguity) search
};

struct PoseConfig {
  float tls_threshold = 1.5f;     // m; residual truncation of the weighted TLS (paper Eq. 8)
  uint32_t max_iterations = 50;   // GNC iterations
  uint32_t min_inliers = 3;       // fewer -> NoSolution
};

struct LocalizerConfig {
  uint32_t max_scan_points = 262144;  // larger scans are rejected with CapacityExceeded
  VoxelConfig voxel;
  ClusterConfig cluster;
  FieldConfig field;
  TriangleConfig triangle;
  MatchConfig match;
  CliqueConfig clique;
  PoseConfig pose;
  RefineConfig refine;  // off by default (the "gsf+refine" evaluation row turns it on)
};

Status validate(const LocalizerConfig& config);
// The parameters a map built for this config records (and a localizer checks).
MapParams map_params_from(const LocalizerConfig& config);
// Ok if a map built with `params` can serve a localizer with `config`.
Status check_map_params(const LocalizerConfig& config, const MapParams& params);

}  // namespace gsf
