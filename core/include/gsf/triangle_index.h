// The map's triangle hash index as plain CSR arrays (it lives in the map blob): sorted unique keys,
// offsets (key_count + 1) and triangle ids grouped by key. Lookup is a binary search: O(log keys),
// bounded. match_triangle() queries the 27 neighbouring keys of a query triangle and applies Outram's
// acceptance rules (every side within the relative tolerance, the three labels equal in order).
#pragma once
#include <cstdint>

#include "gsf/fixed_vector.h"
#include "gsf/status.h"
#include "gsf/triangle.h"

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

struct TriangleMatch {
  uint32_t query;  // query triangle id
  uint32_t map;    // map triangle id
};

// Appends accepted map triangles for query triangle `qid` to `out`, at most `per_query_cap`.
// Returns CapacityExceeded if `out` filled up (deterministic prefix kept) or the cap was hit.
Status match_triangle(const Triangle& query, uint32_t qid, const TriangleIndexView& index, const Triangle* map_triangles,
                      const TriangleConfig& config, uint32_t per_query_cap, FixedVector<TriangleMatch>& out);

}  // namespace gsf
