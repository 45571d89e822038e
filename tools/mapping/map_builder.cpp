#include "mapping/map_builder.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <initializer_list>
#include <map>
#include <memory>
#include <unordered_set>

#include "gsf/class_table.h"
#include "gsf/detail/arena.h"
#include "gsf/detail/fixed_vector.h"
#include "gsf/detail/gaussian_field.h"
#include "gsf/detail/instance_clustering.h"
#include "gsf/detail/pole_extraction.h"
#include "gsf/detail/triangle.h"
#include "gsf/detail/triangle_index.h"
#include "gsf/detail/voxel_layer.h"
#include "gsf/map_format.h"
#include "mapping/floor_div.h"
#include "mapping/map_writer.h"
#include "mapping/refine_layer_builder.h"
#include "mapping/scan_triangles.h"
#include "mapping/tiled_stages.h"
#include "mapping/workspace.h"

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace gsf::mapping {
namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

TileStoreConfig tile_store_config(const MapBuildConfig& config) {
  TileStoreConfig t;
  if (config.tile_size > 0.0f && config.stages.voxel.voxel_size > 0.0f)
    t.tile_voxels = std::max(1, static_cast<int>(std::lround(config.tile_size / config.stages.voxel.voxel_size)));
  t.max_resident_tiles = config.max_resident_tiles;
  t.spill_dir = config.spill_dir;
  return t;
}

// One map section: `elems` records of `elem_bytes` each.
struct SectionData {
  MapSection id;
  const void* data;
  size_t elems, elem_bytes;
};

// Writes the sections in order; stops at the sink's first error and returns it.
Status write_sections(MapSink& sink, std::initializer_list<SectionData> sections) {
  for (const SectionData& d : sections) {
    const Status s = sink.section(d.id, d.data, d.elems * d.elem_bytes);
    if (s != Status::Ok) return s;
  }
  return Status::Ok;
}

// The map's triangle settings: the map's K (TriangleConfig::map_neighbours) and room for every
// triangle among ni instances.
TriangleConfig map_triangle_config(const TriangleConfig& query, uint32_t ni) {
  TriangleConfig tc = query;
  tc.neighbours = tc.map_k();
  tc.map_neighbours = 0;
  const uint64_t tri_cap = std::min<uint64_t>(uint64_t(ni) * tc.neighbours * (tc.neighbours - 1) / 2 + 16, 1u << 30);
  tc.max_triangles = static_cast<uint32_t>(tri_cap);
  return tc;
}

// The triangles in index-key order (format v5: a key's bucket is a contiguous run) and the hash index,
// written to the sink; frees *all.
Status write_triangle_index(MapSink& sink, std::vector<Triangle>* all, float side_bin, MapView* header,
                            MapBuildStats* st) {
  const uint32_t nt = static_cast<uint32_t>(all->size());
  std::vector<Triangle> sorted(nt + 1);
  std::vector<uint64_t> ikeys(nt + 1), scratch(nt + 1);
  std::vector<uint32_t> offsets(nt + 2), ids(nt + 1);
  uint32_t key_count = 0;
  const Status s = build_triangle_index(all->data(), nt, side_bin, sorted.data(), ikeys.data(), offsets.data(),
                                        &key_count, scratch.data(), ids.data());
  if (s != Status::Ok) return s;
  std::vector<Triangle>().swap(*all);  // copied to `sorted`, not read after this
  std::vector<uint32_t>().swap(ids);
  std::vector<uint64_t>().swap(scratch);
  st->triangles = nt;
  st->index_keys = key_count;
  header->counts.triangles = nt;
  header->counts.index_keys = key_count;
  return write_sections(sink, {{MapSection::Triangles, sorted.data(), nt, sizeof(MapTriangle)},
                               {MapSection::IndexKeys, ikeys.data(), key_count, sizeof(uint64_t)},
                               {MapSection::IndexOffsets, offsets.data(), size_t(key_count) + 1, sizeof(uint32_t)}});
}

// Instances and their grids (quantised by the tile stages), freed once written.
Status write_instances(MapSink& sink, MapContent* content) {
  const Status s = write_sections(
      sink, {{MapSection::Instances, content->instances.data(), content->instances.size(), sizeof(MapInstance)},
             {MapSection::GridMean, content->mean.data(), content->mean.size(), sizeof(uint8_t)},
             {MapSection::GridVar, content->var.data(), content->var.size(), sizeof(uint16_t)}});
  if (s != Status::Ok) return s;
  std::vector<MapInstance>().swap(content->instances);
  std::vector<uint8_t>().swap(content->mean);
  std::vector<uint16_t>().swap(content->var);
  return Status::Ok;
}

// The semantic layer (paletted by the tile stages).
Status write_semantic_layer(MapSink& sink, const MapContent& c) {
  return write_sections(
      sink,
      {{MapSection::SemanticTileKeys, c.semantic_keys.data(), c.semantic_keys.size(), sizeof(uint32_t)},
       {MapSection::SemanticPaletteOffsets, c.semantic_palette_offsets.data(), c.semantic_palette_offsets.size(),
        sizeof(uint32_t)},
       {MapSection::SemanticPalette, c.semantic_palette.data(), c.semantic_palette.size(), sizeof(uint32_t)},
       {MapSection::SemanticCells, c.semantic_cells.data(), c.semantic_cells.size(), sizeof(uint8_t)},
       {MapSection::SemanticNeighbours, c.semantic_neighbours.data(), c.semantic_neighbours.size(), sizeof(uint32_t)}});
}

}  // namespace

