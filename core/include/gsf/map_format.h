// The on-board map: one versioned, little-endian binary blob, validated once and then used in place.
//
//   [MapHeader][SectionEntry x section_count][pad to 16][section 0][pad]...[section n-1]
//
// The header and section table are covered by header_crc; every section by its own CRC-32. load_map()
// checks every size, offset, count, CRC, index and float before returning a MapView whose pointers
// point into the caller's buffer (zero copy; the buffer must outlive the view and be 16-byte aligned).
// The full specification is docs/map-format.md. Writing uses the same MapView type as input, so a map
// round-trips through write_map()/load_map() without any other representation.
#pragma once
#include <cstddef>
#include <cstdint>

#include "gsf/georeference.h"
#include "gsf/status.h"

namespace gsf {

constexpr char kMapMagic[8] = {'G', 'S', 'F', 'M', 'A', 'P', '\r', '\n'};
// 2: semantic layer for hypothesis verification; 3: georeference (origin + frame) and the class table id;
// 4: compact - only what the localizer reads, grids quantised, the refinement layer stored in its grid
// with normals; 5: triangles stored in index-key order, the key carries the labels, no IndexEntries
// section; 6: each semantic palette entry carries its cells' 4-neighbour mask (SemanticNeighbours), so
// verification's neighbour test is one load. Older maps -> VersionMismatch (rebuild with gsf build-map).
constexpr uint32_t kMapVersion = 6;

// Parameters the map was built with that a localizer must agree with (checked by the Localizer).
struct MapParams {
  uint32_t num_classes;          // D
  uint32_t instance_class_mask;  // ClassMask of instantiable classes
  uint32_t field_input_dims;     // 2 (bird's-eye) or 3
  uint32_t inducing_stride;      // M, inducing points of each field (the query's fields must use the same)
  uint32_t grid_nx, grid_ny, grid_layers;
  uint32_t triangle_neighbours;  // K of the map's triangles (TriangleConfig::map_k())
  float grid_spacing, layer_spacing, grid_z0;
  float length_scale, signal_variance, noise_variance;
  float field_radius;
  float voxel_size;
  float side_bin, min_side, max_side;
  float semantic_cell;           // m; cell of the semantic layer (0 when the map has none)
  uint32_t semantic_tile_cells;  // cells per tile side (0 when the map has none)
  uint32_t class_table_id;       // ClassTable::id() of the label set the map was built with (class_table.h)
  float refine_cell;             // m; cell of the refinement layer's grid (0 when the map has none)
};
static_assert(sizeof(MapParams) == 92, "on-disk layout (docs/map-format.md)");

struct MapCounts {
  uint32_t instances;
  uint32_t triangles;
  uint32_t index_keys;
  uint32_t refine_points;  // 0 when the map has no refinement layer
  float road_length_m;     // length of the mapping drive, for bytes-per-km reporting
  float bounds_min[3];
  float bounds_max[3];
  uint32_t semantic_tiles;    // tiles of the semantic layer (0: no layer; verification is then off)
  uint32_t refine_tiles;      // tiles of the refinement layer (0 when refine_points is 0)
  uint32_t semantic_palette;  // palette entries over all semantic tiles (0 without the layer)
  uint32_t reserved[2];       // 0
};
static_assert(sizeof(MapCounts) == 64, "on-disk layout (docs/map-format.md)");

struct MapHeader {
  char magic[8];
  uint32_t version;
  uint32_t header_bytes;  // sizeof(MapHeader) + section table
  uint64_t total_bytes;   // whole blob
  uint32_t section_count;
  uint32_t flags;
  MapGeoreference georef;  // double origin of the map-local frame and the name of the map's frame
  MapParams params;
  MapCounts counts;
  uint32_t header_crc;  // CRC-32 of header (this field as 0) + section table
  uint32_t pad[2];      // explicit, so the header has no compiler padding (all of it is CRC-covered)
};

enum class MapSection : uint32_t {
  Instances = 1,           // MapInstance x instances
  GridMean,                // uint8 x instances x G x D  (posterior mean on the canonical, yaw-0 grid; quantised)
  GridVar,                 // uint16 x instances x G     (posterior variance on that grid; quantised)
  Triangles,               // MapTriangle x triangles, sorted by index key (triangle.h)
  IndexKeys,               // uint64 x index_keys (sorted, unique)
  IndexOffsets,            // uint32 x (index_keys + 1): key k's triangles are Triangles[off[k] .. off[k + 1])
  RefineTiles,             // MapRefineTile x refine_tiles (refine_layer.h) - optional
  RefinePoints,            // MapRefinePoint x refine_points - optional
  SemanticTileKeys,        // uint32 x semantic_tiles (sorted, unique; semantic_grid.h)
  SemanticPaletteOffsets,  // uint32 x (semantic_tiles + 1; 0 without the layer): each tile's palette
  SemanticPalette,         // uint32 x semantic_palette (class masks)
  SemanticCells,           // uint8 x semantic_tiles x semantic_tile_cells^2 (indices into the tile's palette)
  SemanticNeighbours,      // uint32 x semantic_palette (per palette entry: its cells' 4-neighbour mask)
};
constexpr uint32_t kMapSectionCount = 13;

struct SectionEntry {
  uint32_t id;
  uint32_t elem_bytes;
  uint64_t offset;
  uint64_t bytes;
  uint32_t crc;
  uint32_t reserved;
};

// Quantisation levels of the stored grids: a mean is a uint8 of GridMean, a variance a uint16 of
// GridVar (map_quantization.h quantises and dequantises them).
constexpr uint32_t kGridMeanLevels = 255;
constexpr uint32_t kGridVarLevels = 65535;

// An instance and the scales of its quantised grids: mean = mean_min + q * mean_step (q: uint8 of
// GridMean), variance = var_min + q * var_step (q: uint16 of GridVar); map_quantization.h.
struct MapInstance {
  float centroid[3];
  float stability;
  uint32_t point_count;
  float mean_min, mean_step;
  float var_min, var_step;
  uint8_t label;  // dense class
  uint8_t pad[3];
};
static_assert(sizeof(MapInstance) == 40, "on-disk layout");

// A triangle of three instances (triangle.h builds them; there it is called Triangle). Sides sorted
// d01 <= d12 <= d20; stored in index-key order.
struct MapTriangle {
  uint32_t v[3];
  float side[3];
  uint8_t label[3];
  uint8_t orientation;  // TriangleOrientation (triangle.h): the bird's-eye sense of v0 -> v1 -> v2
};
static_assert(sizeof(MapTriangle) == 28, "on-disk layout (docs/map-format.md)");

// The refinement layer (refine_layer.h: RefineLayerView reads these): points with normals, quantised in
// their grid cell, grouped by tile.
struct MapRefineTile {
  uint32_t key;          // semantic_tile_key(tx, ty), strictly increasing over the section
  uint32_t first_point;  // the tile's points are first_point .. next tile's first_point - 1
  int32_t z_base;        // z cell index of local z 0
};
static_assert(sizeof(MapRefineTile) == 12, "on-disk layout (docs/map-format.md)");

struct MapRefinePoint {
  uint16_t cell;      // (z - z_base) << 8 | (y - 16 ty) << 4 | (x - 16 tx), non-decreasing in a tile
  uint8_t offset[3];  // position in the cell: (offset + 0.5) / 256 of the cell per axis
  int8_t normal[3];   // round(127 n); all zero: no reliable normal
};
static_assert(sizeof(MapRefinePoint) == 8, "on-disk layout (docs/map-format.md)");

static_assert(sizeof(MapHeader) == 256 && sizeof(SectionEntry) == 32, "on-disk layout (docs/map-format.md)");
static_assert(offsetof(MapHeader, georef) == 32 && offsetof(MapHeader, params) == 88 &&
                  offsetof(MapHeader, counts) == 180 && offsetof(MapHeader, header_crc) == 244,
              "on-disk layout (docs/map-format.md)");

// Zero-copy view over a validated blob (or, for write_map, over the builder's arrays). Coordinates in
// the sections are map-local (relative to georef.origin); georef says where that is.
struct MapView {
  MapGeoreference georef = local_georeference();
  MapParams params{};
  MapCounts counts{};
  const MapInstance* instances = nullptr;
  const uint8_t* grid_mean = nullptr;  // quantised; map_quantization.h dequantises an instance's grid
  const uint16_t* grid_var = nullptr;
  const MapTriangle* triangles = nullptr;
  const uint64_t* index_keys = nullptr;
  const uint32_t* index_offsets = nullptr;  // into triangles (stored in key order)
  const MapRefineTile* refine_tiles = nullptr;
  const MapRefinePoint* refine_points = nullptr;
  const uint32_t* semantic_tile_keys = nullptr;
  const uint32_t* semantic_palette_offsets = nullptr;
  const uint32_t* semantic_palette = nullptr;
  const uint8_t* semantic_cells = nullptr;
  const uint32_t* semantic_neighbours = nullptr;
  size_t total_bytes = 0;

