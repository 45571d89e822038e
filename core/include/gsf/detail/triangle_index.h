// Internal (gsf/detail): a pipeline stage or building block, not part of the stable interface; it may
// change between versions. The stable interface is localizer.h, config.h, map_format.h, scan.h, status.h,
// platform.h, class_table.h, georeference.h and the C API gsf.h.
// The map's triangle hash index as plain CSR arrays (it lives in the map blob): sorted unique keys,
// offsets (key_count + 1) and triangle ids grouped by key. Lookup is a binary search: O(log keys),
// bounded. TriangleMatcher (triangle_matcher.h) queries the 27 neighbouring keys of a query triangle,
// applies Outram's acceptance rules and ranks what it accepts.
#pragma once
#include <cstdint>

#include "gsf/detail/triangle.h"
#include "gsf/status.h"

namespace gsf {

struct TriangleIndexView {
  const uint64_t* keys = nullptr;
  const uint32_t* offsets = nullptr;
  const uint32_t* entries = nullptr;
  uint32_t key_count = 0;
  uint32_t entry_count = 0;

  // [*begin, *end) into entries for `key`; false (empty range) if absent.
  bool lookup(uint64_t key, uint32_t* begin, uint32_t* end) const;
  // Structural checks for untrusted arrays: keys strictly increasing, offsets monotone from 0 to
  // entry_count, entries < triangle_count.
  Status validate(uint32_t triangle_count) const;
};

// Host-side builder: fills caller arrays (keys: n, offsets: n + 1, entries: n; scratch: n uint64 + n
// uint32) and returns the number of unique keys in *key_count. Deterministic: entries sorted by (key, id).
Status build_triangle_index(const Triangle* triangles, uint32_t n, float side_bin, uint64_t* keys, uint32_t* offsets,
                            uint32_t* entries, uint32_t* key_count, uint64_t* scratch_keys);

}  // namespace gsf