MapBuilder::MapBuilder(const MapBuildConfig& config)
    : config_(config.stages),
      classes_(label_set(config.stages)),
      options_(config),
      georef_(local_georeference()),
      store_(tile_store_config(config)) {
  if (config_.classes) config_.classes = &classes_;
  // Map scans are voxelised on the host: at least scan_max_voxels per scan (MapBuildConfig).
  config_.voxel.max_voxels = std::max(config_.voxel.max_voxels, config.scan_max_voxels);
  // The map's voxels average every point's softmax (offline; the query thins them, VoxelConfig).
  config_.voxel.prob_samples = 0;
  scan_arena_.resize(VoxelLayer::required_bytes(config_.voxel) + 64);
  georef_valid_ = set_frame_name(&georef_, options_.frame.c_str());
  for (int k = 0; k < 3; ++k) georef_.origin[k] = options_.origin[k];
  georef_valid_ = georef_valid_ && valid_georeference(georef_);
  origin_fixed_ = options_.origin_given;
  if (options_.triangle_min_detections > 0 || options_.scan_triangles)
    detector_ok_ = detector_.init(config_, config_.voxel.max_voxels) == Status::Ok;
}

// Validity, origin and the scan's voxels (into scan_arena_), with its pose in the map-local frame.
Status MapBuilder::voxelize(const ScanView& scan, const Eigen::Isometry3d& frame_T_lidar, VoxelLayer* layer,
                            Eigen::Isometry3d* map_T_lidar, uint64_t* dropped) {
  if (!georef_valid_) return Status::InvalidArgument;
  if (!frame_T_lidar.matrix().allFinite()) return Status::InvalidInput;
  if (!origin_fixed_) {
    // Half up, not std::round's half away from zero: floor(x + 0.5) moves by exactly n when x moves by a
    // whole n, so a drive shifted by whole metres gets an origin shifted by the same (sim poses start at
    // y = -2.5, where std::round would give -3 unshifted but 5412343 = 5412345 - 2 shifted).
    for (int k = 0; k < 3; ++k) georef_.origin[k] = std::floor(frame_T_lidar.translation()[k] + 0.5);
    origin_fixed_ = true;
  }
  // Into the map-local frame in double, before anything becomes float.
  *map_T_lidar = to_map_local(georef_, frame_T_lidar);
  if (map_T_lidar->translation().cwiseAbs().maxCoeff() > kMaxMapLocalCoordinate) return Status::InvalidInput;
  Arena arena = aligned_arena(scan_arena_.data(), scan_arena_.size());
  Status s = layer->bind(arena, config_.voxel);
  if (s != Status::Ok) return s;
  layer->set_classes(config_.classes);
  VoxelStats vst;
  s = layer->build(scan, &vst);
  if (s != Status::Ok && s != Status::CapacityExceeded) return s;
  if (dropped) *dropped += vst.dropped_points;
  return Status::Ok;
}

