// Internal (gsf/detail): a pipeline stage or building block, not part of the stable interface; it may
// change between versions. The stable interface is localizer.h, config.h, map_format.h, scan.h, status.h,
// platform.h, class_table.h, georeference.h, stage_configs.h, stage_results.h and the C API gsf.h.
// The 2-Wasserstein distance between two Gaussian semantic fields probed on the same grid points.
//
// Each probe is N(mu, S (x) I_D): mean mu (G x D), covariance S (G x G) shared by the D outputs. With
// the stability weights W = diag(w_c) applied as y -> W^1/2 y (paper Table III),
//   W2^2 = sum_s (mu1(s)-mu2(s))^T W (mu1(s)-mu2(s)) + tr(W) [tr S1 + tr S2 - 2 tr((S1^1/2 S2 S1^1/2)^1/2)]
// Exact path: tr((S1^1/2 S2 S1^1/2)^1/2) = sum_i sqrt(lambda_i(L1^T S2 L1)) with S1 = L1 L1^T: one
// Cholesky and one symmetric eigen-solve (cyclic Jacobi, in the arena), in double; O(G^3) per sweep.
// Fast path: treat grid points as independent (diagonal S): O(G D); exact whenever S1, S2 are diagonal.
// The observed-only variant compares only grid points the query field actually saw (its variance below
// a threshold): a single scan sees part of a neighbourhood the map saw whole, and unobserved points
// would add the same penalty to the right and the wrong candidate alike.
#pragma once
#include <cstdint>

#include "gsf/detail/arena.h"
#include "gsf/status.h"

namespace gsf {

// Stability weights per dense class (stability_weight()), D = kNumClasses values.
void stability_weights(float* out);

double w2_mean_term(const float* mean1, const float* mean2, uint32_t g, const float* weights);
double w2_squared_diag(const float* mean1, const float* var1, const float* mean2, const float* var2, uint32_t g,
                       const float* weights);

struct ObservedW2 {
  double w2 = 0.0;    // summed over compared grid points
  uint32_t used = 0;  // grid points compared
};
// Diagonal W2 over the grid points where var_query(s) <= max_query_var. cov_weight scales the
// covariance term (1 = the paper's W2; 0 = mean term only; the localizer's is
// GsfFilterConfig::covariance_weight, default 0). The mean term is summed in float (relative error
// about 1e-6 of w2_mean_term's double sum), in a fixed order that every build keeps.
ObservedW2 w2_squared_diag_observed(const float* mean_query, const float* var_query, const float* mean_map,
                                    const float* var_map, uint32_t g, const float* weights, float max_query_var,
                                    float cov_weight);

class W2Exact {
 public:
  static size_t required_bytes(uint32_t max_grid);
  Status bind(Arena& arena, uint32_t max_grid);
  // cov1, cov2: g x g row-major symmetric PSD. Returns W2^2 (>= 0) in *out.
  Status w2_squared(const float* mean1, const float* cov1, const float* mean2, const float* cov2, uint32_t g,
                    const float* weights, double* out);

 private:
  uint32_t max_grid_ = 0;
  double* l1_ = nullptr;   // g x g
  double* tmp_ = nullptr;  // g x g
  double* c_ = nullptr;    // g x g, eigen-solved in place
};

}  // namespace gsf
