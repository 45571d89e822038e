#include "mapping/map_writer.h"

#include "gsf/detail/map_quantization.h"
#include "mapping/refine_layer_builder.h"
#include "mapping/semantic_layer.h"

namespace gsf::mapping {

Status write_compact_map(const MapContents& c, std::vector<uint64_t>* blob, size_t* bytes, uint32_t* refine_tiles) {
  if (refine_tiles) *refine_tiles = 0;
  MapView view;
  view.georef = c.georef;
  view.params = c.params;
  view.counts = c.counts;
  const uint32_t n = c.counts.instances;
  const uint64_t g = view.grid_points(), gd = g * c.params.num_classes;
  // Grids: one affine scale per instance and grid (mean, variance).
  std::vector<MapInstance> instances(c.instances, c.instances + n);
  std::vector<uint8_t> mean(n * gd);
  std::vector<uint16_t> var(n * g);
  for (uint32_t i = 0; i < n; ++i)
    quantize_instance_grid(c.grid_mean + i * gd, c.grid_var + i * g, g, c.params.num_classes, &instances[i],
                           mean.data() + i * gd, var.data() + i * g);
  std::vector<MapRefineTile> tiles;
  std::vector<MapRefinePoint> points;
  if (c.refine_points > 0) {
    const Status s = build_refine_layer(c.refine_xyz, c.refine_points, c.refine_cell, &tiles, &points);
    if (s != Status::Ok) return s;
    view.params.refine_cell = c.refine_cell;
  } else {
    view.params.refine_cell = 0.0f;
  }
  view.counts.refine_points = static_cast<uint32_t>(points.size());
  view.counts.refine_tiles = static_cast<uint32_t>(tiles.size());
  view.instances = instances.data();
  view.grid_mean = mean.data();
  view.grid_var = var.data();
  view.triangles = c.triangles;
  view.index_keys = c.index_keys;
  view.index_offsets = c.index_offsets;
  view.refine_tiles = tiles.empty() ? nullptr : tiles.data();
  view.refine_points = points.empty() ? nullptr : points.data();
  std::vector<uint32_t> palette_offsets, palette;
  std::vector<uint8_t> palette_cells;
  if (c.counts.semantic_tiles > 0) {
    const uint32_t tc = c.params.semantic_tile_cells;
    const std::vector<uint32_t> dense(c.semantic_cells, c.semantic_cells + size_t(c.counts.semantic_tiles) * tc * tc);
    const Status s =
        palette_semantic_layer(dense, c.counts.semantic_tiles, tc, &palette_offsets, &palette, &palette_cells);
    if (s != Status::Ok) return s;
  }
  view.counts.semantic_palette = static_cast<uint32_t>(palette.size());
  view.semantic_tile_keys = c.semantic_tile_keys;
  view.semantic_palette_offsets = palette_offsets.empty() ? nullptr : palette_offsets.data();
  view.semantic_palette = palette.empty() ? nullptr : palette.data();
  view.semantic_cells = palette_cells.empty() ? nullptr : palette_cells.data();
  const size_t size = map_serialized_size(view);
  if (size == 0) return Status::InvalidArgument;
  blob->assign(size / 8 + 2, 0);
  size_t written = 0;
  const Status s = write_map(view, blob->data(), blob->size() * 8, &written);
  if (s != Status::Ok) return s;
  *bytes = written;
  if (refine_tiles) *refine_tiles = view.counts.refine_tiles;
  return Status::Ok;
}

}  // namespace gsf::mapping