// The query stages' instances of the scan (scan_detections.h) and its position, when they are used.
Status MapBuilder::detect(const VoxelLayer& layer, const Eigen::Isometry3d& map_T_lidar) {
  if (options_.triangle_min_detections == 0 && !options_.scan_triangles) return Status::Ok;
  if (!detector_ok_) return Status::InvalidArgument;
  const size_t before = detections_.size();
  scan_detection_begin_.push_back(static_cast<uint32_t>(before));
  const Status s = detector_.detect(layer, map_T_lidar, &detections_);
  if (s != Status::Ok) return s;
  stats_.scan_detections += detections_.size() - before;
  ScanDetection at{};
  for (int k = 0; k < 3; ++k) at.xyz[k] = static_cast<float>(map_T_lidar.translation()[k]);
  at.label = kAnyLabel;
  scan_positions_.push_back(at);
  return Status::Ok;
}

// Per scan voxel its centroid in the map frame (scan_points_) and map voxel key (scan_order_, in voxel order).
void MapBuilder::to_map(const VoxelLayer& layer, const Eigen::Isometry3d& map_T_lidar) {
  const double vs = config_.voxel.voxel_size;
  const uint32_t n = layer.size();
  scan_points_.resize(size_t(n) * 3);
  scan_order_.resize(n);
  for (uint32_t i = 0; i < n; ++i) {
    const Voxel& v = layer.voxel(i);
    const Eigen::Vector3d p = map_T_lidar * Eigen::Vector3d(v.centroid[0], v.centroid[1], v.centroid[2]);
    for (int k = 0; k < 3; ++k) scan_points_[3 * size_t(i) + k] = p[k];
    scan_order_[i] = {voxel_key(p.x(), p.y(), p.z(), vs), i};
  }
}

// The scan's voxels (scan_order_'s order) into `store`'s accumulators; with `rect` (voxel x0, x1, y0, y1)
// only those inside it.
Status MapBuilder::accumulate(const VoxelLayer& layer, TileStore* store, const int32_t* rect) {
  Status s = Status::Ok;
  for (const auto& [key, i] : scan_order_) {
    if (rect) {
      const int32_t x = voxel_key_x(key), y = voxel_key_y(key);
      if (x < rect[0] || x >= rect[1] || y < rect[2] || y >= rect[3]) continue;
    }
    const Voxel& v = layer.voxel(i);
    const double* p = &scan_points_[3 * size_t(i)];
    VoxelAccum* a = store->accumulator(key, &s);
    if (!a) return s;  // the spill file failed: this scan is partly added, the builder is unusable
    for (int k = 0; k < 3; ++k) a->sum[k] += p[k] * v.count;
    for (int c = 0; c < kNumClasses; ++c) a->prob[c] += double(v.prob[c]) * v.count;
    a->count += v.count;
  }
  return Status::Ok;
}

Status MapBuilder::add_scan(const ScanView& scan, const Eigen::Isometry3d& frame_T_lidar) {
  const auto t0 = std::chrono::steady_clock::now();
  VoxelLayer layer;
  Eigen::Isometry3d map_T_lidar;
  Status s = voxelize(scan, frame_T_lidar, &layer, &map_T_lidar, &stats_.scan_points_dropped);
  if (s != Status::Ok) return s;
  s = detect(layer, map_T_lidar);
  if (s != Status::Ok) return s;
  to_map(layer, map_T_lidar);
  // Tile by tile, so a scan touches each tile once however small the resident budget. Stable: a map
  // voxel still receives this scan's voxels in scan order, so its sums are those of a single-tile build.
  if (store_.tile_voxels() > 0)
    std::stable_sort(scan_order_.begin(), scan_order_.end(),
                     [&](const std::pair<uint64_t, uint32_t>& a, const std::pair<uint64_t, uint32_t>& b) {
                       return store_.tile_of(a.first) < store_.tile_of(b.first);
                     });
  s = accumulate(layer, &store_, nullptr);
  if (s != Status::Ok) return s;
  store_.note_resident_voxels();
  stats_.scans++;
  stats_.points += scan.count;
  stats_.seconds_accumulate += seconds_since(t0);
  return Status::Ok;
}

