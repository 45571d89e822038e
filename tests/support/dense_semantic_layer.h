// Test fixture: a map's semantic layer written densely (tiles of 16 x 16 cells of 1 m), then paletted
// and given neighbour masks as the map builder does (mapping/semantic_layer.h). Shared by the lattice
// layer (lattice_layer.h), the confidence tests' road and the semantic grid's tile -1 test.
#pragma once
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "gsf/detail/semantic_grid.h"
#include "mapping/semantic_layer.h"

namespace gsf_test {

struct DenseSemanticLayer {
  static constexpr uint32_t kTileCells = 16;
  std::vector<uint32_t> keys, cells;  // cells: the dense masks, kTileCells^2 a tile in key order
  std::vector<uint32_t> palette_offsets, palette, neighbours;
  std::vector<uint8_t> indices;
  gsf::SemanticGridView view;

  // The tiles tx in [tx0, tx1), ty in [ty0, ty1), every cell `fill`; finish() makes the view.
  DenseSemanticLayer(int tx0, int tx1, int ty0, int ty1, uint32_t fill) {
    for (int tx = tx0; tx < tx1; ++tx)
      for (int ty = ty0; ty < ty1; ++ty) {
        uint32_t k;
        REQUIRE(gsf::semantic_tile_key(tx, ty, &k));
        keys.push_back(k);
      }
    std::sort(keys.begin(), keys.end());
    cells.assign(keys.size() * kTileCells * kTileCells, fill);
  }
  // ORs `bits` into the cell holding (x, y), which must lie in a stored tile.
  void set(float x, float y, uint32_t bits) {
    const float side = float(kTileCells);
    const int tx = static_cast<int>(std::floor(x / side)), ty = static_cast<int>(std::floor(y / side));
    uint32_t k;
    REQUIRE(gsf::semantic_tile_key(tx, ty, &k));
    const auto it = std::lower_bound(keys.begin(), keys.end(), k);
    REQUIRE((it != keys.end() && *it == k));
    const size_t t = size_t(it - keys.begin());
    const int cx = static_cast<int>(std::floor(x - side * tx)), cy = static_cast<int>(std::floor(y - side * ty));
    cells[(t * kTileCells + size_t(cy)) * kTileCells + size_t(cx)] |= bits;
  }
  const gsf::SemanticGridView& finish() {
    REQUIRE(gsf::mapping::palette_semantic_layer(cells, uint32_t(keys.size()), kTileCells, &palette_offsets, &palette,
                                                 &indices) == gsf::Status::Ok);
    REQUIRE(gsf::mapping::add_semantic_neighbours(keys, kTileCells, &palette_offsets, &palette, &indices,
                                                  &neighbours) == gsf::Status::Ok);
    view.cell = 1.0f;
    view.tile_cells = kTileCells;
    view.tile_count = uint32_t(keys.size());
    view.tile_keys = keys.data();
    view.palette_count = uint32_t(palette.size());
    view.palette_offsets = palette_offsets.data();
    view.palette = palette.data();
    view.cells = indices.data();
    view.neighbours = neighbours.data();
    return view;
  }
};

}  // namespace gsf_test
