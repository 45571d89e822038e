// Internal (gsf/detail): a pipeline stage or building block, not part of the stable interface; it may
// change between versions. The stable interface is localizer.h, config.h, map_format.h, scan.h, status.h,
// platform.h, class_table.h, georeference.h, stage_configs.h, stage_results.h and the C API gsf.h.
// Inducing-point selection for the sparse GP (paper Algorithm 1, "semantic-based sparsification"):
// keep each class's share of the points. N_c = round(p_c N) with a largest-remainder correction so the
// total is exactly min(N, n) and |N_c - p_c N| < 1; within a class, a seeded partial Fisher-Yates picks
// the points. sparsify_random is the plain uniform subset the paper's Fig. 4 compares against.
// Both write ascending indices into `out` and return how many; `scratch` must hold n uint32.
#pragma once
#include <cstdint>

namespace gsf {

uint32_t sparsify_semantic(const uint8_t* labels, uint32_t n, uint32_t target, uint64_t seed, uint32_t* out,
                           uint32_t* scratch);
uint32_t sparsify_random(uint32_t n, uint32_t target, uint64_t seed, uint32_t* out, uint32_t* scratch);

}  // namespace gsf
