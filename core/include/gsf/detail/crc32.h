// Internal (gsf/detail): a pipeline stage or building block, not part of the stable interface; it may
// change between versions. The stable interface is localizer.h, config.h, map_format.h, scan.h, status.h,
// platform.h, class_table.h, georeference.h, stage_configs.h, stage_results.h and the C API gsf.h.
// CRC-32 (IEEE 802.3, reflected, poly 0xEDB88320), as in zlib/PNG; used by the map format.
#pragma once
#include <cstddef>
#include <cstdint>

namespace gsf {

// Continue a CRC: crc32_update(0, ...) starts one; feed chunks in order.
uint32_t crc32_update(uint32_t crc, const void* data, size_t bytes);
inline uint32_t crc32(const void* data, size_t bytes) { return crc32_update(0, data, bytes); }

}  // namespace gsf
