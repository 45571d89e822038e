// Internal (gsf/detail): a pipeline stage or building block, not part of the stable interface; it may
// change between versions. The stable interface is localizer.h, config.h, map_format.h, scan.h, status.h,
// platform.h, class_table.h, georeference.h, stage_configs.h, stage_results.h and the C API gsf.h.
// Pose from correspondences, in double precision: weighted Kabsch (closed form) and the weighted
// truncated least squares of paper Eq. 8,
//     min_{R,t} sum_i w_i min(|b_i - R a_i - t|^2, c^2),
// solved by graduated non-convexity (GNC-TLS, Yang et al. 2020) starting from weighted Kabsch: each
// iteration is a weighted Kabsch with GNC weights, mu grows by 1.4 per iteration, bounded iterations.
// Poses map query points a (scan frame) into map points b.
#pragma once
#include <cstdint>

#include <Eigen/Geometry>

#include "gsf/status.h"

namespace gsf {

// Weighted Kabsch. a, b: n x 3 floats; w: n weights (nullptr = all 1). InvalidInput when the weighted
// points are degenerate (total weight <= 0, fewer than 3 points, or all collinear).
Status kabsch(const float* a, const float* b, const float* w, uint32_t n, Eigen::Isometry3d* b_T_a);

// Weighted upright fit: rotation about z only (yaw) and a 3-D translation, in closed form (2-D
// Procrustes on x, y; z from the weighted means). Rows with mask[i] == 0 are left out (mask nullptr:
// all). InvalidInput when fewer than 2 rows or no positive weight remain, or the rows' horizontal
// spread is zero (yaw undetermined).
Status fit_upright(const float* a, const float* b, const float* w, const uint8_t* mask, uint32_t n,
                   Eigen::Isometry3d* b_T_a);

struct TlsResult {
  Eigen::Isometry3d b_T_a = Eigen::Isometry3d::Identity();
  uint32_t inliers = 0;  // residual <= c
  double cost = 0.0;     // the truncated objective at the solution
  uint32_t iterations = 0;
};

// inlier_mask (optional, n bytes) receives 1 for residual <= threshold.
Status solve_tls(const float* a, const float* b, const float* w, uint32_t n, double threshold, uint32_t max_iterations,
                 TlsResult* out, uint8_t* inlier_mask, float* scratch_weights /* n */);

}  // namespace gsf
