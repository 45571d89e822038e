// Internal (gsf/detail): a pipeline stage or building block, not part of the stable interface; it may
// change between versions. The stable interface is localizer.h, config.h, map_format.h, scan.h, status.h,
// platform.h, class_table.h, georeference.h and the C API gsf.h.
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
#include "gsf/status.h"

namespace gsf {

struct HypothesisConfig {
  // K: hypotheses per query. A 14 x 10 lattice has 140 shifts a heading and the shift votes share the
  // slots among up to shift_headings headings; 96 left the true shift out in lattice zones (suite seeds
  // 1-5, lattice zone 86.5% at 96, 97.0% at 192; docs/results.md). Verification scores each coarsely.
  uint32_t max_hypotheses = 192;
  uint32_t max_peeled = 8;      // of which from peeled maximum cliques; the rest from shift votes,
                                // shared evenly by the headings
  uint32_t shift_headings = 4;  // distinct clique headings whose translations are voted on
  // Heading-diverse cliques: after peeling, while fewer than shift_headings distinct headings were found,
  // up to this many more clique searches run with the consistency graph's edges at the found headings
  // removed (pair directions within heading_separation_deg), so each finds a clique at another heading.
  // In a symmetric layout (a lattice's 90 / 180 deg turns, a row's or avenue's 180) every large clique can
  // share one wrong heading, and the shift votes then never see the true one. 0 = off.
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
  // The answer's height is then the weighted median vertical offset of every correspondence that the
  // answer places within tls_threshold in x and y (answer_height.h), not its hypothesis's own (for a
  // shift vote, the mean of a few votes, each as high as the part of a trunk the scan saw).
};

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
  bool new_heading(const Run& r, uint32_t hp) const;
  uint32_t distinct_headings(const Run& r) const;
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
