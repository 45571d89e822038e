// The Localizer facade: init(config, map, buffer) once, then localize(scan) -> LocalizeResult, with no
// heap use, no exceptions and bounded work per call. Stages (one file each) run in a fixed order:
//   voxel layer -> instances (+ geometric poles) -> query fields -> triangles -> ranked index matches -> GSF filter ->
//   correspondences (ranked) -> pose hypotheses (peeled max cliques + TLS) -> whole-scan verification
//   -> ambiguity -> optional refinement
#pragma once
#include <cstddef>
#include <cstdint>

#include <Eigen/Geometry>

#include "gsf/config.h"
#include "gsf/map_format.h"
#include "gsf/platform.h"
#include "gsf/position_prior.h"
#include "gsf/scan.h"
#include "gsf/stage_results.h"
#include "gsf/status.h"

namespace gsf {

class Arena;           // detail/arena.h: the bump allocator init() binds the stages with
struct WindowOutcome;  // detail/scan_window.h: what the several-scan window found

struct StageTimes {  // nanoseconds from the Clock given at init (all zero without one)
  // match: index lookups and ranking (with the heading votes); gsf: the GSF filter and correspondence accumulation;
  // clique: the hypotheses (cliques + TLS poses); pose: verification and the answer's height; confidence: the
  // answer's comparisons with wrong poses (confidence.h); window: localize_sequence's step after the one-shot
  // (entering the scan, combining or checking; in total too).
  uint64_t voxel = 0, cluster = 0, field = 0, triangle = 0, match = 0, gsf = 0, clique = 0, pose = 0, confidence = 0,
           refine = 0, window = 0, total = 0;
};

// One pose hypothesis as the localizer saw it (diagnostics).
struct HypothesisReport {
  float x = 0, y = 0, yaw_deg = 0;  // map_T_scan translation (map-local) and heading
  uint32_t clique_size = 0, inliers = 0;
  float support = 0;                                // sum of inlier weights
  float verified_score = 0;                         // agree - disagree (semantic_grid.h); 0 without verification
  uint32_t verified_voxels = 0;                     // voxels that landed on known cells
  float verified_agree = 0, verified_disagree = 0;  // the score's two stability-weighted parts
  uint32_t verified_unknown = 0;                    // sampled voxels that landed outside the map's semantic layer
  bool fully_verified = false;                      // scored on verify.max_points (else only the coarse sample)
  // Its place among all the hypotheses, as LocalizeResult::chosen_hypothesis counts (0 = the maximum
  // clique): the reports are ranked by verified score, so report k is the answer when index equals it.
  uint32_t index = 0;
};
constexpr uint32_t kMaxReportedHypotheses = 16;  // the best by verified score (all of them when fewer)
constexpr uint32_t kMaxWindowScans = 4;          // WindowConfig::scans at most (localize_sequence)

struct LocalizeResult {
  Status status = Status::NotInitialized;
  // The pose twice (georeference.h). map_T_scan: map-local frame, relative to the map origin - what
  // every stage computes in, and the frame of the map's own coordinates (instances, hypotheses below).
  // map_frame_T_scan: the same pose in the map's frame (MapView::georef.frame, the frame the mapping
  // poses were in, e.g. UTM metres): map_T_scan with the origin added to the translation in double. Both
  // map scan points (p = R p_scan + t); the rotations are equal. Without an answer map_T_scan is the
  // identity and map_frame_T_scan the origin (the identity before init).
  Eigen::Isometry3d map_T_scan = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d map_frame_T_scan = Eigen::Isometry3d::Identity();
  uint32_t inliers = 0;  // correspondences agreeing with the pose (after TLS)
  uint32_t clique_size = 0;
  double score = 0.0;  // sum of inlier weights
  // Calibrated probability that map_T_scan is right (translation < 5 m and rotation < 10 deg from the
  // truth); 0 without an answer. `confident` is the default decision rule, confidence >=
  // config.confidence.min_probability: act on the pose only when it is true. At most 0.5 when fewer
  // than a third of the scan's sampled voxels land on cells the map observed
  // (confidence_evidence.known_share): a scan mostly beyond the map is never vouched for.
  double confidence = 0.0;
  bool confident = false;
  ConfidenceEvidence confidence_evidence;  // what the confidence was computed from (diagnostics)
  uint32_t scan_voxels = 0;                // voxels of the query's layer (at most voxel.max_voxels)
  uint32_t pole_instances = 0;             // geometric pole / trunk instances among query_instances
  uint32_t pole_instances_dropped = 0;     // ... not kept because cluster.max_instances was full
  uint32_t query_instances = 0, query_triangles = 0, triangle_matches = 0, gsf_survivors = 0, correspondences = 0;
  // What each cap dropped (all ranked before cutting), so a failure can be traced to a cap.
  uint32_t match_candidates = 0;         // map triangles accepted by labels and sides, before the per-triangle cap
  uint32_t match_dropped = 0;            // ... dropped by match.max_matches_per_triangle
  bool sparse_rematch = false;           // too few candidates: matched at triangle.sparse_side_tolerance
  uint32_t tie_ordered_triangles = 0;    // query triangles also tried in a tied vertex order
  uint32_t headings_kept = 0;            // yaw bins the heading votes let through (match.heading_bins)
  uint32_t heading_dropped = 0;          // kept matches whose heading was not among them
  uint32_t candidate_pairs = 0;          // distinct (query, map) instance pairs from surviving matches
  uint32_t below_gate_matches = 0;       // matches below the GSF gate that filled a short pair set
  uint32_t candidate_pairs_dropped = 0;  // pairs refused because match.max_candidates was full
  uint32_t correspondences_dropped = 0;  // pairs ranked out by match.max_correspondences
  uint32_t mirrored_matches = 0;         // triangle matches refused as mirror images (triangle.h)
  uint32_t vote_pairs = 0;               // pairs the shift votes saw (hypotheses.shift_vote_pairs)
  uint32_t vote_pairs_dropped = 0;       // ... and pairs ranked out of them
  uint32_t clique_searches = 0;
  uint32_t hypotheses = 0;         // distinct pose hypotheses (<= hypotheses.max_hypotheses)
  uint32_t chosen_hypothesis = 0;  // index of the answer among them (0 = the maximum clique; HypothesisReport::index)
  bool verified = false;           // the answer was chosen by whole-scan verification
  // What verification charged a voxel on a cell of another above-ground class, estimated for this scan
  // (detail/disagree_weights.h); every other disagreement costs verify.disagree_weight.
  float other_class_weight = 0.0f;
  uint32_t height_votes = 0;  // correspondences whose median set the answer's height (0: its hypothesis's)
  // The missing twin (detail/twin_completion.h, hypotheses.complete_twins): poses proposed from the
  // ranked hypotheses' repetition, and those of them that outscored the first answer and joined a second
  // choice among the hypotheses (`hypotheses`, `chosen_hypothesis` and the reports are then that choice's).
  uint32_t twins_proposed = 0, twins_found = 0;
  HypothesisReport hypothesis[kMaxReportedHypotheses];
  uint64_t clique_nodes = 0;
  uint32_t field_probes = 0;        // query-field probes computed by the GSF filter (cost driver)
  uint32_t field_comparisons = 0;   // (query instance, map instance, yaw bin) similarities computed
  bool refined = false;             // refinement ran and its result was accepted
  bool budget_exhausted = false;    // the first clique search ran out of nodes; its best clique is used
  bool capacity_truncated = false;  // some stage hit a Config capacity and kept a deterministic subset
  StageTimes times;
  // Vehicle modes (docs/vehicle-modes.md).
  bool prior_used = false;                  // localize() was given a position prior
  uint32_t prior_outside_matches = 0;       // map triangle candidates refused as outside the prior
  uint32_t prior_dropped_hypotheses = 0;    // hypotheses outside the prior's disc or heading
  uint32_t prior_dropped_best_inliers = 0;  // the most TLS inliers of one of them
  // What the check's trigger read (Localizer::localize with a prior), before the check could lower it:
  // whether the prior's own answer was confident, and its z_rival against the disc's rivals.
  bool prior_confident_before_check = false;
  float prior_trigger_z_rival = 0.0f;
  bool tracked = false;                 // the result of track(): no instances, triangles or hypotheses
  bool prior_global_check = false;      // a global search checked the prior's answer (thin margin)
  bool prior_contradicted = false;      // ... and gave another pose: confidence <= 1 - its confidence
  bool prior_asked_one_shot = false;    // the prior's answer was not confident: one-shot ran too
  bool prior_one_shot_vouched = false;  // ... was confident at the same pose: this is its result
  // Several scans (localize_sequence): this scan's number in the sequence (calls since reset_sequence,
  // from 0), its own one-shot confidence, and the scans whose evidence made the answer: window_scans of
  // them (1: this scan alone), their numbers in window_ids, newest (this one) first.
  uint32_t sequence_index = 0;
  double single_confidence = 0.0;
  bool window_combined = false;  // the answer is the window's (this scan alone was not confident)
  uint32_t window_scans = 0;
  uint32_t window_ids[kMaxWindowScans] = {};
  uint32_t window_candidates = 0;    // distinct poses the window scored
  bool window_checked = false;       // a confident answer with a thin margin was checked by the window
  bool window_contradicted = false;  // ... which put it elsewhere: replaced, or confidence <= 1 - the window's
  // The vehicle loop (localize_next): tracking was tried on this scan and lost (not confident), so the
  // answer is the one-shot's (with the GNSS prior when given, else localize_sequence's) on the same scan.
  bool track_lost = false;
};

class Localizer {
 public:
  // Bytes of the caller buffer init() needs for this config (independent of the map).
  static size_t required_bytes(const LocalizerConfig& config);

