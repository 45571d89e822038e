// The configuration of each stage of the query pipeline: plain data with the evaluated defaults, units
// in comments. LocalizerConfig (config.h) holds one of each; the stages (gsf/detail) read their own.
// Settable values are in the one parameter list (core/src/parameters.def, docs/parameters.md).
#pragma once
#include <cstdint>

#include "gsf/class_table.h"
#include "gsf/semantic_classes.h"

namespace gsf {

// Voxelisation of the scan (detail/voxel_layer.h).
struct VoxelConfig {
  float voxel_size = 0.4f;  // m
  float min_range = 2.5f;   // m; drops returns from the ego vehicle
  float max_range = 80.0f;  // m
  // 32k: the measured scans make 6k-14k voxels at 0.4 m (docs/memory.md); beyond it a scan's new voxels
  // are dropped and counted, and localize() sets capacity_truncated.
  uint32_t max_voxels = 32768;
  float column_size = 2.0f;      // m; cell of the 2-D gather index
  uint32_t max_columns = 16384;  // gather index cells (hash capacity)
  // Softmax samples per voxel (scans with logits): a voxel's first prob_samples points each add their
  // softmax, later ones only every 2nd, then every 4th, ... point (stride doubling each time the point
  // count doubles), so a dense sensor's near voxels stop paying a softmax per point; position and count
  // take every point. 0: every point (the exact mean).
  uint32_t prob_samples = 8;
};

// Instance clustering of the voxels of instance classes (detail/instance_clustering.h).
struct ClusterConfig {
  ClassMask instance_classes = kDefaultInstanceClasses;
  float tolerance[kNumClasses];  // m, per class; default 0.6 (car 1.0)
  // m, per class: the vertical gap two voxels within tolerance horizontally may have and still connect,
  // when larger than tolerance (otherwise the test is the sphere of radius tolerance). Default 2.0 for
  // pole, trunk and traffic sign (beams 1.13 deg apart up to 100 m, nuScenes' 1.33 deg to 86 m; suite
  // held out: 1.0 / 1.5 / 2.0 m gave 96.3 / 97.0 / 97.3% of all queries, docs/results.md), 0 (the
  // sphere) for the others.
  float vertical_tolerance[kNumClasses];
  uint32_t min_voxels[kNumClasses];  // default 3 (car 8)
  float max_extent[kNumClasses];     // m, horizontal bbox diagonal; default 2.5 (car 8, trunk 2.5)
  uint32_t max_instances = 128;
  ClusterConfig() {
    for (int c = 0; c < kNumClasses; ++c) {
      tolerance[c] = 0.6f;
      vertical_tolerance[c] = 0.0f;
      min_voxels[c] = 3;
      max_extent[c] = 2.5f;
    }
    tolerance[kCar] = 1.0f;
    min_voxels[kCar] = 8;
    max_extent[kCar] = 8.0f;
    max_extent[kTrafficSign] = 3.0f;
    vertical_tolerance[kPole] = vertical_tolerance[kTrunk] = vertical_tolerance[kTrafficSign] = 2.0f;
  }
};

// The two kinds of geometric instance: the index of PoleConfig's per-kind values.
enum PoleKind : uint8_t { kPoleKind = 0, kTrunkKind = 1 };

// Geometric pole / trunk instances from host classes (detail/pole_extraction.h).
// The default hosts are the nuScenes-lidarseg situation. For a label set that has its own pole and
// trunk classes (SemanticKITTI), set_hosts(semantic_kitti table) gives no hosts and no instances:
// InstanceClustering already makes them from the labels.
struct PoleConfig {
  ClassMask pole_hosts = class_bit(kBuilding);     // e.g. nuScenes static.manmade
  ClassMask trunk_hosts = class_bit(kVegetation);  // e.g. nuScenes static.vegetation
  float max_diameter[2] = {1.2f, 1.2f};            // m, per kind: slice box diagonal and thickness about the axis
  float min_height[2] = {2.0f, 2.0f};              // m, per kind: vertical extent of a chain
  uint32_t min_levels = 4;                         // distinct voxel levels in a chain
  float max_tilt_deg = 12.0f;                      // axis from vertical
  float ring_width = 1.0f;                         // m, isolation ring around a slice segment
  float link_radius = 0.6f;                        // m, horizontal offset of linked voxels of stacked segments
  float max_gap = 1.2f;                            // m, empty height bridged between stacked segments
  float stability[2] = {1.0f, 1.0f};               // instance stability per kind (stability_weight(kPole/kTrunk))
  uint32_t max_instances = 64;

