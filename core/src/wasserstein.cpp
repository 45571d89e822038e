#include "gsf/detail/wasserstein.h"

#include <cmath>

#include "avx2_clone.h"
#include "gsf/detail/gaussian_field.h"
#include "gsf/semantic_classes.h"

namespace gsf {

namespace {

// Eigenvalues of a symmetric n x n matrix (row-major, destroyed) by cyclic Jacobi rotations, written
// to the diagonal. Chosen over Eigen's SelfAdjointEigenSolver because that one's max-size
// instantiation puts a 656 KB temporary on the stack (scripts/stack-usage.sh); Jacobi works in place,
// is deterministic and accurate for the symmetric PSD matrices here. Bounded: at most 30 sweeps.
bool jacobi_eigenvalues(double* a, uint32_t n) {
  for (int sweep = 0; sweep < 30; ++sweep) {
    double off = 0.0, diag = 0.0;
    for (uint32_t i = 0; i < n; ++i) {
      diag += a[i * n + i] * a[i * n + i];
      for (uint32_t j = i + 1; j < n; ++j) off += a[i * n + j] * a[i * n + j];
    }
    if (off <= 1e-24 * (diag + 1e-300)) return true;
    for (uint32_t p = 0; p < n; ++p)
      for (uint32_t q = p + 1; q < n; ++q) {
        const double apq = a[p * n + q];
        if (std::fabs(apq) < 1e-300) continue;
        const double theta = (a[q * n + q] - a[p * n + p]) / (2.0 * apq);
        const double t = (theta >= 0 ? 1.0 : -1.0) / (std::fabs(theta) + std::sqrt(theta * theta + 1.0));
        const double c = 1.0 / std::sqrt(t * t + 1.0), s = t * c;
        for (uint32_t k = 0; k < n; ++k) {  // rows p, q
          const double akp = a[p * n + k], akq = a[q * n + k];
          a[p * n + k] = c * akp - s * akq;
          a[q * n + k] = s * akp + c * akq;
        }
        for (uint32_t k = 0; k < n; ++k) {  // columns p, q
          const double akp = a[k * n + p], akq = a[k * n + q];
          a[k * n + p] = c * akp - s * akq;
          a[k * n + q] = s * akp + c * akq;
        }
      }
  }
  return false;
}

}  // namespace

void stability_weights(float* out) {
  for (int c = 0; c < kNumClasses; ++c) out[c] = stability_weight(c);
}

double w2_mean_term(const float* m1, const float* m2, uint32_t g, const float* w) {
  double acc = 0.0;
  for (uint32_t s = 0; s < g; ++s)
    for (int d = 0; d < kNumClasses; ++d) {
      const double e = double(m1[s * kNumClasses + d]) - m2[s * kNumClasses + d];
      acc += w[d] * e * e;
    }
  return acc;
}

static double trace_weights(const float* w) {
  double t = 0.0;
  for (int d = 0; d < kNumClasses; ++d) t += w[d];
  return t;
}

double w2_squared_diag(const float* m1, const float* v1, const float* m2, const float* v2, uint32_t g, const float* w) {
  double cov = 0.0;
  for (uint32_t s = 0; s < g; ++s) {
    const double e = std::sqrt(double(v1[s] > 0 ? v1[s] : 0)) - std::sqrt(double(v2[s] > 0 ? v2[s] : 0));
    cov += e * e;
  }
  return w2_mean_term(m1, m2, g, w) + trace_weights(w) * cov;
}

namespace {
// One grid point's weighted squared mean difference, summed over d = 0, 1, ... in order.
GSF_ALWAYS_INLINE double mean_term_at(const float* a, const float* b, const double* wd) {
  double acc = 0.0;
  for (int d = 0; d < kNumClasses; ++d) {
    const double x = double(a[d]) - double(b[d]);
    acc += wd[d] * x * x;
  }
  return acc;
}
}  // namespace

GSF_AVX2_CLONE ObservedW2 w2_squared_diag_observed(const float* mq, const float* vq, const float* mm, const float* vm,
                                                   uint32_t g, const float* w, float max_var, float cov_weight) {
  ObservedW2 r;
  const double tw = trace_weights(w) * cov_weight;
  double wd[kNumClasses];
  for (int d = 0; d < kNumClasses; ++d) wd[d] = w[d];
  // The hot path of the GSF filter. Four observed points at a time, each its own sum in the same order
  // as mean_term_at: four independent chains of dependent double adds instead of one, which the
  // pipeline overlaps (one chain waited on every add). The same bits. An AVX2 clone on x86-64
  // (avx2_clone.h): the four chains share vector registers (a lattice zone's GSF filter: 46 -> 31 M
  // instructions a scan here), the same +, -, * in the same order.
  for (uint32_t s = 0; s < g;) {
    uint32_t pick[4], n = 0;
    for (; s < g && n < 4; ++s)
      if (vq[s] <= max_var) pick[n++] = s;
    double acc[4];
    if (n == 4) {
      const float *a0 = mq + pick[0] * kNumClasses, *a1 = mq + pick[1] * kNumClasses;
      const float *a2 = mq + pick[2] * kNumClasses, *a3 = mq + pick[3] * kNumClasses;
      const float *b0 = mm + pick[0] * kNumClasses, *b1 = mm + pick[1] * kNumClasses;
      const float *b2 = mm + pick[2] * kNumClasses, *b3 = mm + pick[3] * kNumClasses;
      double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
      for (int d = 0; d < kNumClasses; ++d) {
        const double x0 = double(a0[d]) - double(b0[d]), x1 = double(a1[d]) - double(b1[d]);
        const double x2 = double(a2[d]) - double(b2[d]), x3 = double(a3[d]) - double(b3[d]);
        s0 += wd[d] * x0 * x0;
        s1 += wd[d] * x1 * x1;
        s2 += wd[d] * x2 * x2;
        s3 += wd[d] * x3 * x3;
      }
      acc[0] = s0, acc[1] = s1, acc[2] = s2, acc[3] = s3;
    } else {
      for (uint32_t j = 0; j < n; ++j)
        acc[j] = mean_term_at(mq + pick[j] * kNumClasses, mm + pick[j] * kNumClasses, wd);
    }
    for (uint32_t j = 0; j < n; ++j) {
      if (tw != 0.0) {
        const uint32_t t = pick[j];
        const double e = std::sqrt(double(vq[t] > 0 ? vq[t] : 0)) - std::sqrt(double(vm[t] > 0 ? vm[t] : 0));
        acc[j] += tw * e * e;
      }
      r.w2 += acc[j];
      r.used++;
    }
  }
  return r;
}

size_t W2Exact::required_bytes(uint32_t max_grid) { return counted_bytes<W2Exact>(max_grid); }

Status W2Exact::bind(Arena& arena, uint32_t max_grid) {
  if (max_grid == 0 || max_grid > kMaxGridPoints) return Status::InvalidArgument;
  max_grid_ = max_grid;
  l1_ = arena.allocate<double>(size_t(max_grid) * max_grid);
  tmp_ = arena.allocate<double>(size_t(max_grid) * max_grid);
  c_ = arena.allocate<double>(size_t(max_grid) * max_grid);
  if (arena.counting()) return Status::Ok;
  if (!l1_ || !tmp_ || !c_) return Status::BufferTooSmall;
  return Status::Ok;
}

Status W2Exact::w2_squared(const float* m1, const float* s1, const float* m2, const float* s2, uint32_t g,
                           const float* w, double* out) {
  *out = 0.0;
  if (!c_) return Status::NotInitialized;
  if (g == 0 || g > max_grid_) return Status::InvalidArgument;
  // L1: Cholesky of S1 + jitter (S1 is PSD; the jitter keeps a rank-deficient posterior factorable).
  double tr1 = 0.0, tr2 = 0.0;
  for (uint32_t s = 0; s < g; ++s) {
    tr1 += s1[s * g + s];
    tr2 += s2[s * g + s];
  }
  const double jitter = 1e-9 * (tr1 / g + 1e-12);
  for (uint32_t j = 0; j < g; ++j) {
    double d = double(s1[j * g + j]) + jitter;
    for (uint32_t k = 0; k < j; ++k) d -= l1_[j * g + k] * l1_[j * g + k];
    if (!(d > 0.0)) d = jitter;  // numerically singular direction: contributes ~0 to the trace term
    const double ljj = std::sqrt(d);
    l1_[j * g + j] = ljj;
    for (uint32_t i = j + 1; i < g; ++i) {
      double s = s1[i * g + j];
      for (uint32_t k = 0; k < j; ++k) s -= l1_[i * g + k] * l1_[j * g + k];
      l1_[i * g + j] = s / ljj;
    }
    for (uint32_t k = j + 1; k < g; ++k) l1_[j * g + k] = 0.0;
  }
  // tmp = S2 L1 ; C = L1^T tmp
  for (uint32_t i = 0; i < g; ++i)
    for (uint32_t j = 0; j < g; ++j) {
      double acc = 0.0;
      for (uint32_t k = j; k < g; ++k) acc += double(s2[i * g + k]) * l1_[k * g + j];
      tmp_[i * g + j] = acc;
    }
  for (uint32_t i = 0; i < g; ++i)
    for (uint32_t j = 0; j <= i; ++j) {
      double acc = 0.0;
      for (uint32_t k = i; k < g; ++k) acc += l1_[k * g + i] * tmp_[k * g + j];
      c_[i * g + j] = acc;
      c_[j * g + i] = acc;
    }
  if (!jacobi_eigenvalues(c_, g)) return Status::InvalidInput;
  double cross = 0.0;
  for (uint32_t i = 0; i < g; ++i) {
    const double l = c_[i * g + i];
    cross += l > 0.0 ? std::sqrt(l) : 0.0;
  }
  double cov_term = tr1 + tr2 - 2.0 * cross;
  if (cov_term < 0.0) cov_term = 0.0;  // rounding
  *out = w2_mean_term(m1, m2, g, w) + trace_weights(w) * cov_term;
  return Status::Ok;
}

}  // namespace gsf
