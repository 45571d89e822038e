// Internal (gsf/detail): a pipeline stage or building block, not part of the stable interface; it may
// change between versions. The stable interface is localizer.h, config.h, map_format.h, scan.h, status.h,
// platform.h, class_table.h, georeference.h, stage_configs.h, stage_results.h and the C API gsf.h.
// Tracking: the pose of a scan near a predicted pose (the last pose and odometry), without the global
// search (docs/vehicle-modes.md). Each step bounded:
//   0. point-to-plane ICP from the prediction against the map's refinement layer (refine.h); when it is
//      accepted, ends within one pass of the pattern search's reach of the prediction (1.875 m / 3.75
//      deg, where ICP alone converges well) and the probes of step 3 vouch for it (confidence >=
//      min_probability), that is the answer: a good prediction needs no search. Otherwise:
//   1. a bird's-eye pattern search of whole-scan verification around the prediction (semantic_grid.h:
//      verify_pose_refined, steps of search_step_m / search_step_deg halved each round), which takes a
//      prediction a few metres and degrees off to within about a cell of the map's semantic layer;
//   2. ICP, for centimetres, when the map has that layer (accepted only within its correction limit, as
//      for one-shot): step 0's result when the search ended within TrackConfig::icp_start_m /
//      icp_start_deg of the prediction (the score is flat within a cell, where the search wanders up to
//      a metre; ICP from the prediction did better), else ICP from the search's pose;
//   3. the confidence's probe statistic at the result (confidence.h): the shifted and turned probes,
//      no rivals (there are no other hypotheses). The 180-degree probe counts only where it scores
//      above the result: a flip lies far beyond the search's reach of the prediction, so what rules it
//      out is the prediction (a confident pose and an odometry), unless the scan itself prefers the
//      flip; at the right pose in a symmetric hall the flip scores only a little lower, and under
//      label noise that margin had read as a loss (docs/vehicle-modes.md, *Tracking in a symmetric
//      place*). The inlier factor is left out: tracking forms no instances; it guards one-shot answers
//      in a map of somewhere else, and a tracked pose follows a confident one. Its own model
//      (kTrackingConfidenceModel): the one-shot model is fitted on answers that have rivals, and the
//      rival's margin of a probe 2 m off (tracking's stand-in) is another quantity: TrackingConfidenceModel
//      below, its turn factor fitted on tracking attempts.
// Loss is "not confident": the caller falls back to one-shot localization. A prediction far off ends
// where the pattern search can reach (a few metres), which the probes judge as any wrong pose: no peak.
// A result that ICP took beyond the search's reach of the prediction in position (3.75 m by default: two
// passes a round, semantic_grid.h) is a loss whatever the probes say: tracking vouches only for a pose
// near its prediction.
#pragma once
#include <cstdint>

#include <Eigen/Geometry>

#include "gsf/detail/confidence.h"
#include "gsf/detail/refine.h"
#include "gsf/detail/semantic_grid.h"
#include "gsf/detail/voxel_layer.h"
#include "gsf/platform.h"
#include "gsf/stage_configs.h"

namespace gsf {

// What track() found.
struct TrackOutcome {
  Eigen::Isometry3d map_T_scan = Eigen::Isometry3d::Identity();
  bool refined = false;  // ICP ran and its result was accepted
  ConfidenceEvidence evidence;
  double confidence = 0.0;
  uint64_t search_ns = 0, refine_ns = 0, probe_ns = 0;  // the three steps' times (0 without a clock)
};

// The scan as verification reads it (voxelized from the labels alone unless TrackConfig::use_logits)
// (answer_selection.h prepares the compact points and weights).
struct TrackScan {
  const VerifyPoint* points;
  uint32_t n;
  const VoxelLayer& voxels;
  const float* weights;  // this scan's verification weights
  SearchMemo* memo;      // the pattern search's record (semantic_grid.h; nullptr: none)
};

// The steps above. refiner: nullptr (or without a map layer) skips steps 0 and 2. clock: optional.
TrackOutcome track_pose(const TrackScan& scan, const SemanticGridView& grid, const Eigen::Isometry3d& predicted,
                        const TrackConfig& config, const VerifyConfig& verify, double min_probability, Refiner* refiner,
                        AnswerConfidence& confidence, Clock* clock = nullptr);

// P of a tracked pose (see above): s(a_r + b_r z_rival) s(a_s + b_s z_shift) s(a_t + b_t z_turn), each z
// clipped to [-3, 10] as in confidence.h; z_rival is the closest probe's (a tracked pose has no rivals).
// The rival and shift factors are the one-shot model of 2026-11's, with which tracking was measured on
// the real drives: their right tracked poses have z_shift 1.2-1.8, and a refit of all six numbers on
// the simulator's attempts asked 1.8 (the simulator's scans hold more structure), declining a third
// more of them. The turn factor is fitted (bench/fit_tracking.py, 2026-12-06) on the attempts of the
// suite's tracking worlds, seeds 6-10, with and without label noise 0.15: from a good odometry, from
// poor ones (noise 0.3 and 1.0) and from predictions knocked up to 3, 4 and 8 m / deg off (gsf evaluate
// --prediction-offset), as a pose within 1 m / 5 deg (stricter than the library's 5 m / 10 deg, so
// P under-states that criterion, never over-states it). It asks z_turn of about 3 for 0.9 where the
// old one asked 4, which under label noise declined right poses at z_turn 3.5-3.9 (docs/vehicle-
// modes.md, *The search's whole reach, and a tracking model fitted on tracking*).
struct TrackingConfidenceModel {
  float rival_offset, rival_slope;
  float shift_offset, shift_slope;
  float turn_offset, turn_slope;
};
extern const TrackingConfidenceModel kTrackingConfidenceModel;
double tracking_probability(const ConfidenceEvidence& evidence);

}  // namespace gsf
