// Test fixture: a small semantic layer of a lattice (road, a column every 8 m, one bush), scans of it
// and a voxel layer to score them: shared by the semantic grid's and the answer selection's tests.
#pragma once
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "arena_buffer.h"
#include "dense_semantic_layer.h"
#include "gsf/detail/semantic_grid.h"
#include "gsf/detail/voxel_layer.h"
#include "gsf/detail/wasserstein.h"
#include "gsf/semantic_classes.h"
#include "test_cloud.h"

namespace gsf_test {

using namespace gsf;

// The map's semantic layer over a 64 x 32 m patch: road everywhere, a column every 8 m along y = 0,
// and ONE bush (vegetation) beside the column at x = 24.
struct LatticeLayer : DenseSemanticLayer {
  LatticeLayer() : DenseSemanticLayer(0, 4, -1, 1, kCellObserved | class_bit(kRoad)) {
    for (int c = 0; c < 8; ++c) set(8.0f * c + 0.5f, 0.5f, class_bit(kPole));
    for (float x = 26.0f; x < 28.5f; x += 1.0f)
      for (float y = 2.0f; y < 4.5f; y += 1.0f) set(x, y, class_bit(kVegetation));
    finish();
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
