// The map builder's whole-map stages run tile by tile, so their memory is one tile and its halo, not
// the world. Per tile of the TileStore, the voxels of the tile and of its neighbours within the halo
// are loaded (sorted by key, as the whole map would be) into one VoxelLayer; the localizer's stages run
// on it (instance clustering, geometric poles, per-instance fields, refinement points, semantic layer)
// and the tile keeps what it owns:
//  - an instance (cluster or pole chain) belongs to the tile holding its lowest voxel key (the voxel the
//    whole-map stages discover it from), so an instance spanning a tile border is built once, from the
//    same voxels in the same order as in a whole-map build;
//  - a refinement cell's point is the mean of its owned voxels' centroids over all tiles (exact double
//    sums, so the same in any tiling; cells are final, and emitted, once the column of tiles left of
//    them is done: tiles come x-major; in a blocked build once the column of blocks is);
//  - a semantic-layer tile belongs to the first existing map tile (in id order) it overlaps.
// The halo (tile_halo_m) covers what those read around an owned voxel: an instance's extent plus the
// larger of its clustering tolerance and the field radius, a semantic tile, and a pole chain's reach.
// So the result equals a single-tile (unbounded) build byte for byte, as long as no rejected cluster or
// pole chain is larger than the halo while a truncated part of it would pass (a cluster is rejected for
// extent above max_extent, and the halo is wider than that).
// Capacities (max_instances, max_pole_instances) are applied over the whole map after the tiles, with the
// stages' own rules (largest by points; poles best by score), so capped maps match too.
#pragma once
#include <cstdint>
#include <functional>
#include <vector>

#include "gsf/class_table.h"
#include "gsf/config.h"
#include "gsf/map_format.h"
#include "mapping/map_builder.h"
#include "mapping/tile_store.h"

namespace gsf::mapping {

// What the map is made of before triangles and serialisation, in map order: the clustered instances
// (by their lowest voxel key), then the geometric poles / trunks (likewise), each with its field rows;
// the refinement points (by refinement cell key) and the semantic layer's tiles (by key). Grids and
// the semantic layer are already in their stored form (quantised per instance as each field is fitted,
// paletted per tile), so the builder never holds them as floats or dense masks for the whole map.
struct MapContent {
  std::vector<MapInstance> instances;      // with their grids' quantisation scales (map_quantization.h)
  std::vector<float> centroids;            // 3 per instance
  std::vector<uint8_t> labels;             // per instance
  std::vector<uint8_t> mean;               // per instance G x D, G: the probed field grid (quantised)
  std::vector<uint16_t> var;               // per instance G (quantised)
  std::vector<std::vector<float>> refine;  // x, y, z per point, in chunks (refine_layer_builder.h)
  std::vector<uint32_t> semantic_keys, semantic_palette_offsets, semantic_palette;  // semantic_grid.h
  std::vector<uint8_t> semantic_cells;                                              // palette indices
  std::vector<uint32_t> semantic_neighbours;  // per palette entry (add_semantic_neighbours)
};

// Halo (m) around a map tile that the tile's stages read beyond it (see above).
double tile_halo_m(const LocalizerConfig& config, const ClassTable& classes, const MapBuildConfig& options);

// Builds the content from the store's voxels; fills map_voxels, instances, pole_instances,
// instances_dropped, field_points_dropped, fields_failed, instances_by_class, refine_points,
// semantic_tiles and the cluster and field times of *stats. InvalidInput for an empty store.
Status build_map_content(TileStore& store, const LocalizerConfig& config, const ClassTable& classes,
                         const MapBuildConfig& options, MapContent* out, MapBuildStats* stats,
                         const Progress& progress);

// The blocked build (MapBuilder::build_blocked): the map's tiles in square blocks of block_tiles x
// block_tiles tiles, one block in memory at a time. fill() puts into the (unbounded, emptied) store
// every voxel of the block and of its halo (tile_halo_m around it), final: the stages then run on the
// block's tiles as on the whole store, and the store is emptied for the next block. `tiles`: every tile
// of the map (sorted), for the semantic layer's ownership. The content is build_map_content's.
struct MapBlock {
  int32_t bx = 0, by = 0;       // block coordinates (tile x / block_tiles, floored)
  std::vector<uint64_t> tiles;  // the map tiles in it, sorted
};
using FillBlock = std::function<Status(const MapBlock& block, TileStore* store)>;
// `blocks` sorted x-major (bx, then by).
Status build_map_content_blocked(const std::vector<MapBlock>& blocks, const std::vector<uint64_t>& tiles,
                                 int32_t block_tiles, const FillBlock& fill, TileStore& store,
                                 const LocalizerConfig& config, const ClassTable& classes,
                                 const MapBuildConfig& options, MapContent* out, MapBuildStats* st,
                                 const Progress& progress);

}  // namespace gsf::mapping