Status MapBuilder::build(std::vector<uint64_t>* blob, size_t* bytes, MapBuildStats* stats, const Progress& progress) {
  MemoryMapSink sink(blob);
  return build(sink, bytes, stats, progress);
}

// The tile stages' content (tiled_stages.h), then each section written as soon as it is final and
// freed: the map is never whole in memory.
Status MapBuilder::build(MapSink& sink, size_t* bytes_out, MapBuildStats* stats_out, const Progress& progress) {
  *bytes_out = 0;
  MapBuildStats st = stats_;
  st.georef = georef_;
  MapContent content;
  const Status s = build_content(&content, &st, progress);
  if (s != Status::Ok) return s;
  return write_map(sink, &content, &st, bytes_out, stats_out, progress);
}

// The sections from the content, each freed once written, then the header.
Status MapBuilder::write_map(MapSink& sink, MapContent* content, MapBuildStats* st, size_t* bytes_out,
                             MapBuildStats* stats_out, const Progress& progress) const {
  if (content->instances.size() > kMaxMapInstances) return Status::CapacityExceeded;
  MapView header = map_header(*content, *st);
  Status s = write_instances(sink, content);
  if (s != Status::Ok) return s;
  s = write_triangles(sink, *content, &header, st, progress);
  if (s != Status::Ok) return s;
  std::vector<float>().swap(content->centroids);
  std::vector<uint8_t>().swap(content->labels);
  s = write_refine_layer(sink, content, &header, st);
  if (s != Status::Ok) return s;
  s = write_semantic_layer(sink, *content);
  if (s != Status::Ok) return s;
  *content = MapContent();

  size_t written = 0;
  s = sink.finish(header, &written);
  if (s != Status::Ok) return s;
  *bytes_out = written;
  st->bytes = written;
  if (stats_out) *stats_out = *st;
  return Status::Ok;
}

Status MapBuilder::build_blocked(ScanSequence& drive, MapSink& sink, size_t* bytes_out, MapBuildStats* stats_out,
                                 const Progress& progress, uint32_t* failed_scan) {
  *bytes_out = 0;
  if (failed_scan) *failed_scan = UINT32_MAX;
  if (stats_.scans > 0 || store_.tile_voxels() == 0 || options_.block_tiles == 0) return Status::InvalidArgument;
  std::vector<ScanBox> boxes;
  std::vector<uint64_t> tiles;
  Status s = survey(drive, &boxes, &tiles, progress, failed_scan);
  if (s != Status::Ok) return s;
  MapBuildStats st = stats_;
  st.georef = georef_;
  MapContent content;
  s = blocked_content(drive, boxes, tiles, &content, &st, progress);
  if (s != Status::Ok) return s;
  return write_map(sink, &content, &st, bytes_out, stats_out, progress);
}

