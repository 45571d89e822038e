#include "gsf/map_format.h"

#include <cmath>
#include <cstring>

#include "gsf/detail/crc32.h"
#include "gsf/detail/refine_layer.h"
#include "gsf/detail/semantic_grid.h"
#include "gsf/detail/triangle_index.h"
#include "gsf/semantic_classes.h"

namespace gsf {
namespace {

constexpr uint64_t kAlign = 16;
constexpr uint32_t kMaxInducingStride = 1024;
constexpr uint32_t kMaxGridPointsInMap = 4096;

uint64_t align_up(uint64_t v) { return (v + (kAlign - 1)) & ~(kAlign - 1); }

struct SectionSpec {
  MapSection id;
  uint32_t elem_bytes;
  uint64_t count;  // elements
  const void* data;
};

// The section list a MapView implies: the single source of truth for sizes on write and on load.
// Returns false if a count product overflows.
bool section_specs(const MapView& m, SectionSpec* s) {
  const uint64_t n = m.counts.instances;
  const uint64_t stride = m.params.inducing_stride;
  const uint64_t d = m.params.num_classes;
  const uint64_t g = static_cast<uint64_t>(m.params.grid_nx) * m.params.grid_ny * m.params.grid_layers;
  if (stride > kMaxInducingStride || g > kMaxGridPointsInMap || d > 64) return false;
  s[0] = {MapSection::Instances, sizeof(MapInstance), n, m.instances};
  s[1] = {MapSection::GridMean, sizeof(uint8_t), n * g * d, m.grid_mean};
  s[2] = {MapSection::GridVar, sizeof(uint16_t), n * g, m.grid_var};
  s[3] = {MapSection::Triangles, sizeof(MapTriangle), m.counts.triangles, m.triangles};
  s[4] = {MapSection::IndexKeys, sizeof(uint64_t), m.counts.index_keys, m.index_keys};
  s[5] = {MapSection::IndexOffsets, sizeof(uint32_t), uint64_t(m.counts.index_keys) + 1, m.index_offsets};
  s[6] = {MapSection::RefineTiles, sizeof(MapRefineTile), m.counts.refine_tiles, m.refine_tiles};
  s[7] = {MapSection::RefinePoints, sizeof(MapRefinePoint), m.counts.refine_points, m.refine_points};
  const uint64_t tc = m.params.semantic_tile_cells;
  if (tc > kMaxSemanticTileCells) return false;
  s[8] = {MapSection::SemanticTileKeys, sizeof(uint32_t), m.counts.semantic_tiles, m.semantic_tile_keys};
  const uint64_t tiles = m.counts.semantic_tiles;
  s[9] = {MapSection::SemanticPaletteOffsets, sizeof(uint32_t), tiles ? tiles + 1 : 0, m.semantic_palette_offsets};
  s[10] = {MapSection::SemanticPalette, sizeof(uint32_t), m.counts.semantic_palette, m.semantic_palette};
  s[11] = {MapSection::SemanticCells, sizeof(uint8_t), tiles * tc * tc, m.semantic_cells};
  s[12] = {MapSection::SemanticNeighbours, sizeof(uint32_t), m.counts.semantic_palette, m.semantic_neighbours};
  return true;
}

uint64_t table_end() { return sizeof(MapHeader) + uint64_t(kMapSectionCount) * sizeof(SectionEntry); }

bool all_finite(const float* p, uint64_t n) {
  for (uint64_t i = 0; i < n; ++i)
    if (!std::isfinite(p[i])) return false;
  return true;
}

bool host_is_little_endian() {
  const uint32_t one = 1;
  uint8_t b;
  std::memcpy(&b, &one, 1);
  return b == 1;
}

Status check_params(const MapParams& p) {
  if (p.num_classes != static_cast<uint32_t>(kNumClasses)) return Status::ConfigMismatch;
  if (p.field_input_dims != 2 && p.field_input_dims != 3) return Status::CorruptData;
  if (p.inducing_stride == 0 || p.inducing_stride > kMaxInducingStride) return Status::CorruptData;
  const uint64_t g = uint64_t(p.grid_nx) * p.grid_ny * p.grid_layers;
  if (g == 0 || g > kMaxGridPointsInMap) return Status::CorruptData;
  const float fs[] = {p.grid_spacing, p.layer_spacing, p.grid_z0,  p.length_scale, p.signal_variance, p.noise_variance,
                      p.field_radius, p.voxel_size,    p.side_bin, p.min_side,     p.max_side,        p.refine_cell};
  if (!all_finite(fs, sizeof(fs) / sizeof(fs[0]))) return Status::CorruptData;
  if (!(p.grid_spacing > 0 && p.length_scale > 0 && p.signal_variance > 0 && p.noise_variance > 0 &&
        p.field_radius > 0 && p.voxel_size > 0 && p.side_bin > 0 && p.min_side >= 0 && p.max_side > p.min_side))
    return Status::CorruptData;
  // The triangle keys' 16-bit side fields hold every side up to max_side (triangle.h).
  if (!(p.max_side / p.side_bin < float(kTriangleKeyMaxBin - 1))) return Status::CorruptData;
  // The semantic layer's shape: both zero (no layer) or a positive cell and 1..64 cells per tile.
  const bool no_layer = p.semantic_cell == 0.0f && p.semantic_tile_cells == 0;
  if (!no_layer && !(std::isfinite(p.semantic_cell) && p.semantic_cell > 0 && p.semantic_tile_cells > 0 &&
                     p.semantic_tile_cells <= kMaxSemanticTileCells))
    return Status::CorruptData;
  if (p.refine_cell < 0.0f) return Status::CorruptData;
  return Status::Ok;
}

// A quantisation scale: finite, step >= 0, and the largest level finite.
bool valid_scale(float min, float step, uint32_t levels) {
  return std::isfinite(min) && std::isfinite(step) && step >= 0.0f && std::isfinite(min + step * float(levels));
}

// Semantic checks on the validated sections: everything a later stage indexes with must be in range.
Status check_contents(const MapView& m) {
  const uint32_t n = m.counts.instances;
  const uint32_t d = m.params.num_classes;
  const uint64_t g = m.grid_points();
  for (uint32_t i = 0; i < n; ++i) {
    const MapInstance& in = m.instances[i];
    if (!all_finite(in.centroid, 3) || !std::isfinite(in.stability) || in.stability < 0) return Status::CorruptData;
    if (in.label >= d) return Status::CorruptData;
    // Dequantised grids must be finite, variances >= 0 (every level of a valid scale is).
    if (!valid_scale(in.mean_min, in.mean_step, kGridMeanLevels) ||
        !valid_scale(in.var_min, in.var_step, kGridVarLevels) || in.var_min < 0.0f)
      return Status::CorruptData;
    if (in.pad[0] | in.pad[1] | in.pad[2]) return Status::CorruptData;
  }
  (void)g;
  for (uint32_t t = 0; t < m.counts.triangles; ++t) {
    const MapTriangle& tri = m.triangles[t];
    for (int k = 0; k < 3; ++k) {
      if (tri.v[k] >= n) return Status::CorruptData;
      if (tri.label[k] != m.instances[tri.v[k]].label) return Status::CorruptData;
    }
    if (!all_finite(tri.side, 3) || !(tri.side[0] <= tri.side[1] && tri.side[1] <= tri.side[2]) || tri.side[0] < 0 ||
        tri.orientation < kOrientationCounterClockwise || tri.orientation > kOrientationFlat)
      return Status::CorruptData;
  }
  // CSR index over the triangles (stored in key order): strictly increasing keys, monotone offsets
  // covering exactly the triangles, every triangle's key equal to its bucket's.
  TriangleIndexView index;
  index.keys = m.index_keys;
  index.offsets = m.index_offsets;
  index.key_count = m.counts.index_keys;
  index.triangle_count = m.counts.triangles;
  const Status is = index.validate(m.triangles, m.params.side_bin);
  if (is != Status::Ok) return is;
  // Refinement layer: present exactly when it has points, with a cell size; then structurally valid.
  if ((m.counts.refine_points == 0) != (m.counts.refine_tiles == 0)) return Status::CorruptData;
  if (m.counts.refine_points > 0 && !(m.params.refine_cell > 0.0f)) return Status::CorruptData;
  const Status rs = refine_layer_view(m).validate();
  if (rs != Status::Ok) return rs;
  if (m.counts.semantic_tiles > 0 && m.params.semantic_tile_cells == 0) return Status::CorruptData;
  if (m.counts.semantic_tiles == 0 && m.counts.semantic_palette != 0) return Status::CorruptData;
  return semantic_grid_view(m).validate(d);
}

}  // namespace

size_t map_serialized_size(const MapView& contents) {
  SectionSpec s[kMapSectionCount];
  if (!section_specs(contents, s)) return 0;
  uint64_t off = align_up(table_end());
  for (const SectionSpec& sp : s) off = align_up(off + sp.count * sp.elem_bytes);
  return static_cast<size_t>(off);
}

size_t map_header_bytes() { return static_cast<size_t>(table_end()); }

Status map_layout(const MapView& m, MapSectionLayout* sections, size_t* total) {
  if (total) *total = 0;
  if (check_params(m.params) != Status::Ok || !valid_georeference(m.georef)) return Status::InvalidArgument;
  SectionSpec s[kMapSectionCount];
  if (!section_specs(m, s)) return Status::InvalidArgument;
  uint64_t off = align_up(table_end());
  for (uint32_t i = 0; i < kMapSectionCount; ++i) {
    const uint64_t bytes = s[i].count * s[i].elem_bytes;
    if (sections) sections[i] = {static_cast<uint32_t>(s[i].id), s[i].elem_bytes, off, bytes};
    off = align_up(off + bytes);
  }
  if (total) *total = static_cast<size_t>(off);
  return Status::Ok;
}

Status write_map_header(const MapView& m, const uint32_t* section_crcs, void* out, size_t out_bytes) {
  if (out == nullptr || section_crcs == nullptr) return Status::InvalidArgument;
  if (out_bytes < table_end()) return Status::BufferTooSmall;
  MapSectionLayout layout[kMapSectionCount];
  size_t total = 0;
  const Status ls = map_layout(m, layout, &total);
  if (ls != Status::Ok) return ls;
  uint8_t* base = static_cast<uint8_t*>(out);
  MapHeader h;
  std::memset(&h, 0, sizeof(h));
  std::memcpy(h.magic, kMapMagic, sizeof(kMapMagic));
  h.version = kMapVersion;
  h.header_bytes = static_cast<uint32_t>(table_end());
  h.total_bytes = total;
  h.section_count = kMapSectionCount;
  h.georef = m.georef;
  h.params = m.params;
  h.counts = m.counts;
  SectionEntry table[kMapSectionCount];
  std::memset(table, 0, sizeof(table));
  for (uint32_t i = 0; i < kMapSectionCount; ++i) {
    table[i].id = layout[i].id;
    table[i].elem_bytes = layout[i].elem_bytes;
    table[i].offset = layout[i].offset;
    table[i].bytes = layout[i].bytes;
    table[i].crc = section_crcs[i];
  }
  std::memcpy(base + sizeof(MapHeader), table, sizeof(table));
  std::memcpy(base, &h, sizeof(h));
  const uint32_t crc = crc32(base, table_end());
  std::memcpy(base + offsetof(MapHeader, header_crc), &crc, sizeof(crc));
  return Status::Ok;
}

Status write_map(const MapView& m, void* out, size_t out_bytes, size_t* written) {
  if (written) *written = 0;
  if (!host_is_little_endian()) return Status::Unsupported;
  if (out == nullptr || (reinterpret_cast<uintptr_t>(out) % kAlign) != 0) return Status::InvalidArgument;
  Status ps = check_params(m.params);
  if (ps != Status::Ok || !valid_georeference(m.georef)) return Status::InvalidArgument;
  SectionSpec s[kMapSectionCount];
  if (!section_specs(m, s)) return Status::InvalidArgument;
  for (const SectionSpec& sp : s)
    if (sp.count > 0 && sp.data == nullptr && sp.id != MapSection::IndexOffsets) return Status::InvalidArgument;
  if (m.index_offsets == nullptr) return Status::InvalidArgument;
  MapSectionLayout layout[kMapSectionCount];
  size_t total = 0;
  if (map_layout(m, layout, &total) != Status::Ok || total == 0) return Status::InvalidArgument;
  if (out_bytes < total) return Status::BufferTooSmall;

  uint8_t* base = static_cast<uint8_t*>(out);
  std::memset(base, 0, total);
  uint32_t crcs[kMapSectionCount];
  for (uint32_t i = 0; i < kMapSectionCount; ++i) {
    if (layout[i].bytes) std::memcpy(base + layout[i].offset, s[i].data, layout[i].bytes);
    crcs[i] = crc32(base + layout[i].offset, layout[i].bytes);
  }
  const Status hs = write_map_header(m, crcs, base, total);
  if (hs != Status::Ok) return hs;
  if (written) *written = total;
  return Status::Ok;
}

Status load_map(const void* data, size_t bytes, MapView* out) {
  if (out == nullptr) return Status::InvalidArgument;
  *out = MapView();
  if (data == nullptr) return Status::InvalidArgument;
  if (reinterpret_cast<uintptr_t>(data) % kAlign != 0) return Status::InvalidArgument;
  if (!host_is_little_endian()) return Status::Unsupported;
  if (bytes < sizeof(MapHeader)) return Status::Truncated;
  const uint8_t* base = static_cast<const uint8_t*>(data);
  MapHeader h;
  std::memcpy(&h, base, sizeof(h));
  if (std::memcmp(h.magic, kMapMagic, sizeof(kMapMagic)) != 0) return Status::CorruptData;
  if (h.version != kMapVersion) return Status::VersionMismatch;
  if (h.section_count != kMapSectionCount || h.header_bytes != table_end()) return Status::CorruptData;
  if (bytes < table_end()) return Status::Truncated;
  if (h.total_bytes > bytes) return Status::Truncated;
  if (h.total_bytes != bytes) return Status::CorruptData;
  // Header CRC over header (crc field zeroed) + section table.
  uint32_t crc = crc32_update(0, base, offsetof(MapHeader, header_crc));
  const uint32_t zero = 0;
  crc = crc32_update(crc, &zero, sizeof(zero));
  crc =
      crc32_update(crc, base + offsetof(MapHeader, header_crc) + 4, table_end() - offsetof(MapHeader, header_crc) - 4);
  if (crc != h.header_crc) return Status::CorruptData;
  const Status ps = check_params(h.params);
  if (ps != Status::Ok) return ps;
  if (h.flags != 0 || h.counts.reserved[0] | h.counts.reserved[1]) return Status::CorruptData;
  if (!valid_georeference(h.georef)) return Status::CorruptData;

  MapView m;
  m.georef = h.georef;
  m.params = h.params;
  m.counts = h.counts;
  m.total_bytes = bytes;
  SectionSpec s[kMapSectionCount];
  if (!section_specs(m, s)) return Status::CorruptData;
  SectionEntry table[kMapSectionCount];
  std::memcpy(table, base + sizeof(MapHeader), sizeof(table));
  uint64_t prev_end = table_end();
  const void* ptr[kMapSectionCount];
  for (uint32_t i = 0; i < kMapSectionCount; ++i) {
    const SectionEntry& e = table[i];
    if (e.id != static_cast<uint32_t>(s[i].id) || e.elem_bytes != s[i].elem_bytes) return Status::CorruptData;
    if (e.bytes != s[i].count * s[i].elem_bytes) return Status::CorruptData;
    if (e.offset % kAlign != 0 || e.offset < prev_end || e.offset > bytes || e.bytes > bytes - e.offset)
      return Status::CorruptData;
    if (crc32(base + e.offset, e.bytes) != e.crc) return Status::CorruptData;
    ptr[i] = base + e.offset;
    prev_end = e.offset + e.bytes;
  }
  m.instances = static_cast<const MapInstance*>(ptr[0]);
  m.grid_mean = static_cast<const uint8_t*>(ptr[1]);
  m.grid_var = static_cast<const uint16_t*>(ptr[2]);
  m.triangles = static_cast<const MapTriangle*>(ptr[3]);
  m.index_keys = static_cast<const uint64_t*>(ptr[4]);
  m.index_offsets = static_cast<const uint32_t*>(ptr[5]);
  m.refine_tiles = m.counts.refine_tiles ? static_cast<const MapRefineTile*>(ptr[6]) : nullptr;
  m.refine_points = m.counts.refine_points ? static_cast<const MapRefinePoint*>(ptr[7]) : nullptr;
  m.semantic_tile_keys = m.counts.semantic_tiles ? static_cast<const uint32_t*>(ptr[8]) : nullptr;
  m.semantic_palette_offsets = m.counts.semantic_tiles ? static_cast<const uint32_t*>(ptr[9]) : nullptr;
  m.semantic_palette = m.counts.semantic_tiles ? static_cast<const uint32_t*>(ptr[10]) : nullptr;
  m.semantic_cells = m.counts.semantic_tiles ? static_cast<const uint8_t*>(ptr[11]) : nullptr;
  m.semantic_neighbours = m.counts.semantic_tiles ? static_cast<const uint32_t*>(ptr[12]) : nullptr;
  const Status cs = check_contents(m);
  if (cs != Status::Ok) return cs;
  *out = m;
  return Status::Ok;
}

}  // namespace gsf
