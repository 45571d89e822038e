// Internal (gsf/detail): a pipeline stage or building block, not part of the stable interface; it may
// change between versions. The stable interface is localizer.h, config.h, map_format.h, scan.h, status.h,
// platform.h, class_table.h, georeference.h, stage_configs.h, stage_results.h and the C API gsf.h.
// The Gaussian semantic field (GSF, the middle layer of the scene graph): per instance, a sparse GP
// f: R^2 or R^3 -> R^D from positions around the instance to class-probability vectors.
//
// Matern-3/2 kernel k(r) = s^2 (1 + sqrt3 r / l) exp(-sqrt3 r / l); D independent outputs share the
// kernel, so one M x M Cholesky of K + sigma^2 I serves all D: alpha = (K + sigma^2 I)^-1 Y (M x D).
// Inputs are instance-local (relative to the centroid). input_dims = 2 gives a bird's-eye field: the
// z coordinate is dropped, so ground-level "stuff" around a pole counts as much as the pole itself.
// Probing on a fixed grid gives the posterior mean (G x D) and covariance (G x G, shared by all D
// outputs) that the 2-Wasserstein similarity compares (wasserstein.h).
#pragma once
#include <cstdint>
#include <limits>

#include "gsf/detail/arena.h"
#include "gsf/detail/voxel_layer.h"
#include "gsf/semantic_classes.h"
#include "gsf/stage_configs.h"
#include "gsf/status.h"

namespace gsf {

constexpr uint32_t kMaxInducing = 96;
constexpr uint32_t kMaxGridPoints = 128;

Status validate(const FieldConfig& config);
inline uint32_t grid_points(const FieldConfig& c) { return c.grid_nx * c.grid_ny * c.grid_layers; }

float matern32(float r, float length_scale, float signal_variance);

// A fitted field: views into memory owned by someone else (arena or map blob).
struct FieldView {
  const float* inputs = nullptr;  // m x 3, instance-local (z = 0 for bird's-eye fields)
  const float* alpha = nullptr;   // m x D
  uint32_t m = 0;
};

// The probe grid: N_x x N_y (x layers) points centred on the instance, rotated by yaw about z.
// out_xyz: grid_points(config) x 3.
void make_probe_grid(const FieldConfig& config, float yaw_radians, float* out_xyz);

// The field's training set: voxels of the metric-semantic layer within config.radius of `center`
// (horizontal distance for bird's-eye fields), as instance-local xyz (n x 3), class probabilities
// (n x D) and labels (n). Writes at most `max` (ids is scratch of the same size); *total, if given,
// is how many matched, so a caller can tell the set was truncated. Returns the count written.
uint32_t collect_field_points(const VoxelLayer& layer, const FieldConfig& config, const float center[3], uint32_t max,
                              uint32_t* ids, float* xyz, float* targets, uint8_t* labels, uint32_t* total = nullptr);

// Caller-owned scratch for fit_instance_field: room for `capacity` gathered voxels' ids and labels.
// Only the M points Algorithm 1 keeps are read further (position and class probabilities, straight
// from the layer), so the gather holds 5 B a voxel, not the 93 B of a copied training set.
struct FieldGather {
  uint32_t capacity = 0;
  uint32_t* ids = nullptr;    // capacity
  uint8_t* labels = nullptr;  // capacity
};

// Workspace for fitting and probing; all memory comes from the arena at bind().
class FieldSolver {
 public:
  static size_t required_bytes(const FieldConfig& config, uint32_t max_points);
  Status bind(Arena& arena, const FieldConfig& config, uint32_t max_points);

  // Fit from n semantic points (instance-local xyz: n x 3, targets: n x D, dense labels: n). When
  // n > M, Algorithm 1 picks M of them. Writes inputs (M x 3), alpha (M x D) and the Cholesky factor
  // (M x M, lower, row-major, kept for probing) into the given arrays; *m_out = rows used.
  Status fit(const float* xyz, const float* targets, const uint8_t* labels, uint32_t n, float* inputs_out,
             float* alpha_out, float* chol_out, uint32_t* m_out);
  // The same fit from n gathered voxels of `layer` (ids, dense labels), instance-local about `center`:
  // only the M points Algorithm 1 picks are read from the layer. Same checks and results as fit() on
  // the copied training set (collect_field_points).
  Status fit_voxels(const VoxelLayer& layer, const uint32_t* ids, const uint8_t* labels, uint32_t n,
                    const float center[3], float* inputs_out, float* alpha_out, float* chol_out, uint32_t* m_out);
  // Recompute the Cholesky factor of K + sigma^2 I for stored inputs (map side: not stored in the map).
  Status factor(const float* inputs, uint32_t m, float* chol_out);

  // Posterior at G grid points: mean (G x D), variance (G), optionally full covariance (G x G). The
  // mean only where the variance is at most mean_max_var (elsewhere 0): a caller that compares only
  // observed points (the GSF filter) skips the rest, a third to half of a probe's work.
  Status probe(const FieldView& field, const float* chol, const float* grid_xyz, uint32_t g, float* mean_out,
               float* var_out, float* cov_out, float mean_max_var = std::numeric_limits<float>::infinity());

  const FieldConfig& config() const { return config_; }

 private:
  float kernel(const float* a, const float* b) const;
  // fit()'s body: Algorithm 1 on the labels, then load(i, xyz, y) puts point i's instance-local
  // position (3) and targets (D) in place, checked finite, and the factor and the solves.
  template <class Load>
  Status fit_selected(const uint8_t* labels, uint32_t n, const Load& load, float* inputs, float* alpha, float* chol,
                      uint32_t* m_out);
  Status solve_alpha(const float* inputs, float* alpha, float* chol, uint32_t m);
  FieldConfig config_{};
  uint32_t max_points_ = 0;
  uint32_t* selected_ = nullptr;
  uint32_t* scratch_ = nullptr;
  float* kstar_ = nullptr;  // M x G
  float* work_ = nullptr;   // M x G
  bool bound_ = false;
};

// The per-instance field fit, one function for the query (localizer) and the map (map builder), so
// their fields cannot drift apart: the layer's voxels within solver.config().radius of `center` into
// `gather`, then FieldSolver::fit_voxels into inputs / alpha / chol (*m rows). *gathered: points used;
// *total: points that matched (more than gathered: truncated by gather.capacity). Returns the fit's
// status.
Status fit_instance_field(FieldSolver& solver, const VoxelLayer& layer, const float center[3],
                          const FieldGather& gather, float* inputs, float* alpha, float* chol, uint32_t* m,
                          uint32_t* gathered, uint32_t* total);

}  // namespace gsf