// The blocked build's first pass, scan by scan in drive order: the add_scan checks, detections and
// counts, the map tiles the scans' voxels fall in (sorted) and each scan's box of voxels (x0, x1, y0, y1).
Status MapBuilder::survey(ScanSequence& drive, std::vector<ScanBox>* boxes, std::vector<uint64_t>* tiles,
                          const Progress& progress, uint32_t* failed_scan) {
  std::unordered_set<uint64_t> seen;
  const uint32_t n = drive.size();
  boxes->assign(n, ScanBox{INT32_MAX, INT32_MIN, INT32_MAX, INT32_MIN});
  for (uint32_t i = 0; i < n; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    ScanView scan;
    Eigen::Isometry3d pose, map_T_lidar;
    VoxelLayer layer;
    Status s = drive.read(i, &scan, &pose);
    if (s == Status::Ok) s = voxelize(scan, pose, &layer, &map_T_lidar, &stats_.scan_points_dropped);
    if (s == Status::Ok) s = detect(layer, map_T_lidar);
    if (s != Status::Ok) {
      if (failed_scan) *failed_scan = i;
      return s;
    }
    to_map(layer, map_T_lidar);
    ScanBox& b = (*boxes)[i];
    uint64_t last = UINT64_MAX;
    for (const auto& kv : scan_order_) {
      const int32_t x = voxel_key_x(kv.first), y = voxel_key_y(kv.first);
      b = {std::min(b[0], x), std::max(b[1], x), std::min(b[2], y), std::max(b[3], y)};
      const uint64_t t = store_.tile_of(kv.first);
      if (t != last) seen.insert(t);
      last = t;
    }
    stats_.scans++;
    stats_.points += scan.count;
    stats_.seconds_accumulate += seconds_since(t0);
    if (progress && (i % 25 == 0 || i + 1 == n)) progress("scans", i + 1, n);
  }
  tiles->assign(seen.begin(), seen.end());
  std::sort(tiles->begin(), tiles->end());
  return tiles->empty() ? Status::InvalidInput : Status::Ok;
}

// The map's tiles in blocks of block_tiles x block_tiles, x-major; per block the scans whose voxels
// reach it or its halo read again, in drive order, and only their voxels there accumulated: every map
// voxel there gets the same sums in the same order as in add_scan's build (tiled_stages.h).
Status MapBuilder::blocked_content(ScanSequence& drive, const std::vector<ScanBox>& boxes,
                                   const std::vector<uint64_t>& tiles, MapContent* content, MapBuildStats* st,
                                   const Progress& progress) {
  const int32_t B = static_cast<int32_t>(options_.block_tiles), T = store_.tile_voxels();
  std::map<std::pair<int32_t, int32_t>, std::vector<uint64_t>> by_block;  // (bx, by): x-major
  for (uint64_t id : tiles)
    by_block[{int32_t(floor_div(TileStore::tile_x(id), B)), int32_t(floor_div(TileStore::tile_y(id), B))}].push_back(
        id);
  std::vector<MapBlock> blocks;
  for (auto& kv : by_block) blocks.push_back(MapBlock{kv.first.first, kv.first.second, std::move(kv.second)});
  const int32_t halo =
      static_cast<int32_t>(std::ceil(tile_halo_m(config_, classes_, options_) / config_.voxel.voxel_size));
  TileStoreConfig tc;
  tc.tile_voxels = T;
  TileStore store(tc);  // unbounded: one block and its halo
  uint64_t reads = 0;
  const FillBlock fill = [&](const MapBlock& b, TileStore* into) {
    const int32_t rect[4] = {b.bx * B * T - halo, (b.bx + 1) * B * T + halo, b.by * B * T - halo,
                             (b.by + 1) * B * T + halo};
    for (uint32_t i = 0; i < boxes.size(); ++i) {
      const ScanBox& x = boxes[i];
      if (x[1] < rect[0] || x[0] >= rect[1] || x[3] < rect[2] || x[2] >= rect[3]) continue;
      const auto t0 = std::chrono::steady_clock::now();
      ScanView scan;
      Eigen::Isometry3d pose, map_T_lidar;
      VoxelLayer layer;
      Status s = drive.read(i, &scan, &pose);
      if (s == Status::Ok) s = voxelize(scan, pose, &layer, &map_T_lidar, nullptr);
      if (s != Status::Ok) return s;
      to_map(layer, map_T_lidar);
      s = accumulate(layer, into, rect);
      if (s != Status::Ok) return s;
      ++reads;
      st->seconds_accumulate += seconds_since(t0);
    }
    into->note_resident_voxels();
    return Status::Ok;
  };
  const Status s =
      build_map_content_blocked(blocks, tiles, B, fill, store, config_, classes_, options_, content, st, progress);
  st->tiles = store.stats();
  st->tiles.tiles = static_cast<uint32_t>(tiles.size());
  st->blocks = static_cast<uint32_t>(blocks.size());
  st->block_scan_reads = reads;
#if defined(__GLIBC__)
  malloc_trim(0);  // as build_content
#endif
  return s;
}