  // The same total broken down by stage (for memory budgets). Recorded by the one layout function while
  // it binds, so the parts always sum to required_bytes (other = the Impl object and its alignment).
  struct Budget {
    size_t voxel, cluster, poles, field, triangle, match, gsf_cache, correspondence, clique, refine, window, other,
        total;
  };
  static Budget budget(const LocalizerConfig& config);

  // `map` must stay valid (and its blob unchanged) for the Localizer's lifetime. The map's build
  // parameters must agree with config (field, grid, triangles): otherwise ConfigMismatch. `buffer`
  // must be 16-byte aligned (InvalidArgument otherwise) and at least required_bytes(config) long.
  Status init(const LocalizerConfig& config, const MapView& map, void* buffer, size_t bytes, Clock* clock = nullptr);

  // One-shot global localization of one scan. Always fills `out` (status inside as well as returned).
  Status localize(const ScanView& scan, LocalizeResult* out);
  // The same with a position prior (position_prior.h): only map triangles near the prior are matched and
  // only hypotheses inside it are answers. InvalidArgument for an invalid prior (validate()); NoSolution
  // when no hypothesis lies inside it. A wrong prior gives a wrong answer at low confidence or none: a
  // confident answer with a thin margin over its rivals (z_rival below kPriorGlobalCheckZ), however well
  // it agrees with the map, or one no triangle match confirms beyond its own clique (inliers <=
  // hypotheses.min_inliers), is checked by a global search from the scan's own triangles
  // (prior_global_check): a pose elsewhere that verification scores higher takes the answer's confidence
  // down to at most 1 - its own, or replaces the answer when it lies in the prior's disc (prior_contradicted);
  // one that scores a little lower is one more rival in the answer's confidence (a near tie). Not caught:
  // a disc holding a turned copy of a repetitive scene whose rivals there are weak (position_prior.h);
  // a heading in the prior rules it out. The query (and its check) runs on the scan's labels without the GSF filter:
  // the disc narrows the candidates as the filter would, so the logits are not read (docs/vehicle-modes.md).
  // An answer left not confident that the check did not contradict is localized again without the prior
  // (prior_asked_one_shot): when one-shot is confident at the same pose (hypotheses.same_pose_m / _deg),
  // its result is returned (prior_one_shot_vouched), so a prior never answers less than one-shot would;
  // after that call last_instances() / last_correspondences() / score_pose() describe the one-shot run.
  Status localize(const ScanView& scan, const PositionPrior& prior, LocalizeResult* out);

