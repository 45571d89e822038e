// Test fixture: a small semantic layer of a lattice (road, a column every 8 m, one bush), scans of it
// and a voxel layer to score them: shared by the semantic grid's and the answer selection's tests.
#pragma once
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "arena_buffer.h"
#include "gsf/detail/semantic_grid.h"
#include "gsf/detail/voxel_layer.h"
#include "gsf/detail/wasserstein.h"
#include "gsf/semantic_classes.h"
#include "mapping/semantic_layer.h"
#include "test_cloud.h"

namespace gsf_test {

using namespace gsf;

// The map's semantic layer over a 64 x 32 m patch: road everywhere, a column every 8 m along y = 0,
// and ONE bush (vegetation) beside the column at x = 24.
struct LatticeLayer {
  std::vector<uint32_t> keys, cells;  // cells: dense masks, stored with a palette per tile as the map does
  std::vector<uint32_t> palette_offsets, palette, neighbours;
  std::vector<uint8_t> indices;
  SemanticGridView view;
  LatticeLayer() {
    const uint32_t T = 16;
    for (int tx = 0; tx < 4; ++tx)
      for (int ty = -1; ty < 1; ++ty) {
        uint32_t k;
        semantic_tile_key(tx, ty, &k);
        keys.push_back(k);
      }
    std::sort(keys.begin(), keys.end());
    cells.assign(keys.size() * T * T, kCellObserved | class_bit(kRoad));
    view.cell = 1.0f;
    view.tile_cells = T;
    view.tile_count = static_cast<uint32_t>(keys.size());
    view.tile_keys = keys.data();
    for (int c = 0; c < 8; ++c) set(8.0f * c + 0.5f, 0.5f, class_bit(kPole));
    for (float x = 26.0f; x < 28.5f; x += 1.0f)
      for (float y = 2.0f; y < 4.5f; y += 1.0f) set(x, y, class_bit(kVegetation));
    REQUIRE(mapping::palette_semantic_layer(cells, view.tile_count, T, &palette_offsets, &palette, &indices) ==
            Status::Ok);
    REQUIRE(mapping::add_semantic_neighbours(keys, T, &palette_offsets, &palette, &indices, &neighbours) == Status::Ok);
    view.palette_count = static_cast<uint32_t>(palette.size());
    view.palette_offsets = palette_offsets.data();
    view.palette = palette.data();
    view.cells = indices.data();
    view.neighbours = neighbours.data();
  }
  void set(float x, float y, uint32_t bits) {
    const int tx = static_cast<int>(std::floor(x / 16)), ty = static_cast<int>(std::floor(y / 16));
    uint32_t k;
    semantic_tile_key(tx, ty, &k);
    const size_t t = std::lower_bound(keys.begin(), keys.end(), k) - keys.begin();
    const int cx = static_cast<int>(x - 16.0f * tx), cy = static_cast<int>(y - 16.0f * ty);
    cells[t * 256 + cy * 16 + cx] |= bits;
  }
};

// The query scan seen from (sx, 0): road, the columns, and the bush if it is in the world at all.
inline Cloud lattice_scan(float sx, bool with_bush) {
  Cloud c;
  for (float x = -20; x <= 20; x += 0.3f)
    for (float y = -10; y <= 10; y += 0.3f) c.add(x, y, 0.0f, 40);
  for (int col = 0; col < 8; ++col)
    for (float z = 0.3f; z < 4.0f; z += 0.2f) c.add(8.0f * col + 0.5f - sx, 0.5f, z, 80);
  if (with_bush)
    for (float x = 26.0f; x < 28.5f; x += 0.2f)
      for (float y = 2.0f; y < 4.5f; y += 0.2f)
        for (float z = 0.3f; z < 1.2f; z += 0.3f) c.add(x - sx, y, z, 70);
  return c;
}

// The lattice layer, a voxel layer for scans of it (min_range 0: they start at the sensor) and the
// stability weights: what every verification test below starts from.
struct LatticeVerification {
  LatticeLayer layer;
  VoxelConfig config;
  ArenaBuffer buf;
  VoxelLayer voxels;
  float weights[kNumClasses];
  LatticeVerification() : config(scan_config()), buf(VoxelLayer::required_bytes(config)) {
    REQUIRE(voxels.bind(buf.arena, config) == Status::Ok);
    stability_weights(weights);
  }
  void build(const Cloud& scan) { REQUIRE(voxels.build(scan.view(), nullptr) == Status::Ok); }
  static VoxelConfig scan_config() {
    VoxelConfig c;
    c.min_range = 0.0f;
    return c;
  }
};

}  // namespace gsf_test