  // Hosts and stabilities from a label set's table (pole_host_classes, trunk_host_classes,
  // stability(kPole), stability(kTrunk)).
  void set_hosts(const ClassTable& table) {
    pole_hosts = table.pole_host_classes();
    trunk_hosts = table.trunk_host_classes();
    stability[kPoleKind] = table.stability(kPole);
    stability[kTrunkKind] = table.stability(kTrunk);
  }
};

// Each instance's Gaussian semantic field (detail/gaussian_field.h).
struct FieldConfig {
  float radius = 8.0f;            // m; semantic points within this distance train the field
  uint32_t inducing_points = 32;  // M (Algorithm 1 target), <= kMaxInducing
  float length_scale = 2.0f;      // m; Matern kappa
  float signal_variance = 1.0f;   // s^2
  float noise_variance = 0.05f;   // sigma_y^2
  uint32_t input_dims = 2;        // 2 = bird's-eye (x, y) field, 3 = full 3-D inputs
  uint32_t grid_nx = 6, grid_ny = 6;
  float grid_spacing = 2.0f;   // m (6 x 6 at 2 m: as discriminative as 8 x 8 at 1.5 m, 1.8x cheaper)
  uint32_t grid_layers = 1;    // heights (3-D fields only; 1 for bird's-eye)
  float layer_spacing = 1.0f;  // m between layers
  float grid_z0 = 0.0f;        // m; lowest layer height relative to the centroid
  uint64_t seed = 7;           // Algorithm 1's random choice
};

// Triangle descriptors over the instances (detail/triangle.h).
struct TriangleConfig {
  uint32_t neighbours = 10;  // K nearest instances per anchor (query scans)
  // K of the map's triangles (0: neighbours). A map holds every instance seen from any scan of the drive,
  // a query only those it sees, so a query triangle's vertices may not be among the map apex's K
  // nearest; a larger map K keeps them there. Must be 0 or >= neighbours; the map records it.
  uint32_t map_neighbours = 0;
  uint32_t map_k() const { return map_neighbours == 0 ? neighbours : map_neighbours; }
  float min_side = 0.5f;                  // m
  float max_side = 50.0f;                 // m
  float side_bin = 1.0f;                  // m, key quantisation
  float relative_side_tolerance = 0.03f;  // match if |d_q - d_m| < tol * d_q on every side
  // A scan whose triangles find fewer than kSparseScanCandidates (triangle_matcher.h) map triangles at
  // that tolerance is matched at this one instead (0: never; needs the heading votes, which count). A
  // sparse sensor sees an object on two or three rings, so its centroid moves between views by more
  // than 3% of a side; a scan that finds thousands of candidates does not need the looser match (it
  // would only add wrong ones).
  float sparse_side_tolerance = 0.075f;
  uint32_t max_triangles = 4096;  // per scan (capacity)
};

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

// The GSF filter: field similarity of matched instances (detail/gsf_filter.h).
struct GsfFilterConfig {
  // false: no field is fitted or compared, every match at a kept heading passes with omega 1 (the
  // instance-only Outram pipeline: the evaluation's "instance" column).
  bool enabled = true;
  uint32_t yaw_bins = 36;                   // rotation hypotheses are binned for probe caching (10 deg)
  uint32_t probe_cache_slots = 1024;        // cached query-field probes (instance, yaw bin)
  uint32_t similarity_cache_slots = 65536;  // cached omega per (query instance, map instance, yaw bin)
  float observed_variance = 0.6f;           // grid points where the query field's variance exceeds this
                                            // fraction of the prior are unobserved and not compared
  // Weight of the W2 covariance term (wasserstein.h): 0 compares the means only (docs/gsf-field.md: the
  // covariance term measures a sparse scan's density against a dense map); 1 = the paper's W2 (ablation).
  float covariance_weight = 0.0f;
  float tau = 0.2f;  // omega = exp(-w2 / tau), w2 per compared grid point
};

// Pose hypotheses from the consistency graph's cliques and shift votes (detail/pose_hypotheses.h).
struct HypothesisConfig {
  // K: hypotheses per query. A 14 x 10 lattice has 140 shifts a heading and the shift votes share the
  // slots among up to shift_headings headings; 96 left the true shift out in lattice zones (suite seeds
  // 1-5, lattice zone 86.5% at 96, 97.0% at 192; docs/results.md). Verification scores each coarsely.
  uint32_t max_hypotheses = 192;
  uint32_t max_peeled = 8;  // of which from peeled maximum cliques; the rest from shift votes,
                            // shared evenly by the headings
  // Distinct clique headings whose translations are voted on: of all found, the best supported by the
  // votes (their best translation bin's support; a clique's own fit can keep 3 of its 13-16 pairs at a
  // stray heading, which then took the place of a true one: seed 41's lattice, the cheap family's hall).
  uint32_t shift_headings = 4;
  // Heading-diverse cliques: after peeling, up to this many more clique searches run with the consistency
  // graph's edges at the found headings removed (pair directions within heading_separation_deg), so each
  // finds a clique at another heading. In a symmetric layout (a lattice's 90 / 180 deg turns, a row's or
  // avenue's 180) every large clique can share one wrong heading, and the shift votes then never see the
  // true one. They run however many headings peeling found (before 2026-12-08 only while fewer than
  // shift_headings: two stray headings then kept a lattice's true heading out). 0 = off.
  uint32_t heading_cliques = 3;
  float heading_separation_deg = 15.0f;
  // m; translation vote bins. Bins are ranked by their support, the weight of the votes within
  // tls_threshold (<= shift_bin) of the mean of the bin's own votes (they may lie in a neighbouring
  // bin): a translation whose votes straddle a bin edge is then not outranked by a lattice's other
  // shifts, and bins with fewer supporting votes than min_inliers but enough of their own still follow.
  float shift_bin = 2.0f;
  // Pairs the shift votes see: the consistency graph's max_correspondences best pairs and the next ones
  // by the same ranking (correspondence_set.h), up to this many. In a lattice the graph's 512 can hold
  // only 2-10 true pairs of the 5,000-10,000 candidates, because every lattice shift gathers as many
  // triangle votes as the truth; a translation vote over all of them still finds the true shift among
  // its peaks. Votes cost a sort per heading; a bin's fit reads only the bins around it. At most
  // max_correspondences: the graph's pairs only.
  uint32_t shift_vote_pairs = 8192;
  uint64_t first_budget = 200000;  // branch-and-bound nodes for the first (maximum) clique
  uint64_t next_budget = 20000;    // nodes for each further clique
  float consistency_eps = 1.0f;    // m; | |a_i-a_j| - |b_i-b_j| | <= eps (Outram: 1.0 m)
  // Weight of height differences in those distances. An instance centroid's height depends on how much
  // of a pole or trunk one scan sees (near columns lose their tops); 1 = Outram's 3-D distances.
  float consistency_z_weight = 1.0f;
  float tls_threshold = 1.5f;    // m; residual truncation of the weighted TLS (paper Eq. 8)
  uint32_t max_iterations = 50;  // GNC iterations
  uint32_t min_inliers = 3;      // a clique or TLS solution with fewer is no hypothesis
  float same_pose_m = 2.0f;      // hypotheses closer than this and same_pose_deg are one answer
  float same_pose_deg = 5.0f;
  // Upright prior: a hypothesis whose z axis leans more than this from the map's is re-solved upright
  // (yaw and translation on its inliers, which are then recounted; fewer than min_inliers: dropped).
  // A vehicle-mounted sensor is near level (Outram's own failures include upside-down poses). 8 deg: a
  // road's grade (<= ~10%, 5.7 deg) plus mounting; clique poses of few mid-height centroids came out
  // tilted 8-12 deg at the right place. 0 disables.
  float max_tilt_deg = 8.0f;
  // The missing twin (detail/twin_completion.h): after verification, the other headings' best hypotheses
  // moved by the displacements between the answer and its twins are snapped onto the map's instances
  // and verified; one that outscores the answer joins a second choice. One-shot only (a prior's disc
  // holds its own place). Off: the hypotheses as generated.
  bool complete_twins = true;
  // The answer's height is then the weighted median vertical offset of every correspondence that the
  // answer places within tls_threshold in x and y (answer_height.h), not its hypothesis's own (for a
  // shift vote, the mean of a few votes, each as high as the part of a trunk the scan saw).
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
  // ... and the best `refine_turned` of the fully scored ones turned more than 90 deg from the best: in a
  // hall or a symmetric street the true pose can be the 180-degree twin of the best, whose clique pose is
  // a few metres off and scores low until searched (issue 24: the confident wrong answers were flips).
  // Only with refine_top > 0 (the best is the first searched); a prior's global check searches none.
  // With a prior at most 2 and 1 (its disc holds one or two places: localizer.cpp, disc_verify_config).
  // 3, not 2, since 2026-12-07: in a hall the truth can be the third-best turned one (fresh seeds 31-32:
  // confident wrong 24 -> 21, answered right the same; 3-4% more instructions a query).
  uint32_t refine_turned = 3;
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

// Point-to-plane refinement against the map's refinement layer (detail/refine.h).
struct RefineConfig {
  bool enabled = false;
  uint32_t max_points = 2000;  // query points used (deterministic stride subsample)
  uint32_t iterations = 10;
  float radius_start = 1.5f;    // m, correspondence radius of the first iteration (<= 1.5 cell)
  float radius_end = 0.5f;      // m, of the last
  float cell = 1.0f;            // m, grid cell: must equal the map's (MapParams::refine_cell)
  float max_correction = 3.0f;  // m, larger moves are rejected
  uint32_t min_inliers = 100;
};

// The answer's confidence (detail/confidence.h).
struct ConfidenceConfig {
  // The default decision rule: LocalizeResult::confident = confidence >= min_probability.
  float min_probability = 0.9f;
  // Query voxels the confidence scores the answer and each of its probes and rivals on (a uniform
  // stride). Twice verify.max_points: a 32-beam scan's 5-6k voxels whole. The probes compare the answer
  // with poses a few metres or a half turn away; under label noise the voxels that tell them apart are a
  // few fence or hedge cues, and a stride of 2 dropped half of them (seeds 7-8: 93.6 -> 94.9% of right
  // answers vouched for, docs/confidence.md). kConfidenceModel is fitted at this value.
  uint32_t probe_points = 8192;
};

// Tracking after a fix: Localizer::track (detail/tracker.h, docs/vehicle-modes.md).
struct TrackConfig {
  // Bind the refiner (RefineConfig, its workspace) even when one-shot refinement is off, so track() can
  // refine; off: track() uses the pattern search alone.
  bool refine = true;
  uint32_t search_rounds = 4;    // pattern-search rounds around the prediction (steps halved each round)
  float search_step_m = 1.0f;    // m, first round's move; reaches about 2 x (1 + 1/2 + ...) = 3.75 m
  float search_step_deg = 2.0f;  // deg, first round's turn; reaches about 7.5 deg
  // ICP's budget (at most RefineConfig's max_points / iterations): the search leaves it within a cell.
  uint32_t icp_points = 1000;
  uint32_t icp_iterations = 6;
  // ICP starts from the prediction when the pattern search ends within these of it (the verification
  // score is flat within a semantic cell), else from the search's pose. 0: always from the search's.
  float icp_start_m = 1.0f;
  float icp_start_deg = 2.0f;
  // The confidence probes' sample: at most this many scan voxels (0: verify.max_points, the default).
  // 2,048 saves 0.25 ms but turned one confident tracked scan of seed 10 into a (recovered) loss.
  uint32_t probe_points = 0;
  // Voxelize the scan's logits (a softmax per point) when it carries them; off: its labels alone (one-hot
  // per point). Tracking reads only the voxels' centroids and argmax labels.
  bool use_logits = false;
};

// Localizer::localize_sequence: several scans tied by odometry (detail/scan_window.h).
struct WindowConfig {
  // N: the scans combined (this one and the last N - 1 given to localize_sequence); 1: off (no memory).
  uint32_t scans = 3;
  // K: poses each scan keeps for its successors (its answer, then its rivals).
  uint32_t candidates = 4;
};

}  // namespace gsf