  // Tracking (detail/tracker.h): the pose of `scan` near `predicted_map_frame_T_scan` (the map's frame,
  // as LocalizeResult::map_frame_T_scan: e.g. the last pose times odometry): ICP from the prediction
  // against the map's refinement layer (config.track.refine), kept when the confidence's probes vouch
  // for it; otherwise a pattern search of whole-scan verification, ICP and the probes again. Bounded
  // work, no global search. Loss = !out->confident: fall back to
  // localize(). InvalidArgument for a prediction that is not a rigid pose (non-finite, a rotation off by
  // more than 1e-3) or lies over 1000 km from the map's origin, Unsupported for a map without a semantic
  // layer.
  Status track(const ScanView& scan, const Eigen::Isometry3d& predicted_map_frame_T_scan, LocalizeResult* out);

  // Several scans tied by odometry (detail/scan_window.h, docs/vehicle-modes.md): localize(scan) one-shot;
  // when that is not confident and the last config.window.scans - 1 scans of the sequence are held, their
  // candidate poses and this scan's are moved to this scan through the odometry and scored on all the
  // window's scans together, and the confidence comes from that combined evidence (window_combined,
  // window_scans, window_ids). The window's answer replaces the single scan's when its confidence is
  // higher and this scan agrees with it about as well as the older ones do (a wrong odometry moves their
  // poses where this scan is not: ScanWindow, newest_agrees). A confident answer with a thin margin over
  // its rivals (z_rival < kWindowCheckZ) is checked by the window: if the combined scans put the scan
  // elsewhere (at a pose this scan agrees with as well), the window's answer replaces it when more
  // confident, else it keeps at most 1 - the window's confidence (window_checked, window_contradicted).
  // `previous_T_scan`: this scan's pose in the previous scan's frame (odometry between the two calls' scans); ignored
  // on the first call after init() or reset_sequence(). Every call (whatever its status) enters the scan into the
  // window. InvalidArgument for an odometry that is not a rigid pose (non-finite, a rotation off by more
  // than 1e-3) or a step over 1 km (the window is reset). With window.scans = 1 this is
  // localize(scan) with sequence numbers.
  Status localize_sequence(const ScanView& scan, const Eigen::Isometry3d& previous_T_scan, LocalizeResult* out);
  // Forgets the window: the next localize_sequence() starts a sequence (after a gap in the odometry).
  void reset_sequence();

