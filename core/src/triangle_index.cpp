#include "gsf/detail/triangle_index.h"

#include <algorithm>
#include <cmath>

namespace gsf {

bool TriangleIndexView::range_from(uint64_t lo, uint64_t hi, uint32_t* from, uint32_t* begin, uint32_t* end) const {
  *begin = *end = 0;
  uint32_t a = *from;
  if (a == 0) {
    if (key_count == 0) return false;
    // Branch-free lower bound (the first key >= lo): the same index as the branching binary search.
    const uint64_t* base = keys;
    uint32_t n = key_count;
    while (n > 1) {
      const uint32_t half = n / 2;
      base = base[half] < lo ? base + half : base;
      n -= half;
    }
    a = static_cast<uint32_t>(base - keys) + (*base < lo ? 1u : 0u);
  } else if (a < key_count && keys[a] < lo) {
    // Gallop: keys[prev] < lo; double the step until a key >= lo (or the end), then bisect.
    uint32_t prev = a, step = 1;
    while (prev + step < key_count && keys[prev + step] < lo) {
      prev += step;
      step *= 2;
    }
    uint32_t l = prev + 1, r = prev + step < key_count ? prev + step : key_count;
    while (l < r) {
      const uint32_t m = l + (r - l) / 2;
      if (keys[m] < lo) l = m + 1;
      else r = m;
    }
    a = l;
  }
  uint32_t b = a;
  while (b < key_count && keys[b] <= hi) ++b;  // keys are unique: at most hi - lo + 1 steps
  *from = b;
  if (b == a) return false;
  *begin = offsets[a];
  *end = offsets[b];
  return true;
}

Status TriangleIndexView::validate(const Triangle* triangles, float side_bin) const {
  if (key_count > 0 && (!keys || !triangles)) return Status::CorruptData;
  if (!offsets || offsets[0] != 0 || offsets[key_count] != triangle_count) return Status::CorruptData;
  for (uint32_t i = 0; i < key_count; ++i) {
    if (offsets[i] > offsets[i + 1]) return Status::CorruptData;
    if (i > 0 && keys[i - 1] >= keys[i]) return Status::CorruptData;
  }
  for (uint32_t i = 0; i < key_count; ++i)
    for (uint32_t t = offsets[i]; t < offsets[i + 1]; ++t)
      if (triangle_key(triangles[t], side_bin) != keys[i]) return Status::CorruptData;
  return Status::Ok;
}

Status build_triangle_index(const Triangle* in, uint32_t n, float bin, Triangle* out, uint64_t* keys, uint32_t* offsets,
                            uint32_t* key_count, uint64_t* scratch, uint32_t* ids) {
  *key_count = 0;
  offsets[0] = 0;
  if (!(bin > 0.0f)) return Status::InvalidArgument;
  for (uint32_t i = 0; i < n; ++i) {
    scratch[i] = triangle_key(in[i], bin);
    if (scratch[i] == kInvalidTriangleKey) return Status::InvalidArgument;
    ids[i] = i;
  }
  std::sort(ids, ids + n,
            [&](uint32_t a, uint32_t b) { return scratch[a] < scratch[b] || (scratch[a] == scratch[b] && a < b); });
  uint32_t k = 0;
  for (uint32_t i = 0; i < n; ++i) {
    out[i] = in[ids[i]];
    const uint64_t key = scratch[ids[i]];
    if (k == 0 || keys[k - 1] != key) {
      keys[k] = key;
      offsets[k] = i;
      ++k;
    }
  }
  offsets[k] = n;
  *key_count = k;
  return Status::Ok;
}

}  // namespace gsf
