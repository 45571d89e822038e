#include "gsf/detail/gaussian_field.h"

#include <cmath>

#include "avx2_clone.h"
#include "fast_exp.h"
#include "gsf/detail/sparsify.h"

namespace gsf {
namespace {

constexpr float kSqrt3 = 1.7320508075688772f;

// In-place lower Cholesky of a row-major m x m SPD matrix (double accumulation; only the lower triangle
// is read, the upper one is zero on return). Returns false if not PD. Column by column: L's finished
// columns are mirrored into the upper triangle, so column j's update runs over contiguous rows i and
// vectorises; each entry still subtracts k = 0, 1, ... in order (the same bits as the row-wise loop).
GSF_ALWAYS_INLINE bool cholesky(float* a, uint32_t m) {
  double s[kMaxInducing];
  for (uint32_t j = 0; j < m; ++j) {
    double d = a[j * m + j];
    for (uint32_t k = 0; k < j; ++k) d -= double(a[j * m + k]) * a[j * m + k];
    if (!(d > 0.0)) return false;
    const double ljj = std::sqrt(d);
    a[j * m + j] = static_cast<float>(ljj);
    for (uint32_t i = j + 1; i < m; ++i) s[i] = a[i * m + j];
    for (uint32_t k = 0; k < j; ++k) {
      const float* lk = a + size_t(k) * m;  // L's column k, mirrored: lk[i] = L_ik for i > k
      const double ljk = lk[j];
      for (uint32_t i = j + 1; i < m; ++i) s[i] -= double(lk[i]) * ljk;
    }
    for (uint32_t i = j + 1; i < m; ++i) {
      const float l = static_cast<float>(s[i] / ljj);
      a[i * m + j] = l;
      a[j * m + i] = l;
    }
  }
  for (uint32_t j = 0; j < m; ++j)
    for (uint32_t k = j + 1; k < m; ++k) a[j * m + k] = 0.0f;
  return true;
}

// Solve L x = b in place (b: m x cols, row-major). Row-oriented so the inner loop runs over the
// contiguous columns (vectorisable); float accumulation is ample for M <= 96 with noise on the diagonal.
GSF_ALWAYS_INLINE void forward_solve(const float* l, uint32_t m, float* b, uint32_t cols) {
  for (uint32_t i = 0; i < m; ++i) {
    float* bi = b + size_t(i) * cols;
    const float* li = l + size_t(i) * m;
    uint32_t k = 0;
    // Four earlier rows per sweep over bi: each element still subtracts l_ik b_k for k = 0, 1, ... in
    // order (bit-identical; this file is compiled with -ffp-contract=off), with a quarter of the
    // loads and stores of bi.
    for (; k + 4 <= i; k += 4) {
      const float l0 = li[k], l1 = li[k + 1], l2 = li[k + 2], l3 = li[k + 3];
      const float* b0 = b + size_t(k) * cols;
      const float* b1 = b0 + cols;
      const float* b2 = b1 + cols;
      const float* b3 = b2 + cols;
      for (uint32_t c = 0; c < cols; ++c) bi[c] = (((bi[c] - l0 * b0[c]) - l1 * b1[c]) - l2 * b2[c]) - l3 * b3[c];
    }
    for (; k < i; ++k) {
      const float lik = li[k];
      const float* bk = b + size_t(k) * cols;
      for (uint32_t c = 0; c < cols; ++c) bi[c] -= lik * bk[c];
    }
    const float inv = 1.0f / l[i * m + i];
    for (uint32_t c = 0; c < cols; ++c) bi[c] *= inv;
  }
}

// Solve L^T x = b in place.
GSF_ALWAYS_INLINE void backward_solve(const float* l, uint32_t m, float* b, uint32_t cols) {
  for (uint32_t ii = m; ii-- > 0;) {
    float* bi = b + size_t(ii) * cols;
    for (uint32_t k = ii + 1; k < m; ++k) {
      const float lki = l[k * m + ii];
      const float* bk = b + size_t(k) * cols;
      for (uint32_t c = 0; c < cols; ++c) bi[c] -= lki * bk[c];
    }
    const float inv = 1.0f / l[ii * m + ii];
    for (uint32_t c = 0; c < cols; ++c) bi[c] *= inv;
  }
}

}  // namespace

float matern32(float r, float length_scale, float signal_variance) {
  const float a = kSqrt3 * r / length_scale;
  return signal_variance * (1.0f + a) * detail::exp_nonpositive(-a);
}

namespace {
// kernel(a, b_s) for the g points b_s of a probe grid given by coordinate (gx, gy, gz), in two loops:
// squared distances, then the kernel of each, a loop without branches; both vectorise (sqrt, divide
// and the exp). The same arithmetic as kernel().
template <bool kThreeD>
GSF_ALWAYS_INLINE void kernel_row(const float* a, const float* gx, const float* gy, const float* gz, uint32_t g,
                                  float length_scale, float signal_variance, float* row) {
  for (uint32_t s = 0; s < g; ++s) {
    const float dx = a[0] - gx[s], dy = a[1] - gy[s], dz = kThreeD ? a[2] - gz[s] : 0.0f;
    row[s] = dx * dx + dy * dy + dz * dz;
  }
  for (uint32_t s = 0; s < g; ++s) row[s] = matern32(std::sqrt(row[s]), length_scale, signal_variance);
}
}  // namespace

Status validate(const FieldConfig& c) {
  if (!(c.radius > 0 && c.length_scale > 0 && c.signal_variance > 0 && c.noise_variance > 0 && c.grid_spacing > 0))
    return Status::InvalidArgument;
  if (c.inducing_points == 0 || c.inducing_points > kMaxInducing) return Status::InvalidArgument;
  if (c.input_dims != 2 && c.input_dims != 3) return Status::InvalidArgument;
  if (c.grid_nx == 0 || c.grid_ny == 0 || c.grid_layers == 0 || grid_points(c) > kMaxGridPoints)
    return Status::InvalidArgument;
  if (c.input_dims == 2 && c.grid_layers != 1) return Status::InvalidArgument;
  return Status::Ok;
}

void make_probe_grid(const FieldConfig& c, float yaw, float* out) {
  const float cy = std::cos(yaw), sy = std::sin(yaw);
  const float x0 = -0.5f * c.grid_spacing * float(c.grid_nx - 1);
  const float y0 = -0.5f * c.grid_spacing * float(c.grid_ny - 1);
  uint32_t g = 0;
  for (uint32_t l = 0; l < c.grid_layers; ++l)
    for (uint32_t j = 0; j < c.grid_ny; ++j)
      for (uint32_t i = 0; i < c.grid_nx; ++i, ++g) {
        const float x = x0 + c.grid_spacing * float(i), y = y0 + c.grid_spacing * float(j);
        out[3 * g + 0] = cy * x - sy * y;
        out[3 * g + 1] = sy * x + cy * y;
        out[3 * g + 2] = c.input_dims == 2 ? 0.0f : c.grid_z0 + c.layer_spacing * float(l);
      }
}

namespace {

// The voxels within config.radius of `center` (ids) and their labels: what Algorithm 1 chooses from.
uint32_t gather_field_voxels(const VoxelLayer& layer, const FieldConfig& config, const float center[3], uint32_t max,
                             uint32_t* ids, uint8_t* labels, uint32_t* total) {
  const uint32_t n = layer.gather_within(center, config.radius, config.input_dims == 2, ids, max, total);
  for (uint32_t k = 0; k < n; ++k) labels[k] = layer.voxel(ids[k]).label;
  return n;
}

}  // namespace

uint32_t collect_field_points(const VoxelLayer& layer, const FieldConfig& config, const float center[3], uint32_t max,
                              uint32_t* ids, float* xyz, float* targets, uint8_t* labels, uint32_t* total) {
  const uint32_t n = gather_field_voxels(layer, config, center, max, ids, labels, total);
  for (uint32_t k = 0; k < n; ++k) {
    const Voxel& v = layer.voxel(ids[k]);
    for (int d = 0; d < 3; ++d) xyz[3 * k + d] = v.centroid[d] - center[d];
    for (int d = 0; d < kNumClasses; ++d) targets[size_t(k) * kNumClasses + d] = v.prob[d];
  }
  return n;
}

size_t FieldSolver::required_bytes(const FieldConfig& config, uint32_t max_points) {
  return counted_bytes<FieldSolver>(config, max_points);
}

Status FieldSolver::bind(Arena& arena, const FieldConfig& config, uint32_t max_points) {
  bound_ = false;
  const Status v = validate(config);
  if (v != Status::Ok) return v;
  if (max_points == 0) return Status::InvalidArgument;
  config_ = config;
  max_points_ = max_points;
  selected_ = arena.allocate<uint32_t>(kMaxInducing);
  scratch_ = arena.allocate<uint32_t>(max_points);
  kstar_ = arena.allocate<float>(size_t(kMaxInducing) * kMaxGridPoints);
  work_ = arena.allocate<float>(size_t(kMaxInducing) * kMaxGridPoints);
  if (arena.counting()) return Status::Ok;
  if (!selected_ || !scratch_ || !kstar_ || !work_) return Status::BufferTooSmall;
  bound_ = true;
  return Status::Ok;
}

float FieldSolver::kernel(const float* a, const float* b) const {
  const float dx = a[0] - b[0], dy = a[1] - b[1];
  const float dz = config_.input_dims == 3 ? a[2] - b[2] : 0.0f;
  return matern32(std::sqrt(dx * dx + dy * dy + dz * dz), config_.length_scale, config_.signal_variance);
}

// An AVX2 clone on x86-64 (avx2_clone.h), like probe(): the kernel rows and the Cholesky vectorise.
GSF_AVX2_CLONE Status FieldSolver::factor(const float* inputs, uint32_t m, float* chol) {
  if (!bound_) return Status::NotInitialized;
  if (m == 0 || m > config_.inducing_points) return Status::InvalidArgument;
  // Row i's kernels to inputs 0..i in one kernel_row (the inputs by coordinate): the same values as
  // kernel(); the noise on the diagonal. Only the lower triangle is filled: cholesky() reads no more.
  float ix[kMaxInducing], iy[kMaxInducing], iz[kMaxInducing];
  for (uint32_t i = 0; i < m; ++i) {
    ix[i] = inputs[3 * i];
    iy[i] = inputs[3 * i + 1];
    iz[i] = inputs[3 * i + 2];
  }
  const float ls = config_.length_scale, sv = config_.signal_variance;
  for (uint32_t i = 0; i < m; ++i) {
    if (config_.input_dims == 3) kernel_row<true>(inputs + 3 * i, ix, iy, iz, i + 1, ls, sv, chol + size_t(i) * m);
    else kernel_row<false>(inputs + 3 * i, ix, iy, iz, i + 1, ls, sv, chol + size_t(i) * m);
    chol[size_t(i) * m + i] += config_.noise_variance;
  }
  return cholesky(chol, m) ? Status::Ok : Status::InvalidInput;
}

template <class Load>
Status FieldSolver::fit_selected(const uint8_t* labels, uint32_t n, const Load& load, float* inputs, float* alpha,
                                 float* chol, uint32_t* m_out) {
  *m_out = 0;
  if (!bound_) return Status::NotInitialized;
  if (n == 0) return Status::InvalidInput;
  if (n > max_points_) return Status::CapacityExceeded;
  const uint32_t m = sparsify_semantic(labels, n, config_.inducing_points, config_.seed, selected_, scratch_);
  for (uint32_t r = 0; r < m; ++r) {
    float xyz[3];
    float* y = alpha + size_t(r) * kNumClasses;
    load(selected_[r], xyz, y);
    for (int k = 0; k < 3; ++k) {
      if (!std::isfinite(xyz[k])) return Status::InvalidInput;
      inputs[3 * r + k] = (k == 2 && config_.input_dims == 2) ? 0.0f : xyz[k];
    }
    for (int d = 0; d < kNumClasses; ++d)
      if (!std::isfinite(y[d])) return Status::InvalidInput;
  }
  const Status s = solve_alpha(inputs, alpha, chol, m);
  if (s == Status::Ok) *m_out = m;
  return s;
}

// An AVX2 clone on x86-64 (avx2_clone.h): the two solves for alpha vectorise over the D outputs.
GSF_AVX2_CLONE Status FieldSolver::solve_alpha(const float* inputs, float* alpha, float* chol, uint32_t m) {
  const Status f = factor(inputs, m, chol);
  if (f != Status::Ok) return f;
  forward_solve(chol, m, alpha, kNumClasses);
  backward_solve(chol, m, alpha, kNumClasses);
  return Status::Ok;
}

Status FieldSolver::fit(const float* xyz, const float* targets, const uint8_t* labels, uint32_t n, float* inputs,
                        float* alpha, float* chol, uint32_t* m_out) {
  const auto load = [xyz, targets](uint32_t i, float* p, float* y) {
    for (int k = 0; k < 3; ++k) p[k] = xyz[3 * i + k];
    for (int d = 0; d < kNumClasses; ++d) y[d] = targets[size_t(i) * kNumClasses + d];
  };
  return fit_selected(labels, n, load, inputs, alpha, chol, m_out);
}

Status FieldSolver::fit_voxels(const VoxelLayer& layer, const uint32_t* ids, const uint8_t* labels, uint32_t n,
                               const float center[3], float* inputs, float* alpha, float* chol, uint32_t* m_out) {
  const auto load = [&layer, ids, center](uint32_t i, float* p, float* y) {
    const Voxel& v = layer.voxel(ids[i]);
    for (int k = 0; k < 3; ++k) p[k] = v.centroid[k] - center[k];
    for (int d = 0; d < kNumClasses; ++d) y[d] = v.prob[d];
  };
  return fit_selected(labels, n, load, inputs, alpha, chol, m_out);
}

// An AVX2 clone on x86-64 (avx2_clone.h): the kernel rows, the mean and the solve run 8 lanes a vector,
// bitwise the same probe (the GSF filter's hot path: most of its instructions are here).
GSF_AVX2_CLONE Status FieldSolver::probe(const FieldView& field, const float* chol, const float* grid, uint32_t g,
                                         float* mean, float* var, float* cov, float mean_max_var) {
  if (!bound_) return Status::NotInitialized;
  const uint32_t m = field.m;
  if (g == 0 || g > kMaxGridPoints || m > kMaxInducing) return Status::InvalidArgument;
  const float prior = config_.signal_variance;
  // k* (m x g), its rows padded to gp = a multiple of the vector width (<= kMaxGridPoints): the solve
  // then runs whole vectors, no scalar tail (columns are independent; the padding points are never read
  // back). The grid by coordinate first, so the distance loop reads contiguous floats.
  constexpr uint32_t kLanes = GSF_VECTOR_FLOATS;
  static_assert(kMaxGridPoints % kLanes == 0, "the padded grid fits");
  const uint32_t gp = (g + kLanes - 1) / kLanes * kLanes;
  float gx[kMaxGridPoints], gy[kMaxGridPoints], gz[kMaxGridPoints];
  for (uint32_t s = 0; s < gp; ++s) {
    gx[s] = s < g ? grid[3 * s] : 0.0f;
    gy[s] = s < g ? grid[3 * s + 1] : 0.0f;
    gz[s] = s < g ? grid[3 * s + 2] : 0.0f;
  }
  const float ls = config_.length_scale, sv = config_.signal_variance;
  for (uint32_t i = 0; i < m; ++i) {
    if (config_.input_dims == 3) kernel_row<true>(field.inputs + 3 * i, gx, gy, gz, gp, ls, sv, kstar_ + i * gp);
    else kernel_row<false>(field.inputs + 3 * i, gx, gy, gz, gp, ls, sv, kstar_ + i * gp);
  }
  // V = L^-1 k* ; var_s = k(0) - |V_s|^2 ; cov = K** - V^T V
  for (uint32_t i = 0; i < m * gp; ++i) work_[i] = kstar_[i];
  if (m > 0) forward_solve(chol, m, work_, gp);
  for (uint32_t s = 0; s < g; ++s) var[s] = 0.0f;
  for (uint32_t i = 0; i < m; ++i) {
    const float* w = work_ + size_t(i) * gp;
    for (uint32_t s = 0; s < g; ++s) var[s] += w[s] * w[s];
  }
  for (uint32_t s = 0; s < g; ++s) {
    const float v = prior - var[s];
    var[s] = v > 0.0f ? v : 0.0f;
  }
  // The mean, one grid point at a time with its D sums in a local array (registers), so the m terms
  // are not loaded from and stored to `mean` once each; every sum still adds i = 0, 1, ... in order.
  for (uint32_t s = 0; s < g; ++s) {
    float acc[kNumClasses] = {};
    if (var[s] <= mean_max_var)
      for (uint32_t i = 0; i < m; ++i) {
        const float ks = kstar_[size_t(i) * gp + s];
        const float* a = field.alpha + size_t(i) * kNumClasses;
        for (int d = 0; d < kNumClasses; ++d) acc[d] += ks * a[d];
      }
    float* out = mean + size_t(s) * kNumClasses;
    for (int d = 0; d < kNumClasses; ++d) out[d] = acc[d];
  }
  if (cov) {
    for (uint32_t s = 0; s < g; ++s)
      for (uint32_t t = 0; t <= s; ++t) {
        float q = 0.0f;
        for (uint32_t i = 0; i < m; ++i) q += work_[i * gp + s] * work_[i * gp + t];
        const float c = kernel(grid + 3 * s, grid + 3 * t) - q;
        cov[s * g + t] = c;
        cov[t * g + s] = c;
      }
    for (uint32_t s = 0; s < g; ++s) cov[s * g + s] = var[s];
  }
  return Status::Ok;
}

Status fit_instance_field(FieldSolver& solver, const VoxelLayer& layer, const float center[3],
                          const FieldGather& gather, float* inputs, float* alpha, float* chol, uint32_t* m,
                          uint32_t* gathered, uint32_t* total) {
  *m = 0;
  *total = 0;
  *gathered = gather_field_voxels(layer, solver.config(), center, gather.capacity, gather.ids, gather.labels, total);
  return solver.fit_voxels(layer, gather.ids, gather.labels, *gathered, center, inputs, alpha, chol, m);
}

}  // namespace gsf
