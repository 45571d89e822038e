// Offline (host, may use the heap): serialise what the map builder computed at full precision into the
// compact on-board format (map_format.h, version 5): grids quantised per instance (map_quantization.h),
// the refinement layer sorted into its grid with normals (refine_layer_builder.h), the semantic layer
// with a palette per tile (semantic_layer.h). Only what the
// localizer reads is written (the fields' inducing inputs and weights are not: the localizer reads the
// probed grids).
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "gsf/map_format.h"

namespace gsf::mapping {

struct MapContents {
  MapGeoreference georef = local_georeference();
  MapParams params{};                      // refine_cell is set by the writer (0 without refinement points)
  MapCounts counts{};                      // instances, triangles, index_keys, road length, bounds, semantic_tiles
  const MapInstance* instances = nullptr;  // centroid, stability, point_count, label (scales are set here)
  const float* grid_mean = nullptr;        // instances x G x D
  const float* grid_var = nullptr;         // instances x G
  const MapTriangle* triangles = nullptr;  // in index-key order (build_triangle_index)
  const uint64_t* index_keys = nullptr;
  const uint32_t* index_offsets = nullptr;
  const float* refine_xyz = nullptr;  // refine_points x 3, map-local
  uint32_t refine_points = 0;
  float refine_cell = 1.0f;  // m, the localizer's refine.cell
  const uint32_t* semantic_tile_keys = nullptr;
  const uint32_t* semantic_cells = nullptr;  // semantic_tiles x tile_cells^2 masks (the writer palettes them)
};

// Quantises and serialises `c` into `blob` (16-byte aligned words); *bytes is the map's size,
// *refine_tiles (optional) the refinement layer's tile count.
Status write_compact_map(const MapContents& c, std::vector<uint64_t>* blob, size_t* bytes, uint32_t* refine_tiles);

}  // namespace gsf::mapping
