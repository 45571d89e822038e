#include "mapping/semantic_layer.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>

#include "gsf/detail/semantic_grid.h"
#include "mapping/floor_div.h"

namespace gsf::mapping {

uint32_t build_semantic_layer(const VoxelLayer& voxels, const SemanticLayerConfig& c, std::vector<uint32_t>* keys,
                              std::vector<uint32_t>* cells, const std::function<bool(int64_t, int64_t)>& keep_tile) {
  keys->clear();
  cells->clear();
  const uint32_t T = c.tile_cells;
  const double tile = double(c.cell) * T;
  // tile key -> per cell class counts
  std::map<uint32_t, std::vector<std::array<uint32_t, kNumClasses>>> tiles;
  uint32_t skipped = 0;
  for (uint32_t i = 0; i < voxels.size(); ++i) {
    const Voxel& v = voxels.voxel(i);
    const double fx = std::floor(v.centroid[0] / tile), fy = std::floor(v.centroid[1] / tile);
    uint32_t key;
    if (!(std::fabs(fx) < 32768.0 && std::fabs(fy) < 32768.0) ||
        !semantic_tile_key(static_cast<int64_t>(fx), static_cast<int64_t>(fy), &key)) {
      ++skipped;
      continue;
    }
    if (keep_tile && !keep_tile(static_cast<int64_t>(fx), static_cast<int64_t>(fy))) continue;
    auto& t = tiles[key];
    if (t.empty()) t.assign(size_t(T) * T, std::array<uint32_t, kNumClasses>{});
    const int64_t cx = std::clamp<int64_t>(static_cast<int64_t>((v.centroid[0] - fx * tile) / c.cell), 0, T - 1);
    const int64_t cy = std::clamp<int64_t>(static_cast<int64_t>((v.centroid[1] - fy * tile) / c.cell), 0, T - 1);
    t[size_t(cy) * T + size_t(cx)][v.label] += 1;
  }
  for (const auto& [key, t] : tiles) {
    keys->push_back(key);
    for (const auto& counts : t) {
      uint32_t ground = 0, above = 0;
      for (int k = 0; k < kNumClasses; ++k) (class_bit(k) & kGroundClasses ? ground : above) += counts[k];
      uint32_t mask = (ground + above) > 0 ? kCellObserved : 0u;
      for (int k = 0; k < kNumClasses; ++k) {
        const uint32_t group = class_bit(k) & kGroundClasses ? ground : above;
        if (counts[k] > 0 && double(counts[k]) >= double(c.min_share) * group) mask |= class_bit(k);
      }
      cells->push_back(mask);
    }
  }
  return skipped;
}

Status palette_semantic_layer(const std::vector<uint32_t>& cells, uint32_t tile_count, uint32_t tile_cells,
                              std::vector<uint32_t>* palette_offsets, std::vector<uint32_t>* palette,
                              std::vector<uint8_t>* indices) {
  palette_offsets->clear();
  palette->clear();
  indices->clear();
  if (tile_cells == 0 || tile_cells > kMaxSemanticTileCells) return Status::InvalidArgument;
  const size_t per_tile = size_t(tile_cells) * tile_cells;
  if (cells.size() != per_tile * tile_count) return Status::InvalidArgument;
  if (tile_count == 0) return Status::Ok;
  indices->resize(cells.size());
  palette_offsets->push_back(0);
  for (uint32_t t = 0; t < tile_count; ++t) {
    const size_t first = palette->size();
    for (size_t c = 0; c < per_tile; ++c) {
      const uint32_t mask = cells[t * per_tile + c];
      size_t k = first;
      while (k < palette->size() && (*palette)[k] != mask) ++k;  // <= 256 masks a tile
      if (k == palette->size()) palette->push_back(mask);
      (*indices)[t * per_tile + c] = static_cast<uint8_t>(k - first);
    }
    palette_offsets->push_back(static_cast<uint32_t>(palette->size()));
  }
  return Status::Ok;
}

Status add_semantic_neighbours(const std::vector<uint32_t>& keys, uint32_t tile_cells,
                               std::vector<uint32_t>* palette_offsets, std::vector<uint32_t>* palette,
                               std::vector<uint8_t>* indices, std::vector<uint32_t>* neighbours) {
  neighbours->clear();
  if (tile_cells == 0 || tile_cells > kMaxSemanticTileCells) return Status::InvalidArgument;
  const size_t n = keys.size(), per_tile = size_t(tile_cells) * tile_cells;
  if (n == 0) return palette->empty() && indices->empty() ? Status::Ok : Status::InvalidArgument;
  if (palette_offsets->size() != n + 1 || indices->size() != n * per_tile || palette_offsets->back() != palette->size())
    return Status::InvalidArgument;
  const int64_t T = tile_cells;
  // The mask of cell c of tile t, and of global cell (gx, gy) = (tile x * T + cell x, tile y * T + cell
  // y), 0 outside the tiles.
  auto mask_of = [&](size_t t, size_t c) { return (*palette)[(*palette_offsets)[t] + (*indices)[t * per_tile + c]]; };
  auto mask_at = [&](int64_t gx, int64_t gy) -> uint32_t {
    const int64_t tx = floor_div(gx, T), ty = floor_div(gy, T);
    uint32_t key;
    if (!semantic_tile_key(tx, ty, &key)) return 0;
    const auto it = std::lower_bound(keys.begin(), keys.end(), key);
    if (it == keys.end() || *it != key) return 0;
    return mask_of(size_t(it - keys.begin()), size_t(gy - ty * T) * size_t(T) + size_t(gx - tx * T));
  };
  std::vector<uint32_t> offsets, masks, near;
  std::vector<uint8_t> cells(indices->size());
  offsets.reserve(n + 1);
  offsets.push_back(0);
  for (size_t t = 0; t < n; ++t) {
    const int64_t tx = int64_t(keys[t] >> 16) - 32768, ty = int64_t(keys[t] & 0xFFFFu) - 32768;
    const size_t first = masks.size();
    for (int64_t cy = 0; cy < T; ++cy)
      for (int64_t cx = 0; cx < T; ++cx) {
        const int64_t gx = tx * T + cx, gy = ty * T + cy;
        const uint32_t m = mask_of(t, size_t(cy) * size_t(T) + size_t(cx));
        const uint32_t nb = mask_at(gx - 1, gy) | mask_at(gx + 1, gy) | mask_at(gx, gy - 1) | mask_at(gx, gy + 1);
        size_t k = first;
        while (k < masks.size() && !(masks[k] == m && near[k] == nb)) ++k;  // <= 256 pairs a tile
        if (k == masks.size()) {
          masks.push_back(m);
          near.push_back(nb);
        }
        cells[t * per_tile + size_t(cy) * size_t(T) + size_t(cx)] = static_cast<uint8_t>(k - first);
      }
    offsets.push_back(static_cast<uint32_t>(masks.size()));
  }
  *palette_offsets = std::move(offsets);
  *palette = std::move(masks);
  *neighbours = std::move(near);
  *indices = std::move(cells);
  return Status::Ok;
}

}  // namespace gsf::mapping
