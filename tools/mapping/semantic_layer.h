// Builds the map's semantic layer (core/include/gsf/detail/semantic_grid.h) from the map's voxels: per
// bird's-eye cell, the classes that make at least `min_share` of the cell's ground voxels (ground
// classes) or of its above-ground voxels (every other class). Host side; uses the heap.
#pragma once
#include <cstdint>
#include <functional>
#include <vector>

#include "gsf/detail/voxel_layer.h"
#include "gsf/status.h"

namespace gsf::mapping {

struct SemanticLayerConfig {
  float cell = 1.0f;         // m
  uint32_t tile_cells = 16;  // cells per tile side (<= 16: 16 x 16 one-byte palette indices a tile)
  float min_share = 0.1f;    // a class is in a cell's mask if it has this share of the cell's group
};

// Writes sorted tile keys and their cells (tile_cells^2 masks each). Voxels outside the representable
// tile range are skipped; returns how many. keep_tile (if given) picks the tiles (x, y tile coordinates)
// to build; voxels of the others are ignored (the tiled map builder builds each tile once, from the
// map tile that owns it).
uint32_t build_semantic_layer(const VoxelLayer& voxels, const SemanticLayerConfig& config, std::vector<uint32_t>* keys,
                              std::vector<uint32_t>* cells,
                              const std::function<bool(int64_t, int64_t)>& keep_tile = nullptr);

// The stored form (semantic_grid.h, format v4): per tile its distinct masks in order of first appearance
// (row-major) and each cell's index into them. `cells` is tile_count x tile_cells^2 dense masks.
// InvalidArgument when tile_cells exceeds kMaxSemanticTileCells.
Status palette_semantic_layer(const std::vector<uint32_t>& cells, uint32_t tile_count, uint32_t tile_cells,
                              std::vector<uint32_t>* palette_offsets, std::vector<uint32_t>* palette,
                              std::vector<uint8_t>* indices);

// Format v6: gives every palette entry its neighbour mask, the union of the masks of the four cells
// sharing an edge with its cell (across tile edges; a side in a tile that is not stored adds nothing),
// and re-palettes each tile over (mask, neighbour mask) pairs in order of first appearance (at most
// one pair a cell, so at most 256 a tile). In: the paletted layer of palette_semantic_layer (keys
// sorted); out: palette_offsets, palette and indices rewritten, neighbours of palette's length. Needs
// the whole layer (a border cell's neighbours are in the next tile), so it runs once, after the tiles.
// InvalidArgument for inconsistent sizes or tile_cells out of range.
Status add_semantic_neighbours(const std::vector<uint32_t>& keys, uint32_t tile_cells,
                               std::vector<uint32_t>* palette_offsets, std::vector<uint32_t>* palette,
                               std::vector<uint8_t>* indices, std::vector<uint32_t>* neighbours);

}  // namespace gsf::mapping
