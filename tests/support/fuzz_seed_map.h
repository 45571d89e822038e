// The small valid map both map fuzzers start from (fuzz_map_contents patches it; written as
// fuzz/corpus/fuzz_map_loader/tiny_valid.gsfmap, the loader's seed). test_map_format checks that the
// seed file is this map in the current format, and rewrites it when run with GSF_WRITE_SEED=1.
#pragma once
#include <cstdint>
#include <cstring>
#include <vector>

#include "gsf/detail/semantic_grid.h"
#include "gsf/detail/triangle.h"
#include "gsf/map_format.h"
#include "gsf/semantic_classes.h"

namespace gsf_test {

inline std::vector<uint64_t> fuzz_seed_map(size_t* bytes) {
  using namespace gsf;
  MapView v;
  v.georef.origin[0] = 512345.0;  // georeferenced, so the fuzzers start from a real frame and origin
  v.georef.origin[1] = 5412345.0;
  v.georef.origin[2] = 250.5;
  set_frame_name(&v.georef, "utm-32N");
  std::memset(&v.params, 0, sizeof v.params);
  MapParams& p = v.params;
  p.num_classes = kNumClasses;
  p.field_input_dims = 2;
  p.inducing_stride = 2;
  p.grid_nx = 2;
  p.grid_ny = 2;
  p.grid_layers = 1;
  p.grid_spacing = 1;
  p.layer_spacing = 1;
  p.length_scale = 2;
  p.signal_variance = 1;
  p.noise_variance = 0.1f;
  p.field_radius = 8;
  p.voxel_size = 0.4f;
  p.side_bin = 1;
  p.max_side = 50;
  p.class_table_id = 0xF1D8DAB4u;  // SemanticKITTI's (gsf inspect shows it); the loader takes any value
  static MapInstance in[4];
  for (int i = 0; i < 4; ++i) {
    in[i].centroid[0] = i * 2.f;
    in[i].centroid[1] = float(i * i);
    in[i].stability = 1;
    in[i].label = kPole;
    in[i].mean_min = -0.1f;
    in[i].mean_step = 0.004f;
    in[i].var_min = 0.01f;
    in[i].var_step = 1.5e-5f;
  }
  static std::vector<uint8_t> mean(4 * 4 * kNumClasses, 77);
  static std::vector<uint16_t> var(16, 3000);
  // A two-tile refinement layer (1 m cells) so its checks are fuzzed too.
  p.refine_cell = 1.0f;
  static MapRefineTile refine_tiles[2] = {{(32768u << 16) | 32768u, 0, -1}, {(32768u << 16) | 32769u, 2, 0}};
  static MapRefinePoint refine[3] = {{uint16_t(1 << 8 | 1 << 4 | 2), {10, 20, 30}, {0, 0, 127}},
                                     {uint16_t(1 << 8 | 1 << 4 | 3), {200, 100, 50}, {0, 0, 0}},
                                     {uint16_t(2 << 4 | 1), {128, 128, 128}, {0, 127, 0}}};
  static Triangle t[2] = {};
  for (int k = 0; k < 2; ++k) {
    t[k].v[0] = 0;
    t[k].v[1] = 1;
    t[k].v[2] = 2 + k;
    t[k].side[0] = 2.2f;
    t[k].side[1] = 3.6f;
    t[k].side[2] = 5.6f + k;
    for (int j = 0; j < 3; ++j) t[k].label[j] = kPole;
    t[k].orientation = kOrientationCounterClockwise;
  }
  // Format v5: triangles in key order, one key each.
  static uint64_t keys[2] = {triangle_key(t[0], p.side_bin), triangle_key(t[1], p.side_bin)};
  static uint32_t off[3] = {0, 1, 2};
  v.counts.instances = 4;
  v.counts.triangles = 2;
  v.counts.index_keys = 2;
  v.counts.refine_points = 3;
  v.counts.refine_tiles = 2;
  v.instances = in;
  v.grid_mean = mean.data();
  v.grid_var = var.data();
  v.triangles = t;
  v.index_keys = keys;
  v.index_offsets = off;
  v.refine_tiles = refine_tiles;
  v.refine_points = refine;
  // A two-tile semantic layer (2 x 2 cells per tile) so its checks are fuzzed too.
  p.semantic_cell = 1.0f;
  p.semantic_tile_cells = 2;
  static uint32_t tile_keys[2] = {(32768u << 16) | 32768u, (32768u << 16) | 32769u};
  // Tile (0, 0): road, (none) / pole, observed-empty; tile (0, 1) above it: (none), terrain / (none),
  // (none) - rows of increasing y, as palettes of (mask, 4-neighbour mask) pairs (format v6).
  constexpr uint32_t R = gsf::kCellObserved | gsf::class_bit(gsf::kRoad), O = gsf::kCellObserved;
  constexpr uint32_t P = gsf::kCellObserved | gsf::class_bit(gsf::kPole);
  constexpr uint32_t T = gsf::kCellObserved | gsf::class_bit(gsf::kTerrain);
  static uint32_t palette_offsets[3] = {0, 4, 8};
  static uint32_t palette[8] = {R, 0, P, O, 0, T, 0, 0};
  static uint32_t neighbours[8] = {P, R | O, R | O, P | T, P | T, O, 0, T};
  static uint8_t cells[8] = {0, 1, 2, 3, 0, 1, 2, 3};
  v.counts.semantic_tiles = 2;
  v.counts.semantic_palette = 8;
  v.semantic_tile_keys = tile_keys;
  v.semantic_palette_offsets = palette_offsets;
  v.semantic_palette = palette;
  v.semantic_cells = cells;
  v.semantic_neighbours = neighbours;
  *bytes = map_serialized_size(v);
  std::vector<uint64_t> buf(*bytes / 8 + 2);
  write_map(v, buf.data(), *bytes, nullptr);
  return buf;
}

}  // namespace gsf_test
