// The C++ test fixture (tiny_world.h: the simulator's tiny world, its map and query scans) for tests
// written in C (tests/test_c_api.c). Implemented in tiny_world_c.cpp; the world is built on first use.
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "gsf/gsf.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct gsf_test_query {
  const float* xyzi;       // count x 4 (x, y, z, intensity), sensor frame
  const uint32_t* labels;  // count SemanticKITTI label words
  const float* logits;     // count x GSF_NUM_CLASSES synthetic logits
  uint32_t count;
  uint32_t in_zone;  // 1 inside the simulated repetitive zone
  double truth[12];  // ground-truth pose in the simulator's frame (the tiny map's, origin 0), row-major 3x4
} gsf_test_query;

// The tiny world's serialized map blob (16-byte aligned, owned by the fixture) and its size.
const void* gsf_test_tiny_map(size_t* bytes);
// The same map with its header's georeference set to `origin` and `frame` (sections unchanged): what the
// same drive posed in that frame (origin + the simulator's poses) would have given. 16-byte aligned,
// owned by the fixture until the next call; NULL for a bad frame name.
const void* gsf_test_tiny_map_georeferenced(const double origin[3], const char* frame, size_t* bytes);
uint32_t gsf_test_tiny_query_count(void);
// Query k (views into the fixture); GSF_STATUS_NOT_FOUND past the end.
int gsf_test_tiny_query(uint32_t k, gsf_test_query* out);
// What the C++ API (gsf::Localizer with the fixture's config) answers for query k, converted to a
// gsf_result independently of the C API.
int gsf_test_cpp_localize(uint32_t k, gsf_result* out);
// Heap allocations made by this process so far (tests/support/alloc_counter).
uint64_t gsf_test_allocations(void);

#ifdef __cplusplus
}  // extern "C"
#endif
