// Internal (gsf/detail): a pipeline stage or building block, not part of the stable interface; it may
// change between versions. The stable interface is localizer.h, config.h, map_format.h, scan.h, status.h,
// platform.h, class_table.h, georeference.h, stage_configs.h, stage_results.h and the C API gsf.h.
// Pose hypotheses from the correspondences: the consistency graph is built once, then cliques are
// peeled one after another. Each maximum clique gives a weighted TLS pose (paper Eq. 8); every
// correspondence that agrees with that pose is removed before the next search, so the next clique is a
// genuinely different answer (in a lattice: the next lattice shift or rotation). Up to K hypotheses,
// each search with its own node budget, so the stage is bounded in memory and time.
//
// Peeling alone can miss the true shift of a lattice (its correspondences end up spread over mixed
// cliques), so the headings the cliques found are then completed by translation votes: every
// correspondence votes for b - R a, and the best-supported translations become hypotheses too.
//
// The first hypothesis is the paper's answer (the maximum clique); the verification stage
// (semantic_grid.h) re-ranks them against the whole scan.
#pragma once
#include <cstdint>

#include <Eigen/Geometry>

#include "gsf/detail/arena.h"
#include "gsf/detail/fixed_vector.h"
#include "gsf/detail/max_clique.h"
#include "gsf/detail/pose_solver.h"
#include "gsf/detail/semantic_grid.h"
#include "gsf/stage_configs.h"
#include "gsf/status.h"

namespace gsf {

struct PoseHypothesis {
  Eigen::Isometry3d map_T_scan = Eigen::Isometry3d::Identity();
  uint32_t clique_size = 0;
  uint32_t inliers = 0;  // TLS inliers
  double support = 0.0;  // sum of the inliers' GSF weights
  PoseVerification verification;
};

struct HypothesisStats {
  uint32_t searches = 0;          // clique searches run
  uint64_t nodes = 0;             // branch-and-bound nodes over all searches
  bool budget_exhausted = false;  // the first search ran out of nodes (best-so-far used)
  uint32_t merged = 0;            // cliques or vote peaks whose pose repeated an earlier hypothesis
  uint32_t voted = 0;             // vote peaks that gave a pose
  uint32_t tilted = 0;            // poses the upright prior re-solved upright (max_tilt_deg)
  uint32_t heading_cliques = 0;   // hypotheses from heading-diverse clique searches
  uint32_t vote_pairs = 0;        // pairs the shift votes saw
};

// order = 0..n-1 sorted by key (shift-vote bin keys: x << 21 | y, 21 bits each), equal keys by index,
// as std::sort with that comparison would. A stable LSD radix sort of the keys made relative to their
// smallest x and y (a scan's translations span far fewer than 2^16 bins a side), 8 bits a pass, a pass
// skipped when every vote has the same digit; std::sort when the span is wider. The shift votes sort up
// to 8,192 votes once per heading tried. Scratch: n words each.
void sort_by_shift_key(const uint64_t* key, uint32_t n, uint32_t* order, uint32_t* scratch_key,
                       uint32_t* scratch_order);

class PoseHypotheses {
 public:
  static constexpr uint32_t kMaxHypotheses = 256;
  // max_votes: pairs the shift votes may see (>= max_correspondences; 0 = max_correspondences).
  static size_t required_bytes(uint32_t max_correspondences, uint32_t max_hypotheses, uint32_t max_votes = 0);
  Status bind(Arena& arena, uint32_t max_correspondences, uint32_t max_hypotheses, uint32_t max_votes = 0);
  // a, b: n_votes x 3 query / map positions; w: n_votes weights (> 0), best first. The first n form the
  // consistency graph (cliques); the shift votes use all n_votes (>= n; 0 = n). Fills the hypotheses in
  // the order found (the first is the maximum clique's). NoSolution if no clique reaches min_inliers.
  Status generate(const float* a, const float* b, const float* w, uint32_t n, const HypothesisConfig& config,
                  HypothesisStats* stats, uint32_t n_votes = 0);

  uint32_t size() const { return count_; }
  PoseHypothesis& operator[](uint32_t i) { return hyps_[i]; }
  const PoseHypothesis& operator[](uint32_t i) const { return hyps_[i]; }
  // 1 for correspondences in hypothesis h's clique (h < size()); n entries.
  bool in_clique(uint32_t h, uint32_t i) const { return i < max_n_ && owner_[i] == h + 1; }
  // Keeps the hypotheses h with keep[h] != 0 (size() entries), in their order; a correspondence whose
  // clique was dropped belongs to none. Returns how many were dropped (a position prior's filter).
  uint32_t retain(const uint8_t* keep);
  // Appends a hypothesis found outside generate() (twin_completion.h; no clique of its own, so no
  // correspondence is in_clique of it). False when max_hypotheses are held.
  bool add(const PoseHypothesis& h) {
    if (count_ >= max_h_) return false;
    hyps_[count_++] = h;
    return true;
  }

