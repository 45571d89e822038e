#include "gsf/detail/triangle_index.h"

#include <algorithm>
#include <cmath>

namespace gsf {

bool TriangleIndexView::lookup(uint64_t key, uint32_t* begin, uint32_t* end) const {
  *begin = *end = 0;
  if (key_count == 0) return false;
  // Branch-free lower bound (the first key >= key): the same index as the branching binary search.
  const uint64_t* base = keys;
  uint32_t n = key_count;
  while (n > 1) {
    const uint32_t half = n / 2;
    base = base[half] < key ? base + half : base;
    n -= half;
  }
  const uint32_t lo = static_cast<uint32_t>(base - keys) + (*base < key ? 1u : 0u);
  if (lo >= key_count || keys[lo] != key) return false;
  *begin = offsets[lo];
  *end = offsets[lo + 1];
  return true;
}

Status TriangleIndexView::validate(uint32_t triangle_count) const {
  if (key_count > 0 && (!keys || !entries)) return Status::CorruptData;
  if (!offsets || offsets[0] != 0 || offsets[key_count] != entry_count) return Status::CorruptData;
  for (uint32_t i = 0; i < key_count; ++i) {
    if (offsets[i] > offsets[i + 1]) return Status::CorruptData;
    if (i > 0 && keys[i - 1] >= keys[i]) return Status::CorruptData;
  }
  for (uint32_t i = 0; i < entry_count; ++i)
    if (entries[i] >= triangle_count) return Status::CorruptData;
  return Status::Ok;
}

Status build_triangle_index(const Triangle* t, uint32_t n, float bin, uint64_t* keys, uint32_t* offsets,
                            uint32_t* entries, uint32_t* key_count, uint64_t* scratch) {
  *key_count = 0;
  if (!(bin > 0.0f)) return Status::InvalidArgument;
  for (uint32_t i = 0; i < n; ++i) {
    scratch[i] = triangle_key(t[i], bin);
    entries[i] = i;
  }
  std::sort(entries, entries + n,
            [&](uint32_t a, uint32_t b) { return scratch[a] < scratch[b] || (scratch[a] == scratch[b] && a < b); });
  uint32_t k = 0;
  for (uint32_t i = 0; i < n; ++i) {
    const uint64_t key = scratch[entries[i]];
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
