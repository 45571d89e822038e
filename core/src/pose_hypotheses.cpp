#include "gsf/pose_hypotheses.h"

#include <cmath>
#include <new>

#include "gsf/pose_solver.h"

namespace gsf {

size_t PoseHypotheses::required_bytes(uint32_t max_correspondences, uint32_t max_hypotheses) {
  Arena counting;
  PoseHypotheses h;
  h.bind(counting, max_correspondences, max_hypotheses);
  return counting.used();
}

Status PoseHypotheses::bind(Arena& ar, uint32_t n, uint32_t k) {
  max_n_ = max_h_ = count_ = 0;
  if (n == 0 || n > 4096 || k == 0 || k > 64) return Status::InvalidArgument;
  if (graph_.bind(ar, n) != Status::Ok || solver_.bind(ar, n) != Status::Ok) return Status::InvalidArgument;
  clique_.bind(ar, n);
  allowed_ = ar.allocate<uint64_t>((n + 63) / 64);
  owner_ = ar.allocate<uint32_t>(n);
  sub_a_ = ar.allocate<float>(size_t(n) * 3);
  sub_b_ = ar.allocate<float>(size_t(n) * 3);
  sub_w_ = ar.allocate<float>(n);
  tls_w_ = ar.allocate<float>(n);
  mask_ = ar.allocate<uint8_t>(n);
  hyps_ = ar.allocate<PoseHypothesis>(k);
  if (ar.counting()) return Status::Ok;
  if (ar.overflowed()) return Status::BufferTooSmall;
  for (uint32_t i = 0; i < k; ++i) new (&hyps_[i]) PoseHypothesis();
  max_n_ = n;
  max_h_ = k;
  return Status::Ok;
}

Status PoseHypotheses::generate(const float* a, const float* b, const float* w, uint32_t n, const HypothesisConfig& c,
                                HypothesisStats* stats_out) {
  HypothesisStats st;
  count_ = 0;
  if (max_n_ == 0) return Status::NotInitialized;
  if (n > max_n_) return Status::CapacityExceeded;
  for (uint32_t i = 0; i < n; ++i) owner_[i] = 0;
  if (n < c.min_inliers) {
    if (stats_out) *stats_out = st;
    return Status::NoSolution;
  }
  graph_.build(a, b, n, c.consistency_eps, c.consistency_z_weight);
  const uint32_t words = (n + 63) / 64;
  for (uint32_t i = 0; i < words; ++i) allowed_[i] = 0;
  for (uint32_t i = 0; i < n; ++i) allowed_[i >> 6] |= uint64_t(1) << (i & 63);
  const uint32_t K = c.max_hypotheses < max_h_ ? c.max_hypotheses : max_h_;
  const double far2 = 4.0 * double(c.tls_threshold) * c.tls_threshold;
  const double same_rad = double(c.same_pose_deg) * 3.14159265358979323846 / 180.0;
  // Each search removes at least its clique, so K searches (plus K for failed TLS) bound the loop.
  for (uint32_t attempt = 0; attempt < 2 * K && count_ < K; ++attempt) {
    CliqueStats cs;
    const Status s = solver_.solve(graph_, st.searches == 0 ? c.first_budget : c.next_budget, clique_, &cs, allowed_);
    if (st.searches == 0 && s == Status::BudgetExhausted) st.budget_exhausted = true;
    ++st.searches;
    st.nodes += cs.nodes;
    const uint32_t q = clique_.size();
    if (q < c.min_inliers) break;
    auto take_clique = [&]() {
      for (uint32_t i = 0; i < q; ++i) {
        const uint32_t id = clique_[i];
        for (int d = 0; d < 3; ++d) { sub_a_[3 * i + d] = a[3 * id + d]; sub_b_[3 * i + d] = b[3 * id + d]; }
        sub_w_[i] = w[id] > 1e-6f ? w[id] : 1e-6f;
      }
    };
    take_clique();
    TlsResult tls;
    if (solve_tls(sub_a_, sub_b_, sub_w_, q, c.tls_threshold, c.max_iterations, &tls, mask_, tls_w_) != Status::Ok ||
        tls.inliers < c.min_inliers) {
      for (uint32_t i = 0; i < q; ++i) allowed_[clique_[i] >> 6] &= ~(uint64_t(1) << (clique_[i] & 63));
      continue;
    }
    // Re-associate: every correspondence the clique's pose explains (within 2c, clique or not) joins a
    // second TLS solve. A clique is a minimal consistent core; the pose of everything it explains is
    // markedly more accurate, and verification compares poses at the 1 m scale of the semantic layer.
    uint32_t m = 0;
    for (uint32_t i = 0; i < n; ++i) {
      const Eigen::Vector3d pa(a[3 * i], a[3 * i + 1], a[3 * i + 2]), pb(b[3 * i], b[3 * i + 1], b[3 * i + 2]);
      if ((pb - tls.b_T_a * pa).squaredNorm() > far2) continue;
      for (int d = 0; d < 3; ++d) { sub_a_[3 * m + d] = a[3 * i + d]; sub_b_[3 * m + d] = b[3 * i + d]; }
      sub_w_[m] = w[i] > 1e-6f ? w[i] : 1e-6f;
      ++m;
    }
    TlsResult wide;
    if (m > q && solve_tls(sub_a_, sub_b_, sub_w_, m, c.tls_threshold, c.max_iterations, &wide, mask_, tls_w_) == Status::Ok &&
        wide.inliers >= tls.inliers) {
      tls = wide;
    } else {  // mask_ below must describe the clique solve: redo it
      take_clique();
      m = q;
      solve_tls(sub_a_, sub_b_, sub_w_, q, c.tls_threshold, c.max_iterations, &tls, mask_, tls_w_);
    }
    // Only what the final pose explains (its inliers) leaves the graph. Clique members it does not
    // explain stay: a clique that mixed one lattice shift's correspondences with another's must not take
    // the other shift's correspondences with it (that is how a true hypothesis was lost). The final
    // pose has >= min_inliers inliers among the correspondences, so every round removes something.
    const double c2 = double(c.tls_threshold) * c.tls_threshold;
    for (uint32_t i = 0; i < n; ++i) {
      const Eigen::Vector3d pa(a[3 * i], a[3 * i + 1], a[3 * i + 2]), pb(b[3 * i], b[3 * i + 1], b[3 * i + 2]);
      if ((pb - tls.b_T_a * pa).squaredNorm() <= c2) allowed_[i >> 6] &= ~(uint64_t(1) << (i & 63));
    }
    for (uint32_t i = 0; i < q; ++i)  // and the clique itself, so the same search cannot repeat
      if (!((allowed_[clique_[i] >> 6] >> (clique_[i] & 63)) & 1u)) continue;
      else {
        bool any_removed = false;
        for (uint32_t k = 0; k < q && !any_removed; ++k)
          any_removed = !((allowed_[clique_[k] >> 6] >> (clique_[k] & 63)) & 1u);
        if (!any_removed) allowed_[clique_[i] >> 6] &= ~(uint64_t(1) << (clique_[i] & 63));
      }
    bool repeated = false;
    for (uint32_t h = 0; h < count_ && !repeated; ++h) {
      const Eigen::Isometry3d d = hyps_[h].map_T_scan.inverse() * tls.b_T_a;
      const double angle = Eigen::AngleAxisd(d.linear()).angle();
      repeated = d.translation().norm() < c.same_pose_m && angle < same_rad;
    }
    if (repeated) { ++st.merged; continue; }
    PoseHypothesis& h = hyps_[count_];
    h = PoseHypothesis();
    h.map_T_scan = tls.b_T_a;
    h.clique_size = q;
    h.inliers = tls.inliers;
    double support = 0.0;
    for (uint32_t i = 0; i < m; ++i) support += mask_[i] ? sub_w_[i] : 0.0;
    h.support = support;
    ++count_;
    for (uint32_t i = 0; i < q; ++i) owner_[clique_[i]] = count_;
  }
  if (stats_out) *stats_out = st;
  return count_ > 0 ? Status::Ok : Status::NoSolution;
}

}  // namespace gsf
