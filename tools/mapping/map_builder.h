// Offline map building (host side; may use the heap). Scans with their poses are voxelised one by one
// with the same VoxelLayer the localizer uses, and their voxels accumulate into map-local voxels (class
// probabilities averaged, weighted by point counts), kept per 64 m tile with at most
// max_resident_tiles tiles in memory and the others spilled to a temporary file (tile_store.h), so
// the builder's memory is set by its config, not by the length of the drive. A drive it can read again
// (build_blocked: build-map's dataset) is built block by block instead, with no spill file: a first pass
// over the scans (checks, detections, which tiles exist), then per block of tiles the scans that reach it
// read again in drive order and only their voxels there accumulated, so every map voxel gets the same
// sums in the same order and the map is the same bytes, whatever the order of the drive (a drive that
// comes back to every street at its end, as the simulated city's rows-then-columns drive does, left
// add_scan's spill file holding the whole map). Poses come in the map's
// frame (e.g. UTM metres); the builder moves them to the map-local frame by subtracting the map origin
// in double before anything becomes float (georeference.h), so maps of GNSS-posed drives keep
// millimetres. build() then runs the localizer's own stages tile by tile with a halo (tiled_stages.h),
// the same result as over the whole map at once: instance clustering (an object seen from many scans is
// one instance), one Gaussian semantic field per instance probed on its canonical grid, a downsampled
// point layer for refinement and the semantic layer; then triangles and the hash index over all
// instances, and writes the map (map_format.h) section by section to a MapSink (map_writer.h), freeing
// each section once written: with a FileMapSink the map never exists as a whole in memory. What still
// grows with the map is its compact parts held until their section is written (the quantised grids,
// the refinement points, the paletted semantic layer, the triangles and index; docs/results.md, growth
// with map size).
#pragma once
#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "gsf/config.h"
#include "gsf/georeference.h"
#include "gsf/scan.h"
#include "gsf/status.h"
#include "mapping/map_writer.h"
#include "mapping/scan_detections.h"
#include "mapping/semantic_layer.h"
#include "mapping/tile_store.h"

