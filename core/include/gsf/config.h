// LocalizerConfig: every capacity and tuning value of the query pipeline, one sub-struct per stage.
// Defaults are the evaluated settings (docs/results.md); units in comments. Each settable value is in
// the one parameter list (core/src/parameters.def; gsf/parameters.h: names, units, ranges, docs; the
// table is docs/parameters.md). The map builder records the
// values that must agree between map and localizer in MapParams (map_params_from).
#pragma once
#include <cstdint>

#include "gsf/class_table.h"
#include "gsf/detail/confidence.h"
#include "gsf/detail/gaussian_field.h"
#include "gsf/detail/gsf_filter.h"
#include "gsf/detail/instance_clustering.h"
#include "gsf/detail/pole_extraction.h"
#include "gsf/detail/pose_hypotheses.h"
#include "gsf/detail/refine.h"
#include "gsf/detail/scan_window.h"
#include "gsf/detail/tracker.h"
#include "gsf/detail/triangle.h"
#include "gsf/detail/voxel_layer.h"
#include "gsf/map_format.h"
#include "gsf/status.h"

namespace gsf {

// Coarse matching and correspondence selection. Every cap ranks before it cuts (never storage order)
// and the localizer reports how many candidates each cap dropped.
struct MatchConfig {
  uint32_t max_matches_per_triangle = 256;  // best map triangles kept per query triangle (by side residual)
  // Work budget of one scan: the per-triangle cap shrinks to max_matches_per_scan / query triangles
  // (at least 1) when that is smaller, so a lattice's thousands of equally good matches per triangle
  // cannot make the GSF filter and the correspondences cost triangles x 256; still ranked, then capped,
  // and counted in match_dropped. 65,536: the suite's p95 query time halves (87.7 -> 47.4 ms held out,
  // 66.4 -> 38.2 ms seeds 1-5) for -0.1 points of GSF success (instance-only +0.3 / +0.4); a true pair
  // lost by one triangle's cap still comes from the other triangles it is a vertex of. 32,768 (map
  // format v6): p95 -15% again, the slowest world 52 -> 44 ms held out, success within 0.2 points either
  // way (docs/results.md).
  uint32_t max_matches_per_scan = 32768;
  // A map triangle whose bird's-eye sense contradicts the query triangle's is never a match (a mirror
  // image: same sides; triangle.h, TriangleOrientation): vehicles are upright, so their scans map to the
  // map by turns about the vertical, which keep the sense.
  float vertex_tie_tolerance = 0.06f;  // relative; query sides closer than this are tried in both orders
  // Heading votes (localizer.cpp, step 5a): the best `heading_bins` yaw bins (gsf.yaw_bins of them,
  // each with its two neighbours) by the votes of an even sample of `heading_sample_triangles` query
  // triangles' matches; matches at other headings are dropped and counted. 0 = off.
  uint32_t heading_bins = 6;
  uint32_t heading_sample_triangles = 256;
  // With GSF: a triangle match survives if all three omegas reach this. When the surviving matches give
  // fewer than kFillPairs (64, gsf_filter.h) pairs, the matches below it fill the set up to that many,
  // ranked after every surviving pair (localizer.cpp, step 6): a far, sparsely seen instance's field
  // compares poorly even with itself, and the gate alone dropped every true match of an approach road's scan.
  float min_similarity = 0.3f;
  uint32_t max_candidates = 24000;     // distinct (query, map) instance pairs accumulated (capacity)
  uint32_t max_correspondences = 512;  // vertices of the consistency graph (best by votes x weight)
  uint32_t max_field_points = 4096;    // semantic points gathered per query instance field
};

// Whole-scan verification of the pose hypotheses against the map's semantic layer (semantic_grid.h).
struct VerifyConfig {
  bool enabled = true;          // off, or a map without the layer: the maximum clique's pose is the answer
  uint32_t max_points = 4096;   // query voxels scored per hypothesis (uniform stride over the scan)
  uint32_t coarse_divisor = 8;  // every hypothesis is first scored on max_points / coarse_divisor voxels,
  uint32_t full_top = 16;       // and the best full_top of them on max_points
  // The best `refine_top` hypotheses (by first score) are re-scored after a bird's-eye pattern search
  // (semantic_grid.h: verify_pose_refined), so a near-truth clique pose is compared at its best.
  uint32_t refine_top = 4;
  uint32_t refine_rounds = 3;
  // The pattern search's probes are scored on max_points / search_divisor voxels, those of its last
  // (finest) round on max_points / polish_divisor; the pose it ends at is scored on max_points.
  uint32_t search_divisor = 4;
  uint32_t polish_divisor = 4;
  // Rarity weighting: each class's weight is scaled by (its share of the scan's sampled voxels)^-e, then
  // all are rescaled to keep the total weight, so the few voxels of rare classes (the cues beside
  // repeated objects) count for more than the road and rows that agree at every lattice shift. 0 = off.
  float rarity_exponent = 0.5f;
  float refine_step_m = 0.4f;
  float refine_step_deg = 0.8f;
  // score = agree - disagree_weight x disagree. Near-symmetric poses (a flipped avenue, a lattice shift)
  // agree alike on the repeated structure; what separates them is that the true pose contradicts the map
  // rarely, so a disagreement is stronger evidence than an agreement (per voxel, log((1-q)/(1-p)) against
  // log(p/q) for agreement rates p at the truth and q at a wrong pose: 3-7 at p = 0.85-0.95).
  float disagree_weight = 3.0f;
};

struct LocalizerConfig {
  uint32_t max_scan_points = 262144;  // larger scans are rejected with CapacityExceeded
  // The label set of the scans' raw label ids (class_table.h). nullptr: SemanticKITTI, with
  // cluster.instance_classes as the instance classes. With a table, its roles decide: instance classes
  // (cluster.instance_classes is ignored), pole / trunk hosts (poles.pole_hosts / trunk_hosts are
  // replaced) and class stabilities. Read during required_bytes(), budget() and init() only: init()
  // copies the table into the workspace, so the caller's table need not outlive it. The map records
  // the table's id; a localizer with another table gets ConfigMismatch.
  const ClassTable* classes = nullptr;
  VoxelConfig voxel;
  ClusterConfig cluster;
  // Geometric pole / trunk instances (pole_extraction.h); runs only when the label set has host
  // classes (nuScenes-lidarseg: static.manmade, static.vegetation), else costs nothing.
  PoleConfig poles;
  FieldConfig field;
  TriangleConfig triangle;
  MatchConfig match;
  GsfFilterConfig gsf;
  HypothesisConfig hypotheses;
  VerifyConfig verify;
  RefineConfig refine;  // off by default (the "gsf+refine" evaluation row turns it on)
  ConfidenceConfig confidence;
  TrackConfig track;  // Localizer::track (tracker.h, docs/vehicle-modes.md)
  // Localizer::localize_sequence: several scans tied by odometry (scan_window.h, docs/vehicle-modes.md).
  WindowConfig window;
};

// Ok, or InvalidArgument when a parameter is out of its range or breaks a rule with another one;
// check_config() (parameters.h) says which parameter and why.
Status validate(const LocalizerConfig& config);
// The label set in effect: *config.classes, or the built-in SemanticKITTI table.
const ClassTable& label_set(const LocalizerConfig& config);
// Instance labels a map built with this config can hold: the label set's instance classes, plus kPole /
// kTrunk when it has pole / trunk hosts.
ClassMask instance_label_mask(const LocalizerConfig& config);
// The pole-extraction settings in effect (hosts and stabilities from the label set).
PoleConfig effective_pole_config(const LocalizerConfig& config);
// The parameters a map built for this config records (and a localizer checks).
MapParams map_params_from(const LocalizerConfig& config);
// Ok if a map built with `params` can serve a localizer with `config`.
Status check_map_params(const LocalizerConfig& config, const MapParams& params);

}  // namespace gsf
