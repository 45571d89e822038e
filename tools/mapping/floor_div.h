// Integer floor division for the map builder's tile and cell coordinates (C++ `/` truncates toward 0).
#pragma once
#include <cstdint>

namespace gsf::mapping {

// floor(a / b) for b > 0.
inline int64_t floor_div(int64_t a, int64_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

}  // namespace gsf::mapping