namespace gsf::mapping {

struct MapContent;  // tiled_stages.h

struct MapBuildStats {
  uint32_t scans = 0;
  uint64_t points = 0;
  uint32_t map_voxels = 0;
  uint32_t instances = 0;
  uint32_t pole_instances = 0;        // of which geometric poles / trunks (pole_extraction.h)
  uint32_t instances_dropped = 0;     // clustered instances and poles beyond the config's capacities
  uint64_t field_points_dropped = 0;  // semantic points beyond max_field_points, over all instances
  uint64_t scan_points_dropped = 0;   // scan points in voxels beyond scan_max_voxels, over all scans
  uint32_t instances_by_class[kNumClasses] = {};
  uint32_t triangles = 0;
  uint32_t triangle_instances = 0;      // instances the triangles are built over (triangle_min_detections)
  uint64_t scan_detections = 0;         // instances the query stages found in the mapping scans, summed
  uint32_t scan_triangles = 0;          // triangles added from the mapping scans' views (scan_triangles)
  uint32_t scan_triangles_crowded = 0;  // ... not added: their key was crowded (scan_triangle_max_key_share)
  uint32_t index_keys = 0;
  uint32_t refine_points = 0;
  uint32_t refine_tiles = 0;
  uint32_t semantic_tiles = 0;
  uint32_t fields_failed = 0;
  size_t bytes = 0;
  MapGeoreference georef = local_georeference();  // the map's origin and frame
  double seconds_accumulate = 0, seconds_cluster = 0, seconds_fields = 0, seconds_triangles = 0;
  TileStoreStats tiles;           // the voxel accumulators' tiles: count, spills, reloads, peak resident
  uint32_t blocks = 0;            // build_blocked: blocks of tiles built one at a time
  uint64_t block_scan_reads = 0;  // ... and the scans they read again (each scan once per block it reaches)
};

using Progress = std::function<void(const char* stage, uint64_t done, uint64_t total)>;

// A mapping drive the builder can read more than once (MapBuilder::build_blocked), e.g. build-map's dataset.
class ScanSequence {
 public:
  virtual ~ScanSequence() = default;
  virtual uint32_t size() const = 0;
  // Scan i, the same points every time it is read, and its pose in the map's frame (as add_scan's);
  // the view stays valid until the next read.
  virtual Status read(uint32_t i, ScanView* scan, Eigen::Isometry3d* frame_T_lidar) = 0;
};

// Scan poses farther than this from the map origin (m, on any axis) are refused with InvalidInput: float32
// steps there are 1/64 m, still far below the 0.4 m voxels, and the builder's voxel keys (2^20 voxels
// either side) and the semantic layer's tile keys (32768 tiles either side) reach well beyond it.
constexpr double kMaxMapLocalCoordinate = 131072.0;

// Instances a map can hold: TriangleBuilder packs three instance ids into one 63-bit key to find each
// triangle once, 21 bits each. Map records and the builder's bookkeeping use 32-bit ids.
constexpr uint32_t kMaxMapInstances = (1u << 21) - 1;

// Everything the builder is configured by (one struct, no setters, no hidden constants).
struct MapBuildConfig {
  // The localizer's stage settings and label set: the map is built with the same stages as the query, and
  // records the parameters the localizer checks at init. Its per-scan capacities are raised for the
  // whole map; its label set (stages.classes, copied) maps raw labels, decides instance classes,
  // geometric pole / trunk hosts and stabilities; the map records its id.
  LocalizerConfig stages;
  // The semantic layer used to verify pose hypotheses; cell <= 0 leaves it out of the map.
  SemanticLayerConfig semantic_layer;
  // Length of the mapped road (m), recorded in the map's counts for reporting; 0 if unknown.
  float road_length_m = 0.0f;
  // m; the refinement layer keeps one point per refine_voxel cube (<= 0: no layer). The layer's grid is
  // stages.refine.cell (the localizer's), so at the default 1 m each grid cell holds one point.
  float refine_voxel = 1.0f;
  // Capacities of the whole-map stages (no hidden constants; what they cut is counted in MapBuildStats).
  // Clustered instances kept, the largest by points first, and geometric poles / trunks kept, the best
  // by score first, both over the whole map. Together below kMaxMapInstances (build() refuses more
  // with CapacityExceeded); the defaults split it (about 3,500 km of the demo world's road each).
  uint32_t max_instances = kMaxMapInstances / 2 + 1;
  uint32_t max_pole_instances = kMaxMapInstances / 2;
  // Semantic points gathered per map instance to fit its field (the localizer's match.max_field_points
  // is the query side's); beyond it the gather order (column by column) decides and the rest is counted.
  uint32_t max_field_points = 200000;
  // Voxels per mapping scan: each scan is voxelised with the localizer's VoxelLayer before accumulation,
  // with at least this capacity, so the on-board default (stages.voxel.max_voxels, sized for the 16 MiB
  // workspace) never truncates a map scan (100k: 14 MB of host memory; truncation is counted).
  uint32_t scan_max_voxels = 100000;
  // The map origin in the frame of the poses. Not given: the first scan's pose translation rounded (half
  // up) to a whole metre. A whole-metre origin keeps the subtraction exact for poses posed to float
  // precision, so the same drive shifted by whole metres gets the same map-local frame and the same map.
  bool origin_given = false;
  std::array<double, 3> origin = {0.0, 0.0, 0.0};
  std::string frame = "local";  // name of the poses' frame (1..31 printable ASCII), e.g. "utm-32N"
  // Bounded memory (tile_store.h, tiled_stages.h): the voxel accumulators live in square tiles of
  // tile_size m in the map-local x-y plane, at most max_resident_tiles of them in memory (the least
  // recently used others spilled to a temporary file in spill_dir, or std::tmpfile() when empty), and
  // build() runs the whole-map stages tile by tile with a halo. Peak memory is then the resident tiles
  // plus one tile's stages and the map being built, whatever the length of the drive; the map is the
  // same bytes as with tile_size = 0 (one tile, everything in memory). Revisits reload spilled tiles.
  // A scan's 80 m range touches up to 16 tiles of 64 m: 24 resident tiles hold them without thrashing.
  float tile_size = 64.0f;
  uint32_t max_resident_tiles = 24;  // 0: no limit (nothing is spilled)
  std::string spill_dir;
  // build_blocked (a drive it can read again): blocks of block_tiles x block_tiles tiles, one at a time
  // with its halo in memory, each from the scans that reach it read again; no spill file. Memory is one
  // block's voxels, whatever the order of the drive; each scan is read once more per block it reaches
  // (1x world: 5.3 times at 2 x 64 m, 3.5 at 3, 3.0 at 4, against an 80 m scan; docs/memory.md).
  // Must be > 0 for build_blocked; add_scan ignores it.
  uint32_t block_tiles = 2;
  // Triangles only among map instances that the query's own instance stages (clustering, geometric
  // poles) found in at least this many mapping scans, same label within detection_radius m (bird's-eye):
  // a query finds those, not the instances only the accumulated drive reveals (scan_detections.h).
  // 0: every map instance is a triangle vertex (the map's other instances are kept either way).
  // An instance needs min(triangle_min_detections, scans whose position is within detection_range m)
  // detections, so a map of one scan, or an instance no scan came near, keeps its triangles.
  // 2 = seen as an instance from two viewpoints. Measured (docs/results.md, "Which map instances a scan
  // finds"): real nuScenes map 0004 keeps 95 of 247 instances, queries 0002 localize 13 of 15
  // overlapping frames instead of 7 with no wrong answer; the simulated suites keep 95-99% of their
  // instances and move by -0.5 to +0.4 points.
  uint32_t triangle_min_detections = 2;
  float detection_radius = 2.0f;
  float detection_range = 80.0f;  // m, a scan's range (the simulated and nuScenes sensors see about 80 m)
  // 1: the map also holds the triangles a query would form at each mapping scan's pose, among the
  // instances that scan's detections are (scan_triangles.h), with the query's K and side limits. 0: only
  // the triangles among each apex's nearest map instances (TriangleConfig::map_k).
  uint32_t scan_triangles = 1;
  // ... except those whose index key this many map triangles already have (0: no limit): in a lattice
  // a scan's triangle among identical columns is one more twin of many, which only crowds the true match
  // out of the query's per-triangle cap (held-out lattice zone 95.9% without scan triangles, 90.5% with
  // all of them, 94.9% at 8, 95.9% at 2; docs/results.md).
  uint32_t scan_triangle_max_key_share = 2;
};

class MapBuilder {
 public:
  explicit MapBuilder(const MapBuildConfig& config);
  // `frame_T_lidar`: the scan's pose in the map's frame (config.frame). InvalidArgument for a bad origin
  // or frame name in the config, InvalidInput for a non-finite pose or one beyond
  // kMaxMapLocalCoordinate from the origin (the scan is then not added), IoError when the tile spill
  // file cannot be created or written (the builder is then unusable).
  Status add_scan(const ScanView& scan, const Eigen::Isometry3d& frame_T_lidar);
  // The map's georeference: final once the first scan was added (or at once when the origin was given).
  const MapGeoreference& georeference() const { return georef_; }
  // The voxel accumulators' tiles so far (spills and reloads happen during add_scan too).
  const TileStoreStats& tile_stats() const { return store_.stats(); }
  // Writes the map to `sink` (e.g. a FileMapSink: straight to a file); *bytes is the map's size. The
  // sink's errors (IoError) are returned.
  Status build(MapSink& sink, size_t* bytes, MapBuildStats* stats, const Progress& progress = nullptr);
  // The same map in memory: `blob` (16-byte aligned words) through a MemoryMapSink.
  Status build(std::vector<uint64_t>* blob, size_t* bytes, MapBuildStats* stats, const Progress& progress = nullptr);
  // The same map from a drive it reads more than once, instead of add_scan and build (a builder that
  // added scans refuses it with InvalidArgument, as does tile_size <= 0 or block_tiles == 0): a first
  // pass over the scans (add_scan's checks and errors, *failed_scan their index), then the map block by
  // block (MapBuildConfig::block_tiles), never a spill file. The same bytes as add_scan and build.
  Status build_blocked(ScanSequence& drive, MapSink& sink, size_t* bytes, MapBuildStats* stats,
                       const Progress& progress = nullptr, uint32_t* failed_scan = nullptr);