  // The vehicle loop of docs/vehicle-modes.md in one call per scan: while the last scan's pose was
  // confident, track() from it times the odometry; at start-up and on a loss (the tracked pose not
  // confident: track_lost), the same scan is localized again from scratch, with `gnss` as a position
  // prior when given (nullptr: none), else by localize_sequence: until the first confident answer the
  // last scans settle a repetitive place together (the window restarts after a tracked scan and after a
  // prior's answer: it holds consecutive scans localized from scratch). `previous_T_scan`: this scan's pose in the
  // previous scan's frame (odometry since the previous call); ignored on the first call after init() or reset_drive().
  // Act on the pose only when out->confident. InvalidArgument for an odometry that is not a rigid pose or a step over 1
  // km (the drive restarts). Calls to localize(), track() or localize_sequence() between two calls break the odometry
  // chain: call reset_drive() after them, and after an odometry fault (the window reads scans through
  // the odometry; docs/vehicle-modes.md, *The loop in the library*).
  Status localize_next(const ScanView& scan, const Eigen::Isometry3d& previous_T_scan, const PositionPrior* gnss,
                       LocalizeResult* out);
  // Forgets the drive (the pose and the window): the next localize_next() is a start-up.
  void reset_drive();

  // The correspondences the last localize() passed to the max clique (for pictures and debugging):
  // copies up to `max` into `out`, returns how many there were.
  struct Correspondence {
    uint32_t query_instance, map_instance;
    float query_xyz[3];
    float weight;
    bool in_clique;
  };
  uint32_t last_correspondences(Correspondence* out, uint32_t max) const;
  // The query instances of the last localize() (clustered, then geometric poles): up to `max`
  // centroids (x, y, z in the scan frame) and labels; returns how many there were.
  uint32_t last_instances(float* xyz, uint8_t* labels, uint32_t max) const;
  // Whole-scan verification of any pose (map-local: to_map_local(map.georef, truth) for a ground truth in
  // the map's frame) against the last scan, scored as verification scores a hypothesis (its weights and
  // disagree_weight; diagnostics: how the ground truth would have scored against the answer). Zero
  // scores without a map semantic layer or before the first localize().
  PoseVerification score_pose(const Eigen::Isometry3d& map_T_scan) const;