 private:
  struct Run;  // one generate() call: its inputs, config, thresholds and stats (pose_hypotheses.cpp)
  // The steps of generate(), in order.
  void peel_cliques(Run& r);
  void find_heading_cliques(Run& r);
  void vote_shifts(Run& r);
  // Their parts.
  bool fit_clique(Run& r, TlsResult* tls, uint32_t* m);
  bool refit(const Run& r, const Eigen::Isometry3d& pose, TlsResult* out, uint32_t* used);
  bool record(Run& r, const TlsResult& tls, uint32_t core_size, uint32_t m);
  bool make_upright(Run& r, TlsResult* tls, uint32_t m);
  bool repeats_earlier(Run& r, const Eigen::Isometry3d& pose) const;
  uint32_t ranked_headings(const Run& r, uint32_t* heads);
  void vote_at_heading(Run& r, const Eigen::Matrix3d& R, uint32_t stop);
  uint32_t bin_votes(const Run& r, const Eigen::Matrix3d& R);
  void bring_best_bin_to(uint32_t taken, uint32_t bins);
  bool fit_translation(const Run& r, const Eigen::Matrix3d& R, uint32_t i0, uint32_t all_bins, Eigen::Vector3d* t,
                       uint32_t* m);
  uint32_t gather_votes(const Run& r, const Eigen::Vector3d& t, double radius, uint32_t all_bins);
  void copy_to_sub(const Run& r, uint32_t slot, uint32_t i);
  void allow_all(uint32_t n);
  bool is_allowed(uint32_t i) const { return ((allowed_[i >> 6] >> (i & 63)) & 1u) != 0; }
  void disallow(uint32_t i) { allowed_[i >> 6] &= ~(uint64_t(1) << (i & 63)); }
  // Shift votes: from `bins` bins in key order (bin_key_, bin_first_, bin_weight_, bin_count_, bin_begin_) keeps,
  // in key order, those with min_inliers supporting votes (bin_rank_ 2) and the others with min_inliers
  // votes of their own (1), bin_weight_ then holding the support; returns how many.
  uint32_t rank_shift_bins(uint32_t bins, const float* w, const HypothesisConfig& config);
  // Bin (among the first `bins` of bin_key_, in key order) of key, or UINT32_MAX.
  uint32_t find_bin(uint64_t key, uint32_t bins) const;
  ConsistencyGraph graph_;
  MaxCliqueSolver solver_;
  FixedVector<uint32_t> clique_;
  uint64_t* allowed_ = nullptr;  // words
  uint32_t* owner_ = nullptr;    // per correspondence: 1 + hypothesis whose clique took it, 0 none
  float* sub_a_ = nullptr;
  float* sub_b_ = nullptr;
  float* sub_w_ = nullptr;
  float* tls_w_ = nullptr;
  uint8_t* mask_ = nullptr;
  PoseHypothesis* hyps_ = nullptr;
  uint64_t* vote_key_ = nullptr;    // n: translation bin of each correspondence (shift votes)
  uint32_t* vote_order_ = nullptr;  // n
  uint32_t* bin_first_ = nullptr;   // n: a correspondence of each bin
  float* bin_weight_ = nullptr;     // n: the bin's summed weight
  uint32_t* bin_count_ = nullptr;   // n: the bin's correspondences
  float* bin_support_ = nullptr;    // n: the bin's support (weight of the votes near its mean)
  uint8_t* bin_rank_ = nullptr;     // n: rank class (rank_shift_bins)
  uint32_t* bin_begin_ = nullptr;   // n + 1: a bin's votes are vote_order_[begin[k], begin[k + 1])
  float* vote_t_ = nullptr;         // 2n: each correspondence's bird's-eye translation vote
  uint64_t* bin_key_ = nullptr;     // n: each bin's key, in key order (not compacted: the fits look bins up)
  uint32_t* gather_ = nullptr;      // v: the votes one translation fit reads
  uint32_t max_n_ = 0, max_h_ = 0, max_v_ = 0, count_ = 0;
};

}  // namespace gsf