 private:
  struct TriangleVertices;                 // map_builder.cpp
  using ScanBox = std::array<int32_t, 4>;  // a scan's voxels' x0, x1, y0, y1 (voxel coordinates, inclusive)
  // add_scan's steps (map_builder.cpp).
  Status voxelize(const ScanView& scan, const Eigen::Isometry3d& frame_T_lidar, VoxelLayer* layer,
                  Eigen::Isometry3d* map_T_lidar, uint64_t* dropped);
  Status detect(const VoxelLayer& layer, const Eigen::Isometry3d& map_T_lidar);
  void to_map(const VoxelLayer& layer, const Eigen::Isometry3d& map_T_lidar);
  Status accumulate(const VoxelLayer& layer, TileStore* store, const int32_t* rect);
  // build_blocked's passes.
  Status survey(ScanSequence& drive, std::vector<ScanBox>* boxes, std::vector<uint64_t>* tiles,
                const Progress& progress, uint32_t* failed_scan);
  Status blocked_content(ScanSequence& drive, const std::vector<ScanBox>& boxes, const std::vector<uint64_t>& tiles,
                         MapContent* content, MapBuildStats* st, const Progress& progress);
  // build()'s steps (map_builder.cpp).
  Status build_content(MapContent* content, MapBuildStats* st, const Progress& progress);
  Status write_map(MapSink& sink, MapContent* content, MapBuildStats* st, size_t* bytes, MapBuildStats* stats_out,
                   const Progress& progress) const;
  MapView map_header(const MapContent& content, const MapBuildStats& st) const;
  void choose_triangle_vertices(const MapContent& content, TriangleVertices* v) const;
  Status write_triangles(MapSink& sink, const MapContent& content, MapView* header, MapBuildStats* st,
                         const Progress& progress) const;
  Status write_refine_layer(MapSink& sink, MapContent* content, MapView* header, MapBuildStats* st) const;

  LocalizerConfig config_;  // options_.stages, with classes pointing at classes_
  ClassTable classes_;      // copy of the label set
  MapBuildConfig options_;
  MapGeoreference georef_;
  bool georef_valid_ = false;
  bool origin_fixed_ = false;
  MapBuildStats stats_;
  TileStore store_;  // the map's voxel accumulators
  std::vector<uint8_t> scan_arena_;
  std::vector<double> scan_points_;                        // per scan voxel: its centroid in the map frame
  std::vector<std::pair<uint64_t, uint32_t>> scan_order_;  // per scan voxel: map voxel key, index
  ScanDetector detector_;                                  // with triangle_min_detections > 0
  bool detector_ok_ = false;
  std::vector<ScanDetection> detections_;       // every mapping scan's instances, map-local frame
  std::vector<ScanDetection> scan_positions_;   // every mapping scan's position (label kAnyLabel)
  std::vector<uint32_t> scan_detection_begin_;  // per scan: its first detection in detections_
};

}  // namespace gsf::mapping
