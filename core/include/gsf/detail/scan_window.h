// Internal (gsf/detail): a pipeline stage or building block, not part of the stable interface; it may
// change between versions. The stable interface is localizer.h, config.h, map_format.h, scan.h, status.h,
// platform.h, class_table.h, georeference.h and the C API gsf.h.
// Several scans tied by odometry (Localizer::localize_sequence, docs/vehicle-modes.md): a fixed window of
// the last N scans (N <= 4). Each scan leaves its verification sample (the strided voxels whole-scan
// verification reads, bird's-eye) and its K best poses (its answer and rivals, map-local). When the
// newest scan alone is not confident, every scan's candidates are moved to the newest scan through the
// odometry and scored on all the window's samples together (the older scans' samples moved into the
// newest scan's frame): a lattice's twin poses fit the newest scan alike, but the neighbours see more of
// the scene (and other label errors), so the combined score separates them. The confidence is then
// measured as for one scan (confidence.h) over the combined sample: its rivals are the other combined
// candidates, its probes shift and turn all scans together about the newest sensor.
// Memory: N x verify.max_points x 12 B of samples and N x K poses, bound at init. Work: at most N x K
// candidates scored on the combined sample, verify.refine_top of them pattern-refined, the probes.
#pragma once
#include <cstdint>

#include <Eigen/Geometry>

#include "gsf/detail/arena.h"
#include "gsf/detail/confidence.h"
#include "gsf/detail/semantic_grid.h"
#include "gsf/stage_configs.h"
#include "gsf/status.h"

namespace gsf {

struct VerifyConfig;
struct HypothesisConfig;

// A pose a scan offers the window (map-local map_T_scan of that scan), the instances of that scan it
// explained and their share of the scan's (the confidence's inlier factor).
struct WindowCandidate {
  Eigen::Isometry3d map_T_scan = Eigen::Isometry3d::Identity();
  float inlier_share = 0.0f;
  uint32_t inliers = 0;
};

// What combine() found.
struct WindowOutcome {
  static constexpr uint32_t kMaxScans = 4;
  bool combined = false;                                         // false: fewer than two scans held, or no candidate
  Eigen::Isometry3d map_T_scan = Eigen::Isometry3d::Identity();  // the newest scan's pose (map-local)
  PoseVerification verification;                                 // its score on the combined sample
  ConfidenceEvidence evidence;
  double confidence = 0.0;
  float inlier_share = 0.0f;  // the answer's candidate's (the largest of the scans that offered it)
  // Every held scan's own sample agrees with the answer about as well as the others (ScanWindow's
  // newest_agrees): the newest scan's agreement at most 0.1 below the older scans' lowest. A wrong odometry
  // (or a gap in it) moves the older scans' poses to a pose they agree on where the newest scan is not;
  // without this the answer neither replaces nor contradicts the scan's own (docs/vehicle-modes.md).
  bool newest_agrees = false;
  uint32_t candidates = 0;       // distinct candidates scored
  uint32_t scans = 0;            // scans whose samples were combined (the newest included)
  uint32_t ids[kMaxScans] = {};  // their sequence numbers, newest first
  uint32_t samples = 0;          // combined samples
};

class ScanWindow {
 public:
  static constexpr uint32_t kMaxScans = WindowOutcome::kMaxScans;
  static constexpr uint32_t kMaxCandidates = 8;
  static constexpr uint32_t kMaxRivals = 4;
  // max_points: verification's sample size (VerifyConfig::max_points). Nothing is bound for scans <= 1.
  static size_t required_bytes(const WindowConfig& config, uint32_t max_points);
  Status bind(Arena& arena, const WindowConfig& config, uint32_t max_points);
  bool bound() const { return slots_ != nullptr; }

  // Forgets every scan; the next begin_scan() starts a sequence (its number 0).
  void reset();
  // Starts the next scan: moves the held scans into its frame by previous_T_scan (the new scan's pose in
  // the previous scan's frame: odometry; ignored for the first scan of a sequence), drops the oldest
  // when the window is full, and adds the scan's sample: every stride-th of its n compact points
  // (verify_pose's strided sample of at most max_points). Returns the scan's sequence number.
  uint32_t begin_scan(const Eigen::Isometry3d& previous_T_scan, const VerifyPoint* points, uint32_t n);
  // The newest scan's candidates for its successors (at most `candidates`; best first).
  void set_candidates(const WindowCandidate* c, uint32_t n);
  uint32_t scans() const { return held_; }
  // Every held scan's sample in the newest scan's frame, oldest scan first (diagnostics and tests).
  const VerifyPoint* samples() const { return points_; }
  uint32_t sample_count() const { return held_ > 0 ? slots_[held_ - 1].first + slots_[held_ - 1].count : 0; }

  // The newest scan's pose from all held scans: `own` (the newest scan's candidates) and the older
  // scans' moved to it, scored on the combined sample (weights: the newest scan's verification weights),
  // where one puts most samples on the map those it knows half as well or less dropped (keep_known), the
  // best pattern-refined, and the confidence of the best against the others (`confidence`'s capacity
  // must hold the combined sample).
  WindowOutcome combine(const WindowCandidate* own, uint32_t n_own, const SemanticGridView& grid, const float* weights,
                        const VerifyConfig& vc, const HypothesisConfig& hc, AnswerConfidence& confidence);

 private:
  struct Slot {
    uint32_t first = 0, count = 0;  // its samples: points_[first .. first + count)
    uint32_t id = 0;                // sequence number
    Eigen::Isometry3d newest_T_scan = Eigen::Isometry3d::Identity();
    uint32_t candidates = 0;
    WindowCandidate cand[kMaxCandidates];
  };
  struct Scored {
    Eigen::Isometry3d pose;
    PoseVerification v;
    float inlier_share;
    uint32_t inliers;
  };
  void drop_oldest();
  uint32_t gather(const WindowCandidate* own, uint32_t n_own, float same_m, float same_deg);
  uint32_t keep_known(uint32_t n, uint32_t samples);
  uint32_t pick_rivals(uint32_t n, float same_m, float same_deg, Eigen::Isometry3d* rivals) const;
  bool newest_agrees(const SemanticGridView& grid, const float* weights, float lambda) const;

  VerifyPoint* points_ = nullptr;  // scans x max_points: every held scan's sample, in the newest scan's frame
  Scored* scored_ = nullptr;       // scans x candidates: the candidates of one combine()
  Slot* slots_ = nullptr;          // scans: the held scans, oldest first
  uint32_t capacity_scans_ = 0, capacity_candidates_ = 0, max_points_ = 0;
  uint32_t held_ = 0, next_id_ = 0;
};

}  // namespace gsf