// Instances, fields, refinement points and semantic layer, tile by tile (tiled_stages.h). The map
// being built needs the memory of the resident tiles more: the halo loads read them from the file.
Status MapBuilder::build_content(MapContent* content, MapBuildStats* st, const Progress& progress) {
  Status s = store_.spill_resident();
  if (s != Status::Ok) return s;
#if defined(__GLIBC__)
  malloc_trim(0);  // the resident tiles were many small blocks: give their pages back
#endif
  s = build_map_content(store_, config_, classes_, options_, content, st, progress);
  st->tiles = store_.stats();
  if (s != Status::Ok) return s;
#if defined(__GLIBC__)
  // The tile stages freed many small blocks (candidates, per-tile chunks) spread through the heap: hand
  // their pages back before the triangles and the refinement layer are allocated, or the peak counts them.
  malloc_trim(0);
#endif
  return Status::Ok;
}

// The header's contents; counts of later sections are filled in as they are built.
MapView MapBuilder::map_header(const MapContent& content, const MapBuildStats& st) const {
  const uint32_t ni = static_cast<uint32_t>(content.instances.size());
  MapView header;
  header.georef = georef_;
  header.params = map_params_from(config_);
  header.counts.instances = ni;
  header.counts.road_length_m = options_.road_length_m;
  header.counts.semantic_tiles = st.semantic_tiles;
  header.counts.semantic_palette = static_cast<uint32_t>(content.semantic_palette.size());
  if (st.semantic_tiles > 0) {
    header.params.semantic_cell = options_.semantic_layer.cell;
    header.params.semantic_tile_cells = options_.semantic_layer.tile_cells;
  }
  header.params.refine_cell = st.refine_points > 0 ? config_.refine.cell : 0.0f;
  for (int k = 0; k < 3; ++k) {
    header.counts.bounds_min[k] = 1e30f;
    header.counts.bounds_max[k] = -1e30f;
  }
  for (uint32_t i = 0; i < ni; ++i)
    for (int k = 0; k < 3; ++k) {
      header.counts.bounds_min[k] = std::min(header.counts.bounds_min[k], content.instances[i].centroid[k]);
      header.counts.bounds_max[k] = std::max(header.counts.bounds_max[k], content.instances[i].centroid[k]);
    }
  if (ni == 0)
    for (int k = 0; k < 3; ++k) header.counts.bounds_min[k] = header.counts.bounds_max[k] = 0.0f;
  return header;
}

// The triangle vertices: every instance, or those the query stages found in enough mapping scans (kept
// in id order, so the canonical vertex order's id tie-breaks are those of the full build).
struct MapBuilder::TriangleVertices {
  bool all = true;            // every instance: the content's own arrays
  std::vector<uint32_t> ids;  // else the chosen instances, their centroids and labels
  std::vector<float> xyz;
  std::vector<uint8_t> labels;
  const float* vx = nullptr;  // the vertices' centroids (3 each) and labels, whichever they are
  const uint8_t* vl = nullptr;
  uint32_t count = 0;
};

void MapBuilder::choose_triangle_vertices(const MapContent& content, TriangleVertices* v) const {
  const uint32_t ni = static_cast<uint32_t>(content.labels.size());  // the instance records are written and freed
  v->all = options_.triangle_min_detections == 0;
  if (!v->all) {
    const std::vector<uint32_t> det =
        count_detections(content.centroids.data(), content.labels.data(), ni, detections_, options_.detection_radius);
    const std::vector<uint32_t> near = count_detections(content.centroids.data(), content.labels.data(), ni,
                                                        scan_positions_, options_.detection_range);
    v->ids = triangle_vertices(det, near, options_.triangle_min_detections);
    for (uint32_t i : v->ids) {
      for (int k = 0; k < 3; ++k) v->xyz.push_back(content.centroids[3 * size_t(i) + k]);
      v->labels.push_back(content.labels[i]);
    }
  }
  v->vx = v->all ? content.centroids.data() : v->xyz.data();
  v->vl = v->all ? content.labels.data() : v->labels.data();
  v->count = v->all ? ni : static_cast<uint32_t>(v->ids.size());
}

