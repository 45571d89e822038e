// Internal (gsf/detail): a pipeline stage or building block, not part of the stable interface; it may
// change between versions. The stable interface is localizer.h, config.h, map_format.h, scan.h, status.h,
// platform.h, class_table.h, georeference.h, stage_configs.h, stage_results.h and the C API gsf.h.
// The map's refinement layer (format v4): the points the refiner aligns a scan to, already sorted into
// its grid and carrying their normals, so the localizer reads the layer in place (no grid or normals in
// the workspace).
//
// Grid: cubic cells of `cell` metres (the localizer's refine.cell), grouped in bird's-eye tiles of
// kRefineTileCells x kRefineTileCells columns. Only tiles with points are stored, sorted by their key
// (semantic_tile_key of the tile coordinates); a tile holds its first point and the z cell its points'
// local z counts from. A point is 8 bytes: its cell inside the tile (z << 8 | y << 4 | x), its position
// inside that cell (3 x 8 bits, a 1/256 of the cell each) and its unit normal (3 x int8, x 127; all
// zero when the map has no reliable normal there). A tile's points are sorted by cell, so a cell is a
// binary search inside its tile.
//
// Quantisation (closed form, asserted by tests/test_map_format.cpp):
//   position: offset q = min(255, floor(f * 256)) for the fraction f in [0, 1) of the cell,
//             dequantised at the bin centre (q + 0.5) / 256: error <= cell / 512 per axis
//             (1.95 mm at the default 1 m cell) plus float rounding of the cell corner;
//   normal:   q = round(127 n) per component, dequantised as q / |q|: error <= sqrt(3) / 254 in
//             each component before renormalisation, so the direction is within 0.4 degrees.
#pragma once
#include <cstdint>

#include "gsf/map_format.h"
#include "gsf/status.h"

namespace gsf {

constexpr uint32_t kRefineTileCells = 16;      // columns per tile side (4 bits each of the cell id)
constexpr int32_t kRefineTileZCells = 256;     // z cells a tile spans above its z base (8 bits)
constexpr int64_t kGroundMaxTilesPerSide = 4;  // RefineLayerView::ground_near's limit

// MapRefineTile and MapRefinePoint, the layer's records, are in map_format.h.

// Integer cell coordinates of a map-local position.
struct RefineCell {
  int32_t x, y, z;
};

struct RefineLayerView {
  float cell = 0.0f;  // m
  uint32_t tile_count = 0;
  uint32_t point_count = 0;
  const MapRefineTile* tiles = nullptr;
  const MapRefinePoint* points = nullptr;

  bool empty() const { return point_count == 0; }
  // Points of one cell: [*begin, *end) (empty when the cell holds none). *tile_hint caches a tile index.
  void find(const RefineCell& c, uint32_t* begin, uint32_t* end, uint32_t* tile_hint) const;
  // Dequantised position (map-local) of point i in tile t, and of a point of cell c (no tile lookup).
  void position(uint32_t t, uint32_t i, float xyz[3]) const;
  void position_in(const RefineCell& c, const MapRefinePoint& p, float xyz[3]) const;
  // Dequantised normal: unit, or zero when the map has no reliable normal there.
  static void normal(const MapRefinePoint& p, float n[3]);
  // The tile a point index belongs to (binary search over first_point).
  uint32_t tile_of(uint32_t i) const;
  // The index of the tile with this key (binary search), tile_count when the layer has none.
  uint32_t tile_with_key(uint32_t key) const;
  // The map's ground around (x, y) (map-local, bird's-eye, within `radius`): a plane z = a x + b y + c
  // fitted to the points whose normal is within 25 deg of vertical, three times, keeping those within
  // 2, 0.5 and then 0.25 m of the last fit (kerbs, a roof edge, a wall's foot). Its upward unit normal
  // into up; returns how many points the last fit kept (up unchanged when fewer than min_points, or
  // when the disc spans more than kGroundMaxTilesPerSide tiles a side: bounded work).
  uint32_t ground_near(float x, float y, float radius, uint32_t min_points, float up[3]) const;
  // Structural checks for untrusted arrays: cell size, keys strictly increasing, first points monotone
  // from 0 within point_count, cells non-decreasing in each tile, normals zero or near unit length.
  Status validate() const;
};

// The map's refinement layer (empty when the map has none).
inline RefineLayerView refine_layer_view(const MapView& map) {
  RefineLayerView r;
  r.cell = map.params.refine_cell;
  r.tile_count = map.counts.refine_tiles;
  r.point_count = map.counts.refine_points;
  r.tiles = map.refine_tiles;
  r.points = map.refine_points;
  return r;
}

// Tile coordinates and local cell id of a cell (false when the tile key is out of range).
bool refine_tile_of(const RefineCell& c, int32_t* tx, int32_t* ty, uint32_t* key);
// Quantisers shared by the map builder and the tests (the inverse of the view's dequantisation).
uint8_t quantize_cell_offset(float fraction);  // fraction of the cell in [0, 1) -> 0..255
int8_t quantize_normal_component(float n);     // [-1, 1] -> -127..127

}  // namespace gsf
