// Internal (gsf/detail): a pipeline stage or building block, not part of the stable interface; it may
// change between versions. The stable interface is localizer.h, config.h, map_format.h, scan.h, status.h,
// platform.h, class_table.h, georeference.h, stage_configs.h, stage_results.h and the C API gsf.h.
// The map's triangle hash index as plain CSR arrays (it lives in the map blob, format v5): the map's
// triangles are stored sorted by key (triangle.h: labels, then quantised sides), the index holds the
// sorted unique keys and offsets (key_count + 1) into the triangle array, so bucket k is the contiguous
// run triangles[offsets[k] .. offsets[k + 1]). Because the key carries the labels, a bucket holds only
// label-compatible triangles, and because its lowest field is q2, the three q2 neighbours of a query key
// are one key range: one binary search finds them (range()). O(log keys), bounded. TriangleMatcher
// (triangle_matcher.h) queries the 27 neighbouring keys of a query triangle in 9 ranges, applies
// Outram's acceptance rules and ranks what it accepts.
#pragma once
#include <cstdint>

#include "gsf/detail/triangle.h"
#include "gsf/status.h"

namespace gsf {

struct TriangleIndexView {
  const uint64_t* keys = nullptr;
  const uint32_t* offsets = nullptr;
  uint32_t key_count = 0;
  uint32_t triangle_count = 0;

  // Triangle ids [*begin, *end) of the keys in [lo, hi] (hi - lo <= 2: at most 3 keys); false when none.
  bool range(uint64_t lo, uint64_t hi, uint32_t* begin, uint32_t* end) const {
    uint32_t from = 0;
    return range_from(lo, hi, &from, begin, end);
  }
  // range() for a sequence of increasing ranges: searches only the keys from index *from on (every key
  // before *from must be < lo; 0 searches all with a binary search, otherwise the search gallops
  // forward from *from, cheap when the next range is near) and sets *from to the first key > hi.
  bool range_from(uint64_t lo, uint64_t hi, uint32_t* from, uint32_t* begin, uint32_t* end) const;
  // [*begin, *end) of the triangles with `key`; false (empty range) if absent.
  bool lookup(uint64_t key, uint32_t* begin, uint32_t* end) const { return range(key, key, begin, end); }
  // Structural checks for untrusted arrays: keys strictly increasing, offsets monotone from 0 to
  // triangle_count, and every triangle's key (side_bin) equal to its bucket's key.
  Status validate(const Triangle* triangles, float side_bin) const;
};

// Host-side builder: writes the n triangles of `in` in key order to `out` (ties by position in `in`, so
// deterministic), the unique keys to keys (n) and the offsets to offsets (n + 1); *key_count is the number
// of unique keys. Scratch: n uint64 + n uint32; on return scratch_ids[i] is the position in `in` of
// out[i]. InvalidArgument if side_bin is not positive or a triangle
// has no valid key (triangle_key).
Status build_triangle_index(const Triangle* in, uint32_t n, float side_bin, Triangle* out, uint64_t* keys,
                            uint32_t* offsets, uint32_t* key_count, uint64_t* scratch_keys, uint32_t* scratch_ids);

}  // namespace gsf
