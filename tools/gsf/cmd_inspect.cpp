// gsf inspect --map MAP [--json]: header, counts, section sizes and bytes per km of a map file.
#include <cstdio>
#include <cstring>

#include "args.h"
#include "commands.h"
#include "gsf/localizer.h"
#include "gsf/map_format.h"
#include "gsf/semantic_classes.h"
#include "json_writer.h"
#include "pipeline.h"

namespace gsf::cli {

namespace {

// Per-class instance counts and the map's bytes per km of road (0 when the length is unknown).
struct MapSummary {
  uint32_t per_class[kNumClasses] = {};
  double bytes_per_km = 0.0;
};

MapSummary summarize(const MapView& map) {
  MapSummary sum;
  const uint32_t per_class_max = kNumClasses;
  for (uint32_t i = 0; i < map.counts.instances; ++i)
    if (map.instances[i].label < per_class_max) sum.per_class[map.instances[i].label]++;
  const double km = map.counts.road_length_m / 1000.0;
  sum.bytes_per_km = km > 0 ? double(map.total_bytes) / km : 0.0;
  return sum;
}

// The semantic layer's bytes: tile keys and palette offsets (4 B each), the palettes' masks and
// neighbour masks (4 B each), a byte a cell.
uint64_t semantic_layer_bytes(const MapView& map) {
  const uint64_t sem_cells =
      uint64_t(map.counts.semantic_tiles) * map.params.semantic_tile_cells * map.params.semantic_tile_cells;
  return uint64_t(map.counts.semantic_tiles) * 8 + (map.counts.semantic_tiles ? 4 : 0) +
         uint64_t(map.counts.semantic_palette) * 8 + sem_cells;
}

// --json: the header and counts as one JSON object.
void print_json(const std::string& path, const MapFile& file, const MapView& map, const MapSummary& sum) {
  JsonWriter j;
  j.begin_object();
  j.field("file", path);
  j.field("version", kMapVersion);
  j.field("bytes", static_cast<unsigned long long>(map.total_bytes));
  j.field("memory_mapped", file.file.mapped());
  j.field("frame", map.georef.frame);
  j.key("origin");
  j.begin_array();
  for (double o : map.georef.origin) j.exact(o);
  j.end_array();
  j.field("class_table_id", static_cast<unsigned long long>(map.params.class_table_id));
  j.field("road_length_m", map.counts.road_length_m);
  j.field("bytes_per_km", sum.bytes_per_km);
  j.field("instances", map.counts.instances);
  j.field("semantic_tiles", map.counts.semantic_tiles);
  j.field("triangles", map.counts.triangles);
  j.field("index_keys", map.counts.index_keys);
  j.field("refine_points", map.counts.refine_points);
  j.field("refine_tiles", map.counts.refine_tiles);
  j.field("semantic_palette", map.counts.semantic_palette);
  j.field("format_version", kMapVersion);
  j.field("grid_points", map.grid_points());
  j.field("inducing_stride", map.params.inducing_stride);
  j.key("instances_by_class");
  j.begin_object();
  for (int c = 0; c < kNumClasses; ++c)
    if (sum.per_class[c]) j.field(class_name(c), sum.per_class[c]);
  j.end_object();
  j.end_object();
  std::printf("%s\n", j.str().c_str());
}

// The header and counts as text.
void print_text(const std::string& path, const MapFile& file, const MapView& map, const MapSummary& sum) {
  std::printf("map %s: valid, format version %u, %zu bytes, %s\n", path.c_str(), kMapVersion, map.total_bytes,
              file.file.mapped() ? "memory-mapped (used in place)" : "read into memory");
  std::printf("  frame           '%s', origin %.3f, %.3f, %.3f m (map coordinates are relative to it)\n",
              map.georef.frame, map.georef.origin[0], map.georef.origin[1], map.georef.origin[2]);
  std::printf("  class table     id %08x\n", map.params.class_table_id);
  std::printf("  road length     %.1f m  (%.2f MB per km)\n", map.counts.road_length_m, sum.bytes_per_km / 1e6);
  std::printf("  instances       %u, map-local bounds x %.1f..%.1f, y %.1f..%.1f m\n", map.counts.instances,
              map.counts.bounds_min[0], map.counts.bounds_max[0], map.counts.bounds_min[1], map.counts.bounds_max[1]);
  for (int c = 0; c < kNumClasses; ++c)
    if (sum.per_class[c]) std::printf("    %-14s %u\n", class_name(c), sum.per_class[c]);
  std::printf("  triangles       %u in %u hash keys\n", map.counts.triangles, map.counts.index_keys);
  std::printf("  refine points   %u in %u tiles, cell %.2f m\n", map.counts.refine_points, map.counts.refine_tiles,
              map.params.refine_cell);
  const uint64_t sem_bytes = semantic_layer_bytes(map);
  std::printf("  semantic layer  %u tiles of %ux%u cells @ %.2f m, %u palette entries (%.2f MB)\n",
              map.counts.semantic_tiles, map.params.semantic_tile_cells, map.params.semantic_tile_cells,
              map.params.semantic_cell, map.counts.semantic_palette, sem_bytes / 1e6);
}

// Bytes per section (format v5: docs/map-format.md), so the size can be traced to what it stores; the
// field and triangle parameters.
void print_sections(const MapView& map) {
  const uint64_t n = map.counts.instances, g = map.grid_points(), d = map.params.num_classes;
  const struct {
    const char* name;
    uint64_t bytes;
  } sections[] = {
      {"instances", n * sizeof(MapInstance)},
      {"grid means (u8)", n * g * d},
      {"grid variances (u16)", n * g * 2},
      {"triangles", uint64_t(map.counts.triangles) * sizeof(MapTriangle)},
      {"triangle index", uint64_t(map.counts.index_keys) * 12 + 4},
      {"refinement layer", uint64_t(map.counts.refine_tiles) * sizeof(MapRefineTile) +
                               uint64_t(map.counts.refine_points) * sizeof(MapRefinePoint)},
      {"semantic layer", semantic_layer_bytes(map)},
  };
  std::printf("  sections (MB)  ");
  for (const auto& sec : sections) std::printf(" %s %.2f;", sec.name, sec.bytes / 1e6);
  std::printf("\n");
  std::printf(
      "  field           %uD inputs, M <= %u inducing, grid %ux%ux%u @ %.2f m, kappa %.2f, noise %.3f, r %.1f m\n",
      map.params.field_input_dims, map.params.inducing_stride, map.params.grid_nx, map.params.grid_ny,
      map.params.grid_layers, map.params.grid_spacing, map.params.length_scale, map.params.noise_variance,
      map.params.field_radius);
  std::printf("  triangles       K=%u, sides [%.1f, %.1f] m, bin %.2f m\n", map.params.triangle_neighbours,
              map.params.min_side, map.params.max_side, map.params.side_bin);
}

// Workspace budget of a localizer with the default config (refinement on and off), and whether it
// matches the map.
void print_workspace_budget(const MapView& map) {
  LocalizerConfig cfg = default_config();
  cfg.refine.enabled = true;
  const Localizer::Budget b = Localizer::budget(cfg);
  const Status fits = check_map_params(cfg, map.params);
  std::printf("localizer workspace with the default config (%s for this map):\n",
              fits == Status::Ok ? "matches" : "DOES NOT match");
  const struct {
    const char* name;
    size_t bytes;
  } rows[] = {{"voxel layer", b.voxel},         {"instances", b.cluster},
              {"geometric poles", b.poles},     {"query fields", b.field},
              {"triangles", b.triangle},        {"ranked matches", b.match},
              {"GSF probe cache", b.gsf_cache}, {"correspondences", b.correspondence},
              {"hypotheses", b.clique},         {"refinement", b.refine},
              {"scan window", b.window},        {"other", b.other}};
  for (const auto& r : rows) std::printf("    %-18s %10.2f MB\n", r.name, r.bytes / 1e6);
  std::printf("    %-18s %10.2f MB  (%.2f MB without refinement)\n", "total", b.total / 1e6,
              (b.total - b.refine) / 1e6);
  if (map.counts.refine_points > 0 && map.params.refine_cell != cfg.refine.cell)
    std::printf("    note: the map's refinement cell %.2f m differs from refine.cell %.2f m (init: ConfigMismatch)\n",
                map.params.refine_cell, cfg.refine.cell);
}

}  // namespace

int cmd_inspect(int argc, char** argv) {
  const std::vector<OptionSpec> specs = {
      {"map", "map file to inspect", "", false, true},
      {"json", "print JSON instead of text", "", true, false},
      {"help", "show this help", "", true, false},
  };
  for (int i = 2; i < argc; ++i)
    if (!std::strcmp(argv[i], "--help")) {
      std::printf("%s", usage_text("inspect", "Validate a map file and print what it holds.", specs).c_str());
      return 0;
    }
  Args args;
  std::string err;
  if (!args.parse(argc, argv, 2, specs, &err)) return usage_error("inspect", err);
  MapFile file;
  if (read_map_file(args.get("map"), &file, &err) != Status::Ok) {
    std::fprintf(stderr, "gsf inspect: %s\n", err.c_str());
    return 1;
  }
  MapView map;
  const Status s = load_map(file.data(), file.bytes, &map);
  if (s != Status::Ok) {
    std::fprintf(stderr, "gsf inspect: '%s' is not a valid map: %s\n", args.get("map").c_str(),
                 map_load_error(file, s).c_str());
    return 1;
  }
  const MapSummary sum = summarize(map);
  if (args.flag("json")) {
    print_json(args.get("map"), file, map, sum);
    return 0;
  }
  print_text(args.get("map"), file, map, sum);
  print_sections(map);
  print_workspace_budget(map);
  return 0;
}

}  // namespace gsf::cli
