#include "gsf/detail/pose_hypotheses.h"

#include <algorithm>
#include <cmath>
#include <new>

#include "gsf/detail/angles.h"
#include "gsf/detail/pose_distance.h"
#include "gsf/detail/pose_solver.h"

namespace gsf {

namespace {

// Shift-vote bins: a coordinate's bin index offset by 2^20, and the key (x << 21) | y of a bin, both
// fields masked to 21 bits (callers that step to neighbouring bins check the range first).
int64_t shift_coord(double v, float bin) { return static_cast<int64_t>(std::floor(v / bin)) + (1 << 20); }
uint64_t shift_key(int64_t x, int64_t y) { return (uint64_t(x & 0x1FFFFF) << 21) | uint64_t(y & 0x1FFFFF); }

Eigen::Vector3d point(const float* p, uint32_t i) { return Eigen::Vector3d(p[3 * i], p[3 * i + 1], p[3 * i + 2]); }

// Upright at a hypothesis' heading: any clique of this heading may carry degrees of roll or pitch
// (mid-height centroids constrain them poorly), and the bird's-eye verification cannot see tilt, so a
// vote hypothesis must not inherit it.
Eigen::Matrix3d upright_at(const Eigen::Isometry3d& T) {
  return Eigen::AngleAxisd(yaw_of(T), Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

}  // namespace

void sort_by_shift_key(const uint64_t* key, uint32_t n, uint32_t* order, uint32_t* scratch_key,
                       uint32_t* scratch_order) {
  for (uint32_t i = 0; i < n; ++i) order[i] = i;
  if (n < 2) return;
  uint64_t x0 = UINT64_MAX, x1 = 0, y0 = UINT64_MAX, y1 = 0;
  for (uint32_t i = 0; i < n; ++i) {
    const uint64_t x = key[i] >> 21, y = key[i] & 0x1FFFFF;
    x0 = std::min(x0, x);
    x1 = std::max(x1, x);
    y0 = std::min(y0, y);
    y1 = std::max(y1, y);
  }
  if (x1 - x0 > 0xFFFF || y1 - y0 > 0xFFFF) {
    std::sort(order, order + n,
              [key](uint32_t a, uint32_t b) { return key[a] < key[b] || (key[a] == key[b] && a < b); });
    return;
  }
  uint32_t* rel = scratch_key;  // (x - x0) << 16 | (y - y0): the same order as the key
  for (uint32_t i = 0; i < n; ++i) rel[i] = uint32_t(((key[i] >> 21) - x0) << 16) | uint32_t((key[i] & 0x1FFFFF) - y0);
  uint32_t *from = order, *to = scratch_order;
  for (uint32_t shift = 0; shift < 32; shift += 8) {
    uint32_t count[257] = {};
    for (uint32_t i = 0; i < n; ++i) ++count[((rel[from[i]] >> shift) & 0xFF) + 1];
    if (count[((rel[from[0]] >> shift) & 0xFF) + 1] == n) continue;  // one digit for all: the order stays
    for (uint32_t d = 0; d < 256; ++d) count[d + 1] += count[d];
    for (uint32_t i = 0; i < n; ++i) to[count[(rel[from[i]] >> shift) & 0xFF]++] = from[i];
    std::swap(from, to);
  }
  if (from != order) std::copy(from, from + n, order);
}

size_t PoseHypotheses::required_bytes(uint32_t max_correspondences, uint32_t max_hypotheses, uint32_t max_votes) {
  return counted_bytes<PoseHypotheses>(max_correspondences, max_hypotheses, max_votes);
}

Status PoseHypotheses::bind(Arena& ar, uint32_t n, uint32_t k, uint32_t v) {
  max_n_ = max_h_ = max_v_ = count_ = 0;
  if (v == 0) v = n;
  if (n == 0 || n > 4096 || k == 0 || k > kMaxHypotheses || v < n || v > (1u << 20)) return Status::InvalidArgument;
  if (graph_.bind(ar, n) != Status::Ok || solver_.bind(ar, n) != Status::Ok) return Status::InvalidArgument;
  clique_.bind(ar, n);
  allowed_ = ar.allocate<uint64_t>((n + 63) / 64);
  owner_ = ar.allocate<uint32_t>(n);
  // The fits' scratch holds up to all the votes' pairs.
  sub_a_ = ar.allocate<float>(size_t(v) * 3);
  sub_b_ = ar.allocate<float>(size_t(v) * 3);
  sub_w_ = ar.allocate<float>(v);
  tls_w_ = ar.allocate<float>(v);
  mask_ = ar.allocate<uint8_t>(v);
  hyps_ = ar.allocate<PoseHypothesis>(k);
  vote_key_ = ar.allocate<uint64_t>(v);
  vote_order_ = ar.allocate<uint32_t>(v);
  bin_first_ = ar.allocate<uint32_t>(v);
  bin_weight_ = ar.allocate<float>(v);
  bin_count_ = ar.allocate<uint32_t>(v);
  bin_support_ = ar.allocate<float>(v);
  bin_rank_ = ar.allocate<uint8_t>(v);
  bin_begin_ = ar.allocate<uint32_t>(size_t(v) + 1);
  vote_t_ = ar.allocate<float>(size_t(v) * 2);
  bin_key_ = ar.allocate<uint64_t>(v);
  gather_ = ar.allocate<uint32_t>(v);
  if (ar.counting()) return Status::Ok;
  if (ar.overflowed()) return Status::BufferTooSmall;
  for (uint32_t i = 0; i < k; ++i) new (&hyps_[i]) PoseHypothesis();
  max_n_ = n;
  max_h_ = k;
  max_v_ = v;
  return Status::Ok;
}

uint32_t PoseHypotheses::find_bin(uint64_t key, uint32_t bins) const {
  uint32_t lo = 0, hi = bins;
  while (lo < hi) {
    const uint32_t mid = (lo + hi) / 2;
    if (bin_key_[mid] < key) lo = mid + 1;
    else hi = mid;
  }
  return lo < bins && bin_key_[lo] == key ? lo : UINT32_MAX;
}

uint32_t PoseHypotheses::rank_shift_bins(uint32_t bins, const float* w, const HypothesisConfig& c) {
  // Support of each bin: the weight (and number) of votes within tls_threshold of the mean of its own
  // votes. The radius is below a bin (validate: tls_threshold <= shift_bin), so only the 3 x 3 bins
  // around it can hold them; keys are (kx << 21) | ky with both fields offset by 2^20.
  // Rank classes: 2 for a bin with min_inliers supporting votes, 1 for one with min_inliers votes of
  // its own but less support (kept for free slots: no bin the plain ranking offered is lost), 0 dropped.
  // All supports first, then the compaction: it overwrites bins a later bin's neighbour search reads.
  const float r2 = c.tls_threshold * c.tls_threshold;
  auto rank = [&](uint32_t k, uint32_t support_count) {
    bin_rank_[k] = support_count >= c.min_inliers ? 2 : (bin_count_[k] >= c.min_inliers ? 1 : 0);
  };
  // The 3 x 3 bins around bin k are found from a cursor per neighbouring column at the first bin not
  // below the column's lowest key wanted (key + dx 2^21 - 1 as an integer, growing with k: a cursor only
  // moves forward): find_bin's answers, without its binary search per neighbour (9 a bin, the stage's
  // largest cost in a lattice's votes).
  struct Column {
    uint32_t base = 0;
    void seek(const uint64_t* keys, uint32_t n, int64_t lowest) {
      while (base < n && int64_t(keys[base]) < lowest) ++base;
    }
    uint32_t find(const uint64_t* keys, uint32_t n, uint64_t key) const {
      for (uint32_t i = base; i < n && keys[i] <= key; ++i)
        if (keys[i] == key) return i;
      return UINT32_MAX;
    }
  } column[3];
  for (uint32_t k = 0; k < bins; ++k) {
    for (int64_t dx = -1; dx <= 1; ++dx)
      column[dx + 1].seek(bin_key_, bins, int64_t(bin_key_[k]) + dx * (int64_t(1) << 21) - 1);
    float mx = 0.0f, my = 0.0f;
    for (uint32_t e = bin_begin_[k]; e < bin_begin_[k + 1]; ++e) {
      mx += vote_t_[2 * vote_order_[e]];
      my += vote_t_[2 * vote_order_[e] + 1];
    }
    const float inv = 1.0f / static_cast<float>(bin_begin_[k + 1] - bin_begin_[k]);
    mx *= inv;
    my *= inv;
    const uint64_t key = bin_key_[k];
    const int64_t kx = int64_t(key >> 21), ky = int64_t(key & 0x1FFFFF);
    float sw = 0.0f;
    uint32_t sc = 0;
    for (int64_t dx = -1; dx <= 1; ++dx)
      for (int64_t dy = -1; dy <= 1; ++dy) {
        const int64_t x = kx + dx, y = ky + dy;
        if (x < 0 || y < 0 || x > 0x1FFFFF || y > 0x1FFFFF) continue;
        const uint32_t j = column[dx + 1].find(bin_key_, bins, shift_key(x, y));
        if (j == UINT32_MAX) continue;
        for (uint32_t e = bin_begin_[j]; e < bin_begin_[j + 1]; ++e) {
          const uint32_t i = vote_order_[e];
          const float ex = vote_t_[2 * i] - mx, ey = vote_t_[2 * i + 1] - my;
          if (ex * ex + ey * ey > r2) continue;
          sw += w[i];
          ++sc;
        }
      }
    bin_support_[k] = sw;
    rank(k, sc);
  }
  uint32_t kept = 0;
  for (uint32_t k = 0; k < bins; ++k) {
    if (bin_rank_[k] == 0) continue;
    bin_first_[kept] = bin_first_[k];
    bin_weight_[kept] = bin_support_[k];
    bin_count_[kept] = bin_count_[k];
    bin_rank_[kept] = bin_rank_[k];
    ++kept;
  }
  return kept;
}

struct PoseHypotheses::Run {
  const float* a;  // n_votes x 3 query positions
  const float* b;  // n_votes x 3 map positions
  const float* w;  // n_votes weights
  uint32_t n, n_votes;
  const HypothesisConfig& c;
  uint32_t K;       // hypotheses wanted
  double far2;      // (2 tls_threshold)^2: what a core pose explains (refit, the first translation round)
  double c2;        // tls_threshold^2
  double same_rad;  // same_pose_deg
  double max_tilt;  // max_tilt_deg
  HypothesisStats st;

  // Squared residual of correspondence i under pose T.
  double residual2(const Eigen::Isometry3d& T, uint32_t i) const {
    return (point(b, i) - T * point(a, i)).squaredNorm();
  }
};

Status PoseHypotheses::generate(const float* a, const float* b, const float* w, uint32_t n, const HypothesisConfig& c,
                                HypothesisStats* stats_out, uint32_t n_votes) {
  count_ = 0;
  if (max_n_ == 0) return Status::NotInitialized;
  if (n_votes < n) n_votes = n;
  if (n > max_n_ || n_votes > max_v_) return Status::CapacityExceeded;
  for (uint32_t i = 0; i < n; ++i) owner_[i] = 0;
  if (n < c.min_inliers) {
    if (stats_out) *stats_out = HypothesisStats();
    return Status::NoSolution;
  }
  Run r{a,
        b,
        w,
        n,
        n_votes,
        c,
        c.max_hypotheses < max_h_ ? c.max_hypotheses : max_h_,
        4.0 * double(c.tls_threshold) * c.tls_threshold,
        double(c.tls_threshold) * c.tls_threshold,
        deg_to_rad(double(c.same_pose_deg)),
        deg_to_rad(double(c.max_tilt_deg)),
        HypothesisStats()};
  // 1. Peeled maximum cliques (the first is the paper's answer).
  graph_.build(a, b, n, c.consistency_eps, c.consistency_z_weight);
  peel_cliques(r);
  // 1b. Heading-diverse cliques, when the peeled ones found too few headings.
  find_heading_cliques(r);
  // 2. Shift votes at the headings found.
  vote_shifts(r);
  r.st.vote_pairs = n_votes;
  if (stats_out) *stats_out = r.st;
  return count_ > 0 ? Status::Ok : Status::NoSolution;
}

void PoseHypotheses::copy_to_sub(const Run& r, uint32_t slot, uint32_t i) {
  for (int d = 0; d < 3; ++d) {
    sub_a_[3 * slot + d] = r.a[3 * i + d];
    sub_b_[3 * slot + d] = r.b[3 * i + d];
  }
  sub_w_[slot] = r.w[i] > 1e-6f ? r.w[i] : 1e-6f;
}

void PoseHypotheses::allow_all(uint32_t n) {
  const uint32_t words = (n + 63) / 64;
  for (uint32_t i = 0; i < words; ++i) allowed_[i] = 0;
  for (uint32_t i = 0; i < n; ++i) allowed_[i >> 6] |= uint64_t(1) << (i & 63);
}

// Re-associate: every correspondence `pose` explains (within 2c) joins one TLS solve. A clique or a
// vote peak is a core; the pose of everything it explains is markedly more accurate, and
// verification compares poses at the 1 m scale of the semantic layer. False if too few agree.
bool PoseHypotheses::refit(const Run& r, const Eigen::Isometry3d& pose, TlsResult* out, uint32_t* used) {
  const HypothesisConfig& c = r.c;
  uint32_t m = 0;
  for (uint32_t i = 0; i < r.n; ++i)
    if (r.residual2(pose, i) <= r.far2) copy_to_sub(r, m++, i);
  *used = m;
  return m >= c.min_inliers &&
         solve_tls(sub_a_, sub_b_, sub_w_, m, c.tls_threshold, c.max_iterations, out, mask_, tls_w_) == Status::Ok &&
         out->inliers >= c.min_inliers;
}

// Records a hypothesis unless it repeats an earlier one; mask_/sub_w_ describe its TLS solve (m rows).
bool PoseHypotheses::record(Run& r, const TlsResult& tls_in, uint32_t core_size, uint32_t m) {
  TlsResult tls = tls_in;
  if (!make_upright(r, &tls, m) || repeats_earlier(r, tls.b_T_a)) return false;
  PoseHypothesis& h = hyps_[count_++];
  h = PoseHypothesis();
  h.map_T_scan = tls.b_T_a;
  h.clique_size = core_size;
  h.inliers = tls.inliers;
  for (uint32_t i = 0; i < m; ++i) h.support += mask_[i] ? sub_w_[i] : 0.0;
  return true;
}

// Upright prior: a vehicle's sensor is within max_tilt of level. A solve tilted more is re-solved
// upright (yaw and translation) on its inliers, then its inliers recounted: a clique of few mid-height
// centroids fixes heading and place well but tilt poorly, and rejecting it lost the right place; an
// upside-down solve rarely survives the recount. False when it does not.
bool PoseHypotheses::make_upright(Run& r, TlsResult* tls, uint32_t m) {
  const HypothesisConfig& c = r.c;
  const double cos_tilt = tls->b_T_a.linear()(2, 2);
  if (!(c.max_tilt_deg > 0 && cos_tilt < std::cos(r.max_tilt))) return true;
  ++r.st.tilted;
  if (fit_upright(sub_a_, sub_b_, sub_w_, mask_, m, &tls->b_T_a) != Status::Ok) return false;
  tls->inliers = 0;
  for (uint32_t i = 0; i < m; ++i) {
    const Eigen::Vector3d pa(sub_a_[3 * i], sub_a_[3 * i + 1], sub_a_[3 * i + 2]);
    const Eigen::Vector3d pb(sub_b_[3 * i], sub_b_[3 * i + 1], sub_b_[3 * i + 2]);
    mask_[i] = (pb - tls->b_T_a * pa).squaredNorm() <= r.c2;
    tls->inliers += mask_[i];
  }
  return tls->inliers >= c.min_inliers;
}

// Whether `pose` is within same_pose_m and same_pose_deg of an earlier hypothesis (counted as merged).
bool PoseHypotheses::repeats_earlier(Run& r, const Eigen::Isometry3d& pose) const {
  for (uint32_t h = 0; h < count_; ++h) {
    const Eigen::Isometry3d d = hyps_[h].map_T_scan.inverse() * pose;
    if (d.translation().norm() < r.c.same_pose_m && Eigen::AngleAxisd(d.linear()).angle() < r.same_rad) {
      ++r.st.merged;
      return true;
    }
  }
  return false;
}

// 1. Maximum cliques one after another, each with its TLS pose; what a pose explains leaves the graph
// before the next search, so the next clique is a genuinely different answer.
void PoseHypotheses::peel_cliques(Run& r) {
  const HypothesisConfig& c = r.c;
  allow_all(r.n);
  const uint32_t peel = c.max_peeled < r.K ? c.max_peeled : r.K;
  // Each search removes at least one correspondence of its clique, so 2K searches bound the loop.
  for (uint32_t attempt = 0; attempt < 2 * r.K && count_ < peel; ++attempt) {
    CliqueStats cs;
    const Status s = solver_.solve(graph_, r.st.searches == 0 ? c.first_budget : c.next_budget, clique_, &cs, allowed_);
    if (r.st.searches == 0 && s == Status::BudgetExhausted) r.st.budget_exhausted = true;
    ++r.st.searches;
    r.st.nodes += cs.nodes;
    const uint32_t q = clique_.size();
    if (q < c.min_inliers) break;
    TlsResult tls;
    uint32_t m = q;
    const bool fitted = fit_clique(r, &tls, &m);
    // The same clique must not come back: if none of its members left, all of them go.
    bool progressed = false;
    for (uint32_t i = 0; i < q && !progressed; ++i) progressed = !is_allowed(clique_[i]);
    if (!progressed)
      for (uint32_t i = 0; i < q; ++i) disallow(clique_[i]);
    if (!fitted || !record(r, tls, q, m)) continue;
    for (uint32_t i = 0; i < q; ++i) owner_[clique_[i]] = count_;
  }
}

// The clique's TLS pose, or the solve of everything it explains when that agrees at least as well
// (refit; *m rows of the solve in mask_/sub_w_). Only what the final pose explains leaves the graph: a
// clique that mixed two lattice shifts must not take the other shift's correspondences with it (that
// is how true hypotheses were lost). False when the clique gives no pose.
bool PoseHypotheses::fit_clique(Run& r, TlsResult* tls, uint32_t* m) {
  const HypothesisConfig& c = r.c;
  const uint32_t q = clique_.size();
  for (uint32_t i = 0; i < q; ++i) copy_to_sub(r, i, clique_[i]);
  const bool fitted =
      solve_tls(sub_a_, sub_b_, sub_w_, q, c.tls_threshold, c.max_iterations, tls, mask_, tls_w_) == Status::Ok &&
      tls->inliers >= c.min_inliers;
  if (!fitted) return false;
  TlsResult wide;
  uint32_t wm = 0;
  if (refit(r, tls->b_T_a, &wide, &wm) && wm > q && wide.inliers >= tls->inliers) {
    *tls = wide;
    *m = wm;
  } else {  // mask_ must describe the clique's own solve again
    for (uint32_t i = 0; i < q; ++i) copy_to_sub(r, i, clique_[i]);
    solve_tls(sub_a_, sub_b_, sub_w_, q, c.tls_threshold, c.max_iterations, tls, mask_, tls_w_);
  }
  for (uint32_t i = 0; i < r.n; ++i)
    if (r.residual2(tls->b_T_a, i) <= r.c2) disallow(i);
  return true;
}

// 1b. Heading-diverse cliques (HypothesisConfig::heading_cliques): the edges that make cliques at the
// headings found so far leave the graph, and the search runs again on every correspondence. They run
// however many headings peeling found: a clique of min_inliers pairs at a stray heading is a heading
// too, and in a lattice two of them left no room for a true heading that peeling never reached
// (vote_shifts ranks the headings by their shift votes; seed 41's lattice: two confident 180-degree flips).
void PoseHypotheses::find_heading_cliques(Run& r) {
  const HypothesisConfig& c = r.c;
  if (c.heading_cliques == 0 || count_ == 0 || count_ >= r.K) return;
  const double separation = deg_to_rad(double(c.heading_separation_deg));
  const float min_pair = c.tls_threshold;  // shorter pairs cannot tell a heading to within the separation
  uint32_t cleared = 0;                    // hypotheses whose heading's edges are gone
  allow_all(r.n);
  for (uint32_t extra = 0; extra < c.heading_cliques && count_ < r.K; ++extra) {
    for (; cleared < count_; ++cleared)
      graph_.remove_edges_at_heading(r.a, r.b, yaw_of(hyps_[cleared].map_T_scan), separation, min_pair);
    CliqueStats cs;
    solver_.solve(graph_, c.next_budget, clique_, &cs, allowed_);
    ++r.st.searches;
    r.st.nodes += cs.nodes;
    const uint32_t q = clique_.size();
    if (q < c.min_inliers) break;
    for (uint32_t i = 0; i < q; ++i) copy_to_sub(r, i, clique_[i]);
    TlsResult tls;
    if (solve_tls(sub_a_, sub_b_, sub_w_, q, c.tls_threshold, c.max_iterations, &tls, mask_, tls_w_) != Status::Ok ||
        tls.inliers < c.min_inliers || !record(r, tls, q, q)) {
      // No hypothesis from it: its members leave, so the next search differs.
      for (uint32_t i = 0; i < q; ++i) disallow(clique_[i]);
      continue;
    }
    ++r.st.heading_cliques;
    for (uint32_t i = 0; i < q; ++i) owner_[clique_[i]] = count_;
  }
}

// The distinct headings of the hypotheses so far (each the first hypothesis not within same_pose_deg of
// an earlier distinct one) into heads, best supported first: by the support of the heading's best shift-
// vote bin (rank_shift_bins: the weight of the vote pairs within tls_threshold of one translation), ties
// in the order found. A clique's own inlier count does not tell a true heading from a stray one: its fit
// can keep 3 of its 13-16 pairs at the true heading (the cheap family's hall) as at a stray one (seed
// 41's lattice), while at the true heading and a lattice's turns many vote pairs agree on a translation.
// Returns how many.
uint32_t PoseHypotheses::ranked_headings(const Run& r, uint32_t* heads) {
  float support[kMaxHypotheses];
  uint32_t n = 0;
  for (uint32_t hp = 0; hp < count_; ++hp) {
    bool seen = false;
    for (uint32_t k = 0; k < n && !seen; ++k)
      seen =
          Eigen::AngleAxisd(hyps_[heads[k]].map_T_scan.linear().transpose() * hyps_[hp].map_T_scan.linear()).angle() <
          r.same_rad;
    if (seen) continue;
    const uint32_t bins = rank_shift_bins(bin_votes(r, upright_at(hyps_[hp].map_T_scan)), r.w, r.c);
    float best = 0.0f;
    for (uint32_t k = 0; k < bins; ++k)
      if (bin_rank_[k] == 2) best = std::max(best, bin_weight_[k]);
    heads[n] = hp;
    support[n++] = best;
  }
  for (uint32_t i = 1; i < n; ++i)  // insertion sort, stable: n <= max_peeled + heading_cliques
    for (uint32_t j = i; j > 0 && support[j] > support[j - 1]; --j) {
      std::swap(support[j], support[j - 1]);
      std::swap(heads[j], heads[j - 1]);
    }
  return n;
}

// 2. Shift votes. In a repetitive layout the true answer is one translation among many that the
// cliques' headings allow, and peeling may never form it. For each of the shift_headings best-supported
// headings found (ranked_headings), every correspondence votes for the translation b - R a (bins of
// shift_bin metres); the best-supported bins (rank_shift_bins: by the votes within tls_threshold of a
// bin's mean, ties by bin key) become hypotheses until K are found.
void PoseHypotheses::vote_shifts(Run& r) {
  const HypothesisConfig& c = r.c;
  uint32_t heads[kMaxHypotheses];
  const uint32_t total_headings = std::min(ranked_headings(r, heads), c.shift_headings);
  for (uint32_t k = 0; k < total_headings && count_ < r.K; ++k) {
    // An even share of the remaining slots for each remaining heading: the true heading need not be
    // the first clique's.
    const uint32_t quota = (r.K - count_ + (total_headings - k) - 1) / (total_headings - k);
    vote_at_heading(r, upright_at(hyps_[heads[k]].map_T_scan), count_ + quota);
  }
}

// Hypotheses at heading R from the best shift-vote bins, until `stop` hypotheses exist.
void PoseHypotheses::vote_at_heading(Run& r, const Eigen::Matrix3d& R, uint32_t stop) {
  const uint32_t all_bins = bin_votes(r, R);
  const uint32_t bins = rank_shift_bins(all_bins, r.w, r.c);
  for (uint32_t taken = 0; taken < bins && count_ < stop; ++taken) {
    bring_best_bin_to(taken, bins);
    Eigen::Vector3d t;
    uint32_t m = 0;
    if (!fit_translation(r, R, bin_first_[taken], all_bins, &t, &m)) continue;
    TlsResult tls;
    tls.b_T_a.linear() = R;
    tls.b_T_a.translation() = t;
    tls.inliers = m;
    ++r.st.voted;
    record(r, tls, 0, m);
  }
}

// Every vote's translation and bin key, the votes sorted by key, and the runs of equal keys compacted
// to bins (first entry, weight, count, begin, key), in key order. Returns the number of bins.
uint32_t PoseHypotheses::bin_votes(const Run& r, const Eigen::Matrix3d& R) {
  const uint32_t V = r.n_votes;
  for (uint32_t i = 0; i < V; ++i) {
    const Eigen::Vector3d t = point(r.b, i) - R * point(r.a, i);
    vote_key_[i] = shift_key(shift_coord(t.x(), r.c.shift_bin), shift_coord(t.y(), r.c.shift_bin));
    vote_t_[2 * i] = static_cast<float>(t.x());
    vote_t_[2 * i + 1] = static_cast<float>(t.y());
  }
  sort_by_shift_key(vote_key_, V, vote_order_, gather_, bin_first_);  // both free until the bins are filled
  uint32_t bins = 0;
  for (uint32_t k = 0; k < V;) {
    uint32_t e = k;
    float weight = 0.0f;
    while (e < V && vote_key_[vote_order_[e]] == vote_key_[vote_order_[k]]) weight += r.w[vote_order_[e++]];
    bin_first_[bins] = vote_order_[k];
    bin_weight_[bins] = weight;
    bin_count_[bins] = e - k;
    bin_begin_[bins] = k;
    bin_key_[bins] = vote_key_[vote_order_[k]];
    ++bins;
    k = e;
  }
  bin_begin_[bins] = V;
  return bins;
}

// Selection of the next best bin into place `taken` (by rank class, then weight; equal weights by key).
void PoseHypotheses::bring_best_bin_to(uint32_t taken, uint32_t bins) {
  uint32_t best = taken;
  for (uint32_t k = taken + 1; k < bins; ++k)
    if (bin_rank_[k] > bin_rank_[best] ||
        (bin_rank_[k] == bin_rank_[best] &&
         (bin_weight_[k] > bin_weight_[best] ||
          (bin_weight_[k] == bin_weight_[best] && vote_key_[bin_first_[k]] < vote_key_[bin_first_[best]]))))
      best = k;
  std::swap(bin_first_[taken], bin_first_[best]);
  std::swap(bin_weight_[taken], bin_weight_[best]);
  std::swap(bin_count_[taken], bin_count_[best]);
  std::swap(bin_rank_[taken], bin_rank_[best]);
}

// Translation-only fit under the heading R from vote i0: a bin holds a few correspondences, too few
// (and too collinear) to re-estimate roll and pitch; the heading comes from a whole clique. Each round
// reads only the votes of the bins around its translation (gather_votes), not all pairs; the last
// round's votes are the m rows of sub_a_/sub_b_/sub_w_ (mask_ all 1). False with fewer than min_inliers.
bool PoseHypotheses::fit_translation(const Run& r, const Eigen::Matrix3d& R, uint32_t i0, uint32_t all_bins,
                                     Eigen::Vector3d* t_out, uint32_t* m_out) {
  Eigen::Vector3d t = point(r.b, i0) - R * point(r.a, i0);
  uint32_t m = 0;
  for (int it = 0; it < 3; ++it) {
    const double r2 = it == 0 ? r.far2 : r.c2;
    const uint32_t g = gather_votes(r, t, std::sqrt(r2), all_bins);
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    double wsum = 0.0;
    m = 0;
    for (uint32_t e = 0; e < g; ++e) {
      const uint32_t i = gather_[e];
      const Eigen::Vector3d ti = point(r.b, i) - R * point(r.a, i);
      if ((ti - t).squaredNorm() > r2) continue;
      copy_to_sub(r, m, i);
      mask_[m++] = 1;
      sum += double(sub_w_[m - 1]) * ti;
      wsum += sub_w_[m - 1];
    }
    if (m < r.c.min_inliers || !(wsum > 0)) break;
    t = sum / wsum;
  }
  *t_out = t;
  *m_out = m;
  return m >= r.c.min_inliers;
}

// The votes a fit around translation t within radius can use: those in the bins covering the square
// around t, sorted into pair order (into gather_), so the fit's sums are those of a pass over all pairs.
uint32_t PoseHypotheses::gather_votes(const Run& r, const Eigen::Vector3d& t, double radius, uint32_t all_bins) {
  const float bin = r.c.shift_bin;
  const int64_t x0 = shift_coord(t.x() - radius, bin), x1 = shift_coord(t.x() + radius, bin);
  const int64_t y0 = shift_coord(t.y() - radius, bin), y1 = shift_coord(t.y() + radius, bin);
  uint32_t g = 0;
  for (int64_t x = x0; x <= x1; ++x)
    for (int64_t y = y0; y <= y1; ++y) {
      if (x < 0 || y < 0 || x > 0x1FFFFF || y > 0x1FFFFF) continue;
      const uint32_t j = find_bin(shift_key(x, y), all_bins);
      if (j == UINT32_MAX) continue;
      for (uint32_t e = bin_begin_[j]; e < bin_begin_[j + 1]; ++e) gather_[g++] = vote_order_[e];
    }
  std::sort(gather_, gather_ + g);
  return g;
}

uint32_t PoseHypotheses::retain(const uint8_t* keep) {
  uint32_t renumber[kMaxHypotheses + 1] = {};  // 1 + old index -> 1 + new index (0: dropped or none)
  uint32_t kept = 0;
  for (uint32_t h = 0; h < count_; ++h) {
    if (!keep[h]) continue;
    if (kept != h) hyps_[kept] = hyps_[h];
    renumber[h + 1] = ++kept;
  }
  for (uint32_t i = 0; i < max_n_; ++i) owner_[i] = owner_[i] <= count_ ? renumber[owner_[i]] : 0;
  const uint32_t dropped = count_ - kept;
  count_ = kept;
  return dropped;
}

}  // namespace gsf