// Triangles and the hash index over all map instances (or the chosen vertices), with those the mapping
// scans' views would form.
Status MapBuilder::write_triangles(MapSink& sink, const MapContent& content, MapView* header, MapBuildStats* st,
                                   const Progress& progress) const {
  const auto t_tri = std::chrono::steady_clock::now();
  const uint32_t ni = static_cast<uint32_t>(content.labels.size());  // the instance records are written and freed
  const TriangleConfig tc = map_triangle_config(config_.triangle, ni);
  Workspace tws(TriangleBuilder::required_bytes(tc, ni + 1) + size_t(tc.max_triangles) * sizeof(Triangle) + 4096);
  TriangleBuilder tb;
  FixedVector<Triangle> tris;
  if (tb.bind(tws.arena, tc, ni + 1) != Status::Ok || !tris.bind(tws.arena, tc.max_triangles))
    return Status::InvalidArgument;
  TriangleVertices v;
  choose_triangle_vertices(content, &v);
  st->triangle_instances = v.count;
  Status s = tb.build(v.vx, 3, v.vl, v.count, tris);
  if (s != Status::Ok) return s;
  std::vector<Triangle> all(tris.data(), tris.data() + tris.size());
  tws.memory.reset();  // `tris` is copied to `all`
  if (options_.scan_triangles && !detections_.empty()) {
    // What a query at each mapping scan's pose would form (scan_triangles.h), over the same vertices.
    const std::vector<uint32_t> nearest =
        nearest_instances(v.vx, v.vl, v.count, detections_, options_.detection_radius);
    std::vector<uint32_t> begin = scan_detection_begin_;
    begin.push_back(static_cast<uint32_t>(detections_.size()));
    ScanTriangleStats sts;
    const size_t before = all.size();
    s = add_scan_triangles(v.vx, v.vl, v.count, nearest, begin, config_.triangle, options_.scan_triangle_max_key_share,
                           &all, &sts);
    if (s != Status::Ok) return s;
    st->scan_triangles = static_cast<uint32_t>(all.size() - before);
    st->scan_triangles_crowded = sts.crowded;
  }
  const uint32_t nt = static_cast<uint32_t>(all.size());
  if (!v.all)  // vertex numbers -> map instance ids
    for (uint32_t t = 0; t < nt; ++t)
      for (int k = 0; k < 3; ++k) all[t].v[k] = v.ids[all[t].v[k]];
  s = write_triangle_index(sink, &all, tc.side_bin, header, st);
  if (s != Status::Ok) return s;
  st->seconds_triangles = seconds_since(t_tri);
  if (progress) progress("triangles", nt, nt);
  return Status::Ok;
}

// The refinement layer, sorted into its grid with normals (refine_layer_builder.h); frees the points.
Status MapBuilder::write_refine_layer(MapSink& sink, MapContent* content, MapView* header, MapBuildStats* st) const {
  std::vector<MapRefineTile> tiles;
  std::vector<MapRefinePoint> points;
  if (st->refine_points > 0) {
    const Status s = build_refine_layer(&content->refine, config_.refine.cell, &tiles, &points);  // frees the chunks
    if (s != Status::Ok) return s;
  }
  std::vector<std::vector<float>>().swap(content->refine);
  header->counts.refine_points = static_cast<uint32_t>(points.size());
  header->counts.refine_tiles = static_cast<uint32_t>(tiles.size());
  st->refine_tiles = header->counts.refine_tiles;
  return write_sections(sink, {{MapSection::RefineTiles, tiles.data(), tiles.size(), sizeof(MapRefineTile)},
                               {MapSection::RefinePoints, points.data(), points.size(), sizeof(MapRefinePoint)}});
}

}  // namespace gsf::mapping
