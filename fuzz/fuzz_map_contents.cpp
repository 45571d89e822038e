// Structure-aware map fuzzing: start from a valid map (the seed corpus map of fuzz_map_loader, or a
// built-in one), apply the input as (offset, xor) patches anywhere after the header, then re-seal all
// CRCs so the loader's content checks (indices, labels, CSR offsets, floats) are what gets exercised.
// Whatever loads must be safe to use: every index the localizer follows is touched.
#include <cstdint>
#include <cstring>
#include <vector>

#include "gsf/crc32.h"
#include "gsf/map_format.h"
#include "gsf/semantic_classes.h"

namespace {

std::vector<uint64_t> base_map(size_t* bytes) {  // also written as the loader's seed (GSF_WRITE_SEED)
  using namespace gsf;
  MapView v;
  std::memset(&v.params, 0, sizeof v.params);
  MapParams& p = v.params;
  p.num_classes = kNumClasses; p.field_input_dims = 2; p.inducing_stride = 2; p.grid_nx = 2; p.grid_ny = 2;
  p.grid_layers = 1; p.grid_spacing = 1; p.layer_spacing = 1; p.length_scale = 2; p.signal_variance = 1;
  p.noise_variance = 0.1f; p.field_radius = 8; p.voxel_size = 0.4f; p.side_bin = 1; p.max_side = 50;
  static MapInstance in[4];
  for (int i = 0; i < 4; ++i) { in[i].centroid[0] = i * 2.f; in[i].centroid[1] = float(i * i); in[i].stability = 1; in[i].label = kPole; in[i].inducing_count = 2; }
  static std::vector<float> inputs(4 * 2 * 3, 0.5f), alpha(4 * 2 * kNumClasses, 0.1f), mean(4 * 4 * kNumClasses, 0.2f), var(16, 0.3f), refine(8, 1.0f);
  static Triangle t[2] = {};
  for (int k = 0; k < 2; ++k) {
    t[k].v[0] = 0; t[k].v[1] = 1; t[k].v[2] = 2 + k; t[k].side[0] = 2.2f; t[k].side[1] = 3.6f; t[k].side[2] = 5.6f + k;
    for (int j = 0; j < 3; ++j) t[k].label[j] = kPole;
  }
  static uint64_t keys[2] = {7, 9};
  static uint32_t off[3] = {0, 1, 2}, ent[2] = {1, 0};
  v.counts.instances = 4; v.counts.triangles = 2; v.counts.index_keys = 2; v.counts.refine_points = 2;
  v.instances = in; v.field_inputs = inputs.data(); v.field_alpha = alpha.data(); v.grid_mean = mean.data();
  v.grid_var = var.data(); v.triangles = t; v.index_keys = keys; v.index_offsets = off; v.index_entries = ent;
  v.refine_points = refine.data();
  // A two-tile semantic layer (2 x 2 cells per tile) so its checks are fuzzed too.
  p.semantic_cell = 1.0f; p.semantic_tile_cells = 2;
  static uint32_t tile_keys[2] = {(32768u << 16) | 32768u, (32768u << 16) | 32769u};
  static uint32_t cells[8] = {gsf::kCellObserved | gsf::class_bit(gsf::kRoad), 0, gsf::kCellObserved | gsf::class_bit(gsf::kPole),
                              gsf::kCellObserved, 0, gsf::kCellObserved | gsf::class_bit(gsf::kTerrain), 0, 0};
  v.counts.semantic_tiles = 2; v.semantic_tile_keys = tile_keys; v.semantic_cells = cells;
  *bytes = map_serialized_size(v);
  std::vector<uint64_t> buf(*bytes / 8 + 2);
  write_map(v, buf.data(), *bytes, nullptr);
  return buf;
}

void reseal(uint8_t* base) {
  gsf::MapHeader h;
  std::memcpy(&h, base, sizeof h);
  gsf::SectionEntry table[gsf::kMapSectionCount];
  std::memcpy(table, base + sizeof h, sizeof table);
  for (auto& e : table) e.crc = gsf::crc32(base + e.offset, e.bytes);
  std::memcpy(base + sizeof h, table, sizeof table);
  h.header_crc = 0;
  std::memcpy(base, &h, sizeof h);
  const uint32_t crc = gsf::crc32(base, sizeof h + sizeof table);
  std::memcpy(base + offsetof(gsf::MapHeader, header_crc), &crc, 4);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static size_t bytes = 0;
  static const std::vector<uint64_t> base = base_map(&bytes);
  std::vector<uint64_t> work(base);
  uint8_t* m = reinterpret_cast<uint8_t*>(work.data());
  const size_t payload = sizeof(gsf::MapHeader) + gsf::kMapSectionCount * sizeof(gsf::SectionEntry);
  for (size_t i = 0; i + 2 < size; i += 3) {
    const size_t off = payload + ((size_t(data[i]) << 8 | data[i + 1]) % (bytes - payload));
    m[off] ^= data[i + 2];
  }
  reseal(m);
  gsf::MapView view;
  if (gsf::load_map(m, bytes, &view) != gsf::Status::Ok) return 0;
  volatile float sink = 0;
  for (uint32_t t = 0; t < view.counts.triangles; ++t)
    for (int k = 0; k < 3; ++k) sink = sink + view.instances[view.triangles[t].v[k]].centroid[0];
  for (uint32_t k = 0; k < view.counts.index_keys; ++k)
    for (uint32_t e = view.index_offsets[k]; e < view.index_offsets[k + 1]; ++e)
      sink = sink + view.triangles[view.index_entries[e]].side[0];
  uint32_t hint = 0;
  const gsf::SemanticGridView grid = view.semantic_grid();
  for (float x = -3; x < 3; x += 0.7f)
    for (float y = -3; y < 40; y += 0.9f) sink = sink + float(grid.cell_at(x, y, &hint) & 0xFF);
  for (uint32_t i = 0; i < view.counts.instances; ++i)
    if (view.instances[i].label >= gsf::kNumClasses || view.instances[i].inducing_count > view.params.inducing_stride)
      __builtin_trap();
  return 0;
}
