#include "gsf/detail/wasserstein.h"

#include <cmath>
#include <cstring>

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

// The observed W2's mean term runs in float, eight classes a lane: lane k adds classes k and k + 8 of
// every compared grid point, the tail lanes the classes from 16 on, and the lanes meet in a fixed tree
// at the end. That order is the code's, not the compiler's: an AVX2 clone runs the eight lanes as one
// vector, SSE2 and NEON as two, a scalar build one by one, and all give the same bits (the file is
// compiled without contraction into fused multiply-adds). A point's 19 classes are contiguous, so a
// lane reads a row as whole vectors; the double sums over four points it replaced gathered each class
// from four rows, about 2.4x the instructions of a lattice zone's 17k comparisons a scan.
constexpr int kLanes = 8;
constexpr int kTail = kNumClasses - 2 * kLanes;
static_assert(kTail > 0 && kTail <= kLanes, "the classes fill two lanes' rows and a tail");

#if defined(__GNUC__) && !defined(GSF_NO_VECTOR_EXTENSIONS)
// GCC's and Clang's generic vectors: element-wise IEEE operations, lowered to one AVX2 register, two
// SSE2 or NEON ones, or scalars. (The compilers do not vectorise the scalar lanes below by themselves.)
// Loaded and stored through memcpy, never passed by value (a 32-byte vector argument is an ABI question
// for the baseline x86-64 build). Other compilers, or -DGSF_NO_VECTOR_EXTENSIONS, take the scalar lanes:
// the same bits (checked on x86-64 with both).
typedef float Lanes __attribute__((vector_size(kLanes * sizeof(float))));
#endif

struct MeanTermLanes {
#if defined(__GNUC__) && !defined(GSF_NO_VECTOR_EXTENSIONS)
  Lanes lane = {};
  Lanes w_lo, w_hi;
  explicit MeanTermLanes(const float* weights) : w(weights) {
    std::memcpy(&w_lo, w, sizeof w_lo);
    std::memcpy(&w_hi, w + kLanes, sizeof w_hi);
  }
#else
  float lane[kLanes] = {};
  explicit MeanTermLanes(const float* weights) : w(weights) {}
#endif
  const float* w;  // the D class weights
  float tail[kTail] = {};

  GSF_ALWAYS_INLINE float lane_at(int k) const { return lane[k]; }
  // Point (a, b)'s classes.
  GSF_ALWAYS_INLINE void add(const float* a, const float* b) {
#if defined(__GNUC__) && !defined(GSF_NO_VECTOR_EXTENSIONS)
    Lanes a0, b0, a1, b1;
    std::memcpy(&a0, a, sizeof a0);
    std::memcpy(&b0, b, sizeof b0);
    std::memcpy(&a1, a + kLanes, sizeof a1);
    std::memcpy(&b1, b + kLanes, sizeof b1);
    const Lanes x0 = a0 - b0, x1 = a1 - b1;
    lane = lane + w_lo * (x0 * x0);
    lane = lane + w_hi * (x1 * x1);
#else
    for (int k = 0; k < kLanes; ++k) {
      const float x0 = a[k] - b[k];
      const float x1 = a[k + kLanes] - b[k + kLanes];
      lane[k] = lane[k] + w[k] * (x0 * x0);
      lane[k] = lane[k] + w[k + kLanes] * (x1 * x1);
    }
#endif
    for (int k = 0; k < kTail; ++k) {
      const float x = a[k + 2 * kLanes] - b[k + 2 * kLanes];
      tail[k] = tail[k] + w[k + 2 * kLanes] * (x * x);
    }
  }
  GSF_ALWAYS_INLINE float total() const {
    float t = 0.0f;
    for (int k = 0; k < kTail; ++k) t = t + tail[k];
    const float l0 = lane_at(0), l1 = lane_at(1), l2 = lane_at(2), l3 = lane_at(3);
    const float l4 = lane_at(4), l5 = lane_at(5), l6 = lane_at(6), l7 = lane_at(7);
    return (((l0 + l4) + (l2 + l6)) + ((l1 + l5) + (l3 + l7))) + t;
  }
};

}  // namespace

GSF_AVX2_CLONE ObservedW2 w2_squared_diag_observed(const float* mq, const float* vq, const float* mm, const float* vm,
                                                   uint32_t g, const float* w, float max_var, float cov_weight) {
  ObservedW2 r;
  const double tw = trace_weights(w) * cov_weight;
  MeanTermLanes sum(w);
  double cov = 0.0;
  for (uint32_t s = 0; s < g; ++s) {
    if (!(vq[s] <= max_var)) continue;
    sum.add(mq + size_t(s) * kNumClasses, mm + size_t(s) * kNumClasses);
    if (tw != 0.0) {
      const double e = std::sqrt(double(vq[s] > 0 ? vq[s] : 0)) - std::sqrt(double(vm[s] > 0 ? vm[s] : 0));
      cov += e * e;
    }
    r.used++;
  }
  r.w2 = double(sum.total()) + tw * cov;
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
