// Internal (gsf/detail): a pipeline stage or building block, not part of the stable interface; it may
// change between versions. The stable interface is localizer.h, config.h, map_format.h, scan.h, status.h,
// platform.h, class_table.h, georeference.h, stage_configs.h, stage_results.h and the C API gsf.h.
// Quantisation of a map instance's probed grid (format v4, docs/map-format.md): affine per instance,
// mean to 8 bits and variance to 16 bits.
//
//   q = round((x - min) / step), step = (max - min) / levels  (levels 255 or 65535; step 0 when max == min)
//   x' = min + q * step
// Error bound (closed form; tests/test_map_format.cpp asserts it): |x' - x| <= step / 2 + 2^-20 (|min| +
// |max|) (the second term covers the float rounding of the subtraction and of min + q * step). For the
// demo map's grids, mean ranges are about 1 (step 0.004, error <= 0.002) and variance ranges below the
// signal variance 1 (step 1.5e-5). The levels (kGridMeanLevels, kGridVarLevels) are the format's
// (map_format.h); this header includes the format, never the other way round.
#pragma once
#include <cmath>
#include <cstdint>

#include "gsf/map_format.h"

namespace gsf {

// Affine scale of n values: *min and *step (0 when all values are equal or n is 0).
inline void quantization_scale(const float* x, uint64_t n, uint32_t levels, float* min, float* step) {
  float lo = n ? x[0] : 0.0f, hi = lo;
  for (uint64_t i = 1; i < n; ++i) {
    lo = x[i] < lo ? x[i] : lo;
    hi = x[i] > hi ? x[i] : hi;
  }
  *min = lo;
  *step = hi > lo ? (hi - lo) / float(levels) : 0.0f;
}

inline uint32_t quantize_level(float x, float min, float step, uint32_t levels) {
  if (!(step > 0.0f)) return 0;
  const float q = std::round((x - min) / step);
  return q <= 0.0f ? 0u : (q >= float(levels) ? levels : static_cast<uint32_t>(q));
}

inline float dequantize_level(uint32_t q, float min, float step) { return min + float(q) * step; }

// The bound above for one instance's scale.
inline float quantization_error_bound(float min, float step, uint32_t levels) {
  const float max = min + step * float(levels);
  return 0.5f * step + (std::fabs(min) + std::fabs(max)) * (1.0f / 1048576.0f);
}

// Quantises one instance's grid (mean g x d floats, var g floats): sets in->mean_min/step and
// var_min/step, writes q_mean (g x d) and q_var (g). The map builder's side of the round trip.
void quantize_instance_grid(const float* mean, const float* var, uint64_t g, uint64_t d, MapInstance* in,
                            uint8_t* q_mean, uint16_t* q_var);

// Instance i's grid as floats: mean G x D, var G (G = view.grid_points(), D = num_classes). With
// `only` (G flags), the mean only at the grid points flagged nonzero (the rest left as they are): the
// GSF filter needs it only where the query field is observed.
void dequantize_instance_grid(const MapView& view, uint32_t i, float* mean, float* var, const uint8_t* only = nullptr);

}  // namespace gsf