  bool initialized() const { return initialized_; }
  const LocalizerConfig& config() const { return config_; }
  size_t workspace_bytes() const { return workspace_used_; }

  // A prior's confident answer whose z_rival is below this is checked by a global search (localizer.cpp).
  static constexpr float kPriorGlobalCheckZ = 4.0f;
  // ... and so is one when a hypothesis outside the prior's disc has at least this share of the answer's
  // TLS inliers: the scene repeats beyond the disc (localizer.cpp, localize with a prior).
  static constexpr double kPriorCopyInlierShare = 0.8;
  // The confidence of a one-shot or prior answer from a scan of fewer than hypotheses.min_inliers + 2
  // instances is at most this (localizer.cpp, capped_for_few_instances): such answers are right about
  // half the time, so the default rule (confidence.min_probability 0.9) never vouches for one. A window
  // of scans (localize_sequence) and tracking have their own evidence and are not capped.
  static constexpr double kFewInstancesConfidence = 0.5;

 private:
  struct Impl;  // stage objects, bound into the arena (defined in localizer.cpp only)
  static Status bind_workspace(Arena& arena, const LocalizerConfig& config, Impl& impl, Budget* parts);
  // scan_ready: the last call built this scan's voxels, instances, fields and triangles; start at matching.
  Status localize_in(const ScanView& scan, const PositionPrior* prior, LocalizeResult* out, bool scan_ready = false);
  void check_outside_prior(LocalizeResult& out);
  void ask_one_shot(const ScanView& scan, LocalizeResult& out);
  void apply_window(const WindowOutcome& window, LocalizeResult& out) const;
  void check_with_window(const WindowOutcome& window, LocalizeResult& out) const;
  // A sequence scan's confident answer whose z_rival is below this is checked by the window (localizer.cpp).
  static constexpr float kWindowCheckZ = 4.0f;
  LocalizerConfig config_{};
  MapView map_{};
  size_t workspace_used_ = 0;  // bytes of the caller's buffer init() bound
  Impl* impl_ = nullptr;
  Clock* clock_ = nullptr;
  bool initialized_ = false;
  // localize_next's state: the last confident pose (map frame), while there is one.
  bool has_drive_pose_ = false;
  Eigen::Isometry3d drive_pose_ = Eigen::Isometry3d::Identity();
  void settle_with_window(bool has_scan, LocalizeResult& out);
};

}  // namespace gsf
