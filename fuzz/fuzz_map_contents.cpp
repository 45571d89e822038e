// Structure-aware map fuzzing: start from a valid map (tests/support/fuzz_seed_map.h, also the seed
// corpus map of fuzz_map_loader), apply the input as (offset, xor) patches anywhere after the header, then re-seal all
// CRCs so the loader's content checks (indices, labels, CSR offsets, floats) are what gets exercised.
// Whatever loads must be safe to use: every index the localizer follows is touched.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "fuzz_seed_map.h"
#include "gsf/detail/crc32.h"
#include "gsf/detail/map_quantization.h"
#include "gsf/detail/refine_layer.h"
#include "gsf/detail/semantic_grid.h"
#include "gsf/map_format.h"

namespace {

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
  static const std::vector<uint64_t> base = gsf_test::fuzz_seed_map(&bytes);
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
      sink = sink + view.triangles[e].side[0];
  uint32_t hint = 0;
  const gsf::SemanticGridView grid = gsf::semantic_grid_view(view);
  for (float x = -3; x < 3; x += 0.7f)
    for (float y = -3; y < 40; y += 0.9f)
      sink = sink + float((grid.cell_at(x, y, &hint) ^ grid.neighbours_at(x, y)) & 0xFF);
  // The verification scorer follows every palette index a cell names into the masks and neighbour masks.
  gsf::VerifyPoint points[64];
  float weights[gsf::kNumClasses];
  for (int c = 0; c < gsf::kNumClasses; ++c) weights[c] = 1.0f;
  for (uint32_t i = 0; i < 64; ++i)
    points[i] = gsf::VerifyPoint{float(i % 8) * 0.5f - 1.0f, float(i / 8) * 0.5f - 1.0f, i % gsf::kNumClasses};
  sink = sink + gsf::verify_pose(points, 64, grid, Eigen::Isometry3d::Identity(), 64, weights).score;
  for (uint32_t i = 0; i < view.counts.instances; ++i)
    if (view.instances[i].label >= gsf::kNumClasses) __builtin_trap();
  const gsf::RefineLayerView refine = gsf::refine_layer_view(view);
  for (int32_t x = -2; x < 20; ++x)
    for (int32_t z = -2; z < 3; ++z) {
      uint32_t b = 0, e = 0;
      refine.find(gsf::RefineCell{x, x / 2, z}, &b, &e, &hint);
      if (e > view.counts.refine_points || b > e) __builtin_trap();
      for (uint32_t k = b; k < e; ++k) {
        float p[3], n[3];
        refine.position_in(gsf::RefineCell{x, x / 2, z}, view.refine_points[k], p);
        gsf::RefineLayerView::normal(view.refine_points[k], n);
        sink = sink + p[0] + n[0];
      }
    }
  // Dequantised grids: finite, variances >= 0.
  static std::vector<float> mean, var;
  mean.resize(size_t(view.grid_points()) * view.params.num_classes);
  var.resize(view.grid_points());
  for (uint32_t i = 0; i < view.counts.instances; ++i) {
    gsf::dequantize_instance_grid(view, i, mean.data(), var.data());
    for (float v : var)
      if (!(v >= 0.0f) || !std::isfinite(v)) __builtin_trap();
    for (float v : mean)
      if (!std::isfinite(v)) __builtin_trap();
  }
  return 0;
}