  uint32_t grid_points() const { return params.grid_nx * params.grid_ny * params.grid_layers; }
};

// Bytes write_map() needs for these contents.
size_t map_serialized_size(const MapView& contents);
// Serialise into `out` (16-byte aligned, >= map_serialized_size bytes). Padding is zeroed so the
// same contents give the same bytes.
Status write_map(const MapView& contents, void* out, size_t out_bytes, size_t* written);
// For writers that stream the sections (e.g. the offline builder writing straight to a file): the
// layout write_map uses and the header + section table it writes, from the params, counts and
// georeference alone (the data pointers are not read). Sections follow the table in id order, each at
// its offset, zero padding between them.
struct MapSectionLayout {
  uint32_t id;
  uint32_t elem_bytes;
  uint64_t offset;
  uint64_t bytes;
};
// Bytes of the header and section table (the first section starts at the next multiple of 16).
size_t map_header_bytes();
// sections[kMapSectionCount] and *total (the blob size); InvalidArgument for invalid params or georeference.
Status map_layout(const MapView& contents, MapSectionLayout* sections, size_t* total);
// The first map_header_bytes() bytes write_map writes for these contents, given each section's CRC-32.
Status write_map_header(const MapView& contents, const uint32_t* section_crcs, void* out, size_t out_bytes);
// Validate `data` completely and return a view into it. Never reads outside [data, data + bytes).
Status load_map(const void* data, size_t bytes, MapView* out);

}  // namespace gsf
