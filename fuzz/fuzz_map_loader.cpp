// Fuzz the map loader: any byte string must be rejected or yield a view whose every index is in range.
#include <cstdint>
#include <cstring>
#include <vector>

#include "gsf/map_format.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  // load_map requires 16-byte alignment: copy into an aligned buffer (as firmware would place it).
  std::vector<uint64_t> words(size / 8 + 2);
  std::memcpy(words.data(), data, size);
  gsf::MapView view;
  const gsf::Status s = gsf::load_map(words.data(), size, &view);
  if (s != gsf::Status::Ok) return 0;
  // Touch everything the localizer would index with; ASan/UBSan flag any out-of-range access.
  volatile float sink = 0;
  for (uint32_t t = 0; t < view.counts.triangles; ++t)
    for (int k = 0; k < 3; ++k) sink = sink + view.instances[view.triangles[t].v[k]].centroid[0];
  for (uint32_t k = 0; k < view.counts.index_keys; ++k)
    for (uint32_t e = view.index_offsets[k]; e < view.index_offsets[k + 1]; ++e)
      sink = sink + view.triangles[e].side[0];
  return 0;
}
