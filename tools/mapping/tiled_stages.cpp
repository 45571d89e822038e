#include "mapping/tiled_stages.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <unordered_map>
#include <unordered_set>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "gsf/detail/arena.h"
#include "gsf/detail/gaussian_field.h"
#include "gsf/detail/instance_clustering.h"
#include "gsf/detail/map_quantization.h"
#include "gsf/detail/pole_extraction.h"
#include "gsf/detail/voxel_layer.h"
#include "mapping/floor_div.h"
#include "mapping/workspace.h"

namespace gsf::mapping {
namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// An instance a tile owns, before the whole-map capacities and order are applied.
struct Candidate {
  uint64_t key = 0;  // its lowest voxel key: the whole-map discovery order
  Instance in{};
  float score = 0.0f;  // poles: PoleInfo::score (the capacity ranks by it)
  uint32_t chunk = 0;  // its field rows: the chunk of the tile that fitted it, and the row there
  uint32_t row = 0;
  uint32_t inducing = 0;
  MapInstance scales{};  // the quantisation scales of its grid rows (mean_min ... var_step)
  uint32_t field_points_dropped = 0;
  bool fit_ok = false;
};

struct RefineCandidate {
  uint64_t cell;   // refinement cell key
  uint64_t voxel;  // voxel key: the first in key order wins the cell
  float point[3];  // x, y, z
};

// One tile's fitted fields, rows in the tile's candidate order, quantised as they are fitted (the
// quantisation is per instance, so it is the same whenever it runs). Fields grow per tile and are
// gathered into exactly sized map-order arrays at the end, one array at a time, so the builder never
// holds a doubled vector capacity, two whole copies of the fields, or their float form.
struct FieldChunk {
  std::vector<uint8_t> mean;  // the probed grid (the map stores no inducing inputs or weights)
  std::vector<uint16_t> var;
};

// Map-order rows of one field array from the chunks (member `part`), freeing the chunks' rows as it goes.
template <typename T>
void gather_rows(std::vector<FieldChunk>* chunks, std::vector<T> FieldChunk::*part, size_t row,
                 const std::vector<std::pair<uint32_t, uint32_t>>& rows, std::vector<T>* out) {
  std::vector<T>(rows.size() * row).swap(*out);
  for (size_t i = 0; i < rows.size(); ++i) {
    const std::vector<T>& from = (*chunks)[rows[i].first].*part;
    std::copy_n(from.begin() + size_t(rows[i].second) * row, row, out->begin() + i * row);
  }
  for (FieldChunk& c : *chunks) std::vector<T>().swap(c.*part);
}

}  // namespace

double tile_halo_m(const LocalizerConfig& config, const ClassTable& classes, const MapBuildConfig& options) {
  ClassMask instance_classes = config.classes ? classes.instance_classes() : config.cluster.instance_classes;
  double extent = 0.0, tolerance = 0.0;
  for (int c = 0; c < kNumClasses; ++c)
    if (instance_classes & class_bit(c)) {
      extent = std::max(extent, double(config.cluster.max_extent[c]));
      tolerance = std::max(tolerance, double(config.cluster.tolerance[c]));
    }
  const PoleConfig pc = effective_pole_config(config);
  if ((pc.pole_hosts | pc.trunk_hosts) != 0) {
    // A kept chain is thin about a near-vertical axis; its members link within link_radius and its
    // segments look ring_width around them.
    const double chain = std::max(pc.max_diameter[0], pc.max_diameter[1]) + pc.ring_width + pc.link_radius + pc.max_gap;
    extent = std::max(extent, chain);
    tolerance = std::max(tolerance, double(pc.ring_width + pc.link_radius));
  }
  double halo = extent + std::max(tolerance, double(config.field.radius));
  if (options.semantic_layer.cell > 0.0f)
    halo = std::max(halo, double(options.semantic_layer.cell) * options.semantic_layer.tile_cells);
  return halo + 2.0 * config.voxel.voxel_size;  // float rounding of centroids at voxel borders
}

Status build_map_content(TileStore& store, const LocalizerConfig& config, const ClassTable& classes,
                         const MapBuildConfig& options, MapContent* out, MapBuildStats* st, const Progress& progress) {
  *out = MapContent();
  const double vs = config.voxel.voxel_size;
  const int32_t tile = store.tile_voxels();  // 0: one tile, everything loaded
  const int32_t halo = tile == 0 ? 0 : static_cast<int32_t>(std::ceil(tile_halo_m(config, classes, options) / vs));
  const int32_t ring = tile == 0 ? 0 : (halo + tile - 1) / tile;

  ClusterConfig cc0 = config.cluster;
  cc0.instance_classes = classes.instance_classes();
  if (!config.classes) cc0.instance_classes = config.cluster.instance_classes;
  uint32_t min_cluster_voxels = UINT32_MAX;
  for (int c = 0; c < kNumClasses; ++c) min_cluster_voxels = std::min(min_cluster_voxels, cc0.min_voxels[c]);
  const PoleConfig pc0 = effective_pole_config(config);
  const bool poles_on = (pc0.pole_hosts | pc0.trunk_hosts) != 0;

  const FieldConfig& fc = config.field;
  const uint32_t M = fc.inducing_points, G = grid_points(fc), D = kNumClasses;
  const uint32_t max_pts = options.max_field_points;
  Workspace fws(FieldSolver::required_bytes(fc, max_pts) + 4096);
  FieldSolver solver;
  if (solver.bind(fws.arena, fc, max_pts) != Status::Ok) return Status::InvalidArgument;
  std::vector<uint32_t> ids(max_pts);
  std::vector<float> xyz(size_t(max_pts) * 3), targets(size_t(max_pts) * D), chol(size_t(M) * M), grid(size_t(G) * 3);
  std::vector<float> field_inputs(size_t(M) * 3), field_alpha(size_t(M) * D);
  std::vector<float> row_mean(size_t(G) * D), row_var(G);  // one instance's grid before quantisation
  std::vector<uint8_t> gl(max_pts);
  make_probe_grid(fc, 0.0f, grid.data());

  std::vector<Candidate> clustered, poles;
  std::vector<FieldChunk> fields;  // per map tile with candidates
  // Refinement candidates not yet final, and the final points in cell order (chunks of a fixed capacity,
  // so the layer never sits in a doubled vector capacity; handed to the map as chunks).
  std::vector<RefineCandidate> refine;
  constexpr size_t kRefineChunkFloats = size_t(3) << 18;  // 3 MB
  std::vector<std::vector<float>>& refine_chunks = out->refine;
  size_t refine_floats = 0;
  // Tiles come x-major: once a column of tiles is done, no later tile owns a voxel left of its right
  // edge (less a voxel for rounding), so cells left of it are final: per cell the candidate with the
  // lowest voxel key, emitted in cell order (keys are x-major too). Only a column's candidates wait.
  auto flush_refine = [&](uint64_t limit) {
    std::sort(refine.begin(), refine.end(), [](const RefineCandidate& a, const RefineCandidate& b) {
      return a.cell != b.cell ? a.cell < b.cell : a.voxel < b.voxel;
    });
    size_t k = 0;
    for (; k < refine.size() && refine[k].cell < limit; ++k) {
      if (k > 0 && refine[k].cell == refine[k - 1].cell) continue;
      if (refine_chunks.empty() || refine_chunks.back().size() + 3 > kRefineChunkFloats) {
        refine_chunks.emplace_back();
        refine_chunks.back().reserve(kRefineChunkFloats);
      }
      refine_chunks.back().insert(refine_chunks.back().end(), refine[k].point, refine[k].point + 3);
      refine_floats += 3;
    }
    refine.erase(refine.begin(), refine.begin() + k);
  };
  // Per semantic tile: its key, and its place in the per-map-tile chunks (chunk, tile in the chunk).
  // Each chunk is paletted when built (palette_semantic_layer: a tile's palette depends on it alone).
  struct SemanticChunk {
    std::vector<uint32_t> offsets, palette;
    std::vector<uint8_t> cells;
  };
  std::vector<std::pair<uint32_t, std::pair<uint32_t, uint32_t>>> semantic;
  std::vector<SemanticChunk> semantic_chunks;
  const size_t semantic_tile_size = size_t(options.semantic_layer.tile_cells) * options.semantic_layer.tile_cells;
  uint64_t map_voxels = 0;
  double seconds_cluster = 0, seconds_fields = 0;

  // A candidate's field: the same per-instance fit as the localizer's query fields (gaussian_field.h),
  // into rows initialised as a whole-map build initialises them, then quantised (map_quantization.h).
  auto fit_field = [&](const VoxelLayer& layer, Candidate* c) {
    FieldChunk& chunk = fields.back();
    c->chunk = static_cast<uint32_t>(fields.size() - 1);
    c->row = static_cast<uint32_t>(chunk.var.size() / G);
    std::fill(row_mean.begin(), row_mean.end(), 0.0f);
    std::fill(row_var.begin(), row_var.end(), fc.signal_variance);
    float* in_i = field_inputs.data();  // needed only to probe the grid
    float* al_i = field_alpha.data();
    const FieldGather gather{max_pts, ids.data(), xyz.data(), targets.data(), gl.data()};
    uint32_t m = 0, got = 0, total = 0;
    const Status fit =
        fit_instance_field(solver, layer, c->in.centroid, gather, in_i, al_i, chol.data(), &m, &got, &total);
    c->field_points_dropped = total - got;
    c->fit_ok = fit == Status::Ok;
    if (c->fit_ok) {
      c->inducing = m;
      FieldView f{in_i, al_i, m};
      solver.probe(f, chol.data(), grid.data(), G, row_mean.data(), row_var.data(), nullptr);
    }
    chunk.mean.resize(chunk.mean.size() + size_t(G) * D);
    chunk.var.resize(chunk.var.size() + G);
    quantize_instance_grid(row_mean.data(), row_var.data(), G, D, &c->scales,
                           chunk.mean.data() + size_t(c->row) * G * D, chunk.var.data() + size_t(c->row) * G);
  };

  const std::vector<uint64_t> tiles = store.tile_ids();
  for (size_t t = 0; t < tiles.size(); ++t) {
    const uint64_t id = tiles[t];
    const int32_t tx = TileStore::tile_x(id), ty = TileStore::tile_y(id);
    const auto t_cluster = std::chrono::steady_clock::now();
    // The tile and its halo, sorted by key: the order a whole-map build would hold them in.
    std::vector<std::pair<uint64_t, VoxelAccum>> loaded;
    const int32_t x0 = tx * tile - halo, x1 = (tx + 1) * tile + halo;
    const int32_t y0 = ty * tile - halo, y1 = (ty + 1) * tile + halo;
    for (int32_t dx = -ring; dx <= ring; ++dx)
      for (int32_t dy = -ring; dy <= ring; ++dy) {
        const Status s = store.append_voxels(TileStore::tile_id(tx + dx, ty + dy), x0, x1, y0, y1, &loaded);
        if (s != Status::Ok) return s;
      }
    std::sort(loaded.begin(), loaded.end(),
              [](const std::pair<uint64_t, VoxelAccum>& a, const std::pair<uint64_t, VoxelAccum>& b) {
                return a.first < b.first;
              });
    const uint32_t nv = static_cast<uint32_t>(loaded.size());
    if (nv == 0) continue;

    // The voxels as one "scan" of centroids with log-probabilities as logits: the same VoxelLayer then
    // reproduces the accumulated voxels (same grid, one point each) and the localizer's stages apply.
    std::vector<uint64_t> keys(nv);
    std::vector<float> pts(size_t(nv) * 4), logits(size_t(nv) * kNumClasses);
    std::vector<uint32_t> labels(nv);
    for (uint32_t i = 0; i < nv; ++i) {
      const VoxelAccum& a = loaded[i].second;
      keys[i] = loaded[i].first;
      if (store.tile_of(keys[i]) == id) ++map_voxels;
      int best = 0;
      for (int k = 0; k < 3; ++k) pts[4 * i + k] = static_cast<float>(a.sum[k] / a.count);
      pts[4 * i + 3] = 0.0f;
      for (int c = 0; c < kNumClasses; ++c) {
        const double p = a.prob[c] / a.count;
        logits[size_t(i) * kNumClasses + c] = static_cast<float>(std::log(p + 1e-6));
        if (a.prob[c] > a.prob[best]) best = c;
      }
      labels[i] = kitti_from_class(best);
    }
    std::vector<std::pair<uint64_t, VoxelAccum>>().swap(loaded);

    VoxelConfig vc = config.voxel;
    vc.min_range = 0.0f;
    vc.max_range = 1e7f;
    vc.max_voxels = nv + 16;
    vc.max_columns = nv + 16;
    ClusterConfig cc = cc0;
    cc.max_instances = nv / std::max(1u, min_cluster_voxels) + 1;  // every component the tile can hold
    PoleConfig pc = pc0;
    pc.max_instances = nv / std::max(1u, pc0.min_levels) + 1;
    Workspace ws(VoxelLayer::required_bytes(vc) + InstanceClustering::required_bytes(cc, vc.max_voxels) +
                 (poles_on ? PoleExtraction::required_bytes(pc, vc.max_voxels) : 0) + 4096);
    VoxelLayer layer;  // reads the accumulated voxels' library classes as SemanticKITTI ids (above)
    InstanceClustering clusters;
    PoleExtraction pole_stage;
    if (layer.bind(ws.arena, vc) != Status::Ok || clusters.bind(ws.arena, cc, vc.max_voxels) != Status::Ok ||
        (poles_on && pole_stage.bind(ws.arena, pc, vc.max_voxels) != Status::Ok))
      return Status::InvalidArgument;
    clusters.set_classes(&classes);
    ScanView sv;
    sv.points = pts.data();
    sv.stride = 4;
    sv.labels = labels.data();
    sv.logits = logits.data();
    sv.logit_dim = kNumClasses;
    sv.count = nv;
    Status s = layer.build(sv, nullptr);
    if (s != Status::Ok) return s;
    // Layer voxel -> the input voxel that created it (voxels are stored in first-insertion order; two
    // accumulated voxels whose float centroids round into one cell make one layer voxel).
    std::vector<uint32_t> creator;
    if (layer.size() != nv) {
      creator.assign(layer.size(), UINT32_MAX);
      for (uint32_t j = 0; j < nv; ++j) {
        const uint32_t i = layer.find(&pts[4 * size_t(j)]);
        if (i != UINT32_MAX && creator[i] == UINT32_MAX) creator[i] = j;
      }
    }
    auto key_of_voxel = [&](uint32_t i) { return keys[creator.empty() ? i : creator[i]]; };
    ClusterStats cs;
    s = clusters.build(layer, &cs);
    if (s != Status::Ok) return s;
    const size_t clustered_before = clustered.size(), poles_before = poles.size();
    for (uint32_t k = 0; k < clusters.size(); ++k) {
      Candidate c;
      c.key = key_of_voxel(clusters.instance(k).first_voxel);
      if (store.tile_of(c.key) != id) continue;  // another tile's (it holds its lowest voxel)
      c.in = clusters.instance(k);
      clustered.push_back(c);
    }
    if (poles_on) {
      PoleStats ps;
      s = pole_stage.build(layer, &ps);
      if (s != Status::Ok) return s;
      for (uint32_t k = 0; k < pole_stage.size(); ++k) {
        Candidate c;
        c.key = key_of_voxel(pole_stage.instance(k).first_voxel);
        if (store.tile_of(c.key) != id) continue;
        c.in = pole_stage.instance(k);
        c.score = pole_stage.info(k).score;
        poles.push_back(c);
      }
    }
    seconds_cluster += seconds_since(t_cluster);

    const auto t_fields = std::chrono::steady_clock::now();
    if (clustered.size() > clustered_before || poles.size() > poles_before) fields.emplace_back();
    for (size_t k = clustered_before; k < clustered.size(); ++k) fit_field(layer, &clustered[k]);
    for (size_t k = poles_before; k < poles.size(); ++k) fit_field(layer, &poles[k]);
    seconds_fields += seconds_since(t_fields);

    // Refinement candidates: long-term structure, the first owned voxel (key order) per cell.
    if (options.refine_voxel > 0.0f) {
      std::unordered_set<uint64_t> seen;
      for (uint32_t i = 0; i < layer.size(); ++i) {
        const Voxel& v = layer.voxel(i);
        if (classes.stability(v.label) < 1.0f) continue;
        const uint64_t vk = key_of_voxel(i);
        if (store.tile_of(vk) != id) continue;
        const uint64_t cell = voxel_key(v.centroid[0], v.centroid[1], v.centroid[2], options.refine_voxel);
        if (!seen.insert(cell).second) continue;
        refine.push_back({cell, vk, {v.centroid[0], v.centroid[1], v.centroid[2]}});
      }
    }

    // Semantic tiles this map tile owns: the first existing map tile (id order) each overlaps, with a
    // voxel of slack for centroids rounded onto a border.
    if (options.semantic_layer.cell > 0.0f) {
      const double side = double(options.semantic_layer.cell) * options.semantic_layer.tile_cells;
      std::unordered_map<uint64_t, bool> owned;
      auto keep = [&](int64_t fx, int64_t fy) {
        if (tile == 0) return true;
        const uint64_t k = (uint64_t(uint32_t(fx)) << 32) | uint32_t(fy);
        auto it = owned.find(k);
        if (it != owned.end()) return it->second;
        const int32_t ax = static_cast<int32_t>(floor_div(int64_t(std::floor((fx * side - vs) / vs)), tile));
        const int32_t bx = static_cast<int32_t>(floor_div(int64_t(std::floor(((fx + 1) * side + vs) / vs)), tile));
        const int32_t ay = static_cast<int32_t>(floor_div(int64_t(std::floor((fy * side - vs) / vs)), tile));
        const int32_t by = static_cast<int32_t>(floor_div(int64_t(std::floor(((fy + 1) * side + vs) / vs)), tile));
        uint64_t first = UINT64_MAX;
        for (int32_t x = ax; x <= bx && first == UINT64_MAX; ++x)
          for (int32_t y = ay; y <= by; ++y)
            if (store.has_tile(TileStore::tile_id(x, y))) {
              first = TileStore::tile_id(x, y);
              break;
            }
        return owned[k] = first == id;
      };
      std::vector<uint32_t> sem_keys, sem_cells;
      build_semantic_layer(layer, options.semantic_layer, &sem_keys, &sem_cells, keep);
      if (!sem_keys.empty()) {
        for (size_t k = 0; k < sem_keys.size(); ++k)
          semantic.push_back({sem_keys[k], {uint32_t(semantic_chunks.size()), uint32_t(k)}});
        SemanticChunk chunk;
        const Status ps =
            palette_semantic_layer(sem_cells, uint32_t(sem_keys.size()), options.semantic_layer.tile_cells,
                                   &chunk.offsets, &chunk.palette, &chunk.cells);
        if (ps != Status::Ok) return ps;
        chunk.palette.shrink_to_fit();
        semantic_chunks.push_back(std::move(chunk));
      }
    }
    if (tile > 0 && options.refine_voxel > 0.0f && t + 1 < tiles.size() && TileStore::tile_x(tiles[t + 1]) != tx) {
      const double edge = (double(tx + 1) * tile - 1.0) * vs;  // m, a voxel inside the column's right edge
      const int64_t cell_x = static_cast<int64_t>(std::floor(edge / options.refine_voxel)) + (1 << 20);
      if (cell_x > 0 && cell_x < (1 << 21)) flush_refine(uint64_t(cell_x) << 42);
    }
    if (progress) progress("tiles", t + 1, tiles.size());
#if defined(__GLIBC__)
    // The tile's temporaries (tens of MB) were freed between the map's growing arrays: hand their pages
    // back, or the heap's high-water mark grows with the map by the fragments.
    malloc_trim(0);
#endif
  }
  flush_refine(UINT64_MAX);
  std::vector<RefineCandidate>().swap(refine);
  if (map_voxels == 0) return Status::InvalidInput;
  st->map_voxels = static_cast<uint32_t>(map_voxels);

  // Whole-map capacities with the stages' own rules, then discovery (lowest voxel key) order.
  auto keep_best = [](std::vector<Candidate>* v, uint32_t cap, auto better) -> uint32_t {
    if (v->size() <= cap) return 0;
    std::vector<Candidate> ranked = *v;
    std::nth_element(ranked.begin(), ranked.begin() + cap, ranked.end(), better);
    ranked.resize(cap);
    const uint32_t dropped = static_cast<uint32_t>(v->size() - cap);
    v->swap(ranked);
    return dropped;
  };
  st->instances_dropped += keep_best(&clustered, options.max_instances, [](const Candidate& a, const Candidate& b) {
    return a.in.point_count != b.in.point_count ? a.in.point_count > b.in.point_count : a.key < b.key;
  });
  st->instances_dropped += keep_best(&poles, options.max_pole_instances, [](const Candidate& a, const Candidate& b) {
    if (a.score != b.score) return a.score > b.score;
    if (a.in.point_count != b.in.point_count) return a.in.point_count > b.in.point_count;
    return a.key < b.key;
  });
  auto by_key = [](const Candidate& a, const Candidate& b) { return a.key < b.key; };
  std::sort(clustered.begin(), clustered.end(), by_key);
  std::sort(poles.begin(), poles.end(), by_key);
  std::vector<Candidate> found = std::move(clustered);
  found.insert(found.end(), poles.begin(), poles.end());
  st->pole_instances = static_cast<uint32_t>(poles.size());
  std::vector<Candidate>().swap(poles);
  const uint32_t ni = static_cast<uint32_t>(found.size());
  st->instances = ni;

  // Field rows into map order (rows of dropped instances are left out).
  std::vector<std::pair<uint32_t, uint32_t>> rows(ni);
  for (uint32_t i = 0; i < ni; ++i) rows[i] = {found[i].chunk, found[i].row};
  gather_rows(&fields, &FieldChunk::mean, size_t(G) * D, rows, &out->mean);
  gather_rows(&fields, &FieldChunk::var, G, rows, &out->var);
  std::vector<FieldChunk>().swap(fields);
  out->instances.resize(ni);
  out->centroids.resize(size_t(ni) * 3);
  out->labels.resize(ni);
  for (uint32_t i = 0; i < ni; ++i) {
    const Candidate& c = found[i];
    MapInstance& mi = out->instances[i];
    std::memset(&mi, 0, sizeof(mi));
    for (int k = 0; k < 3; ++k) mi.centroid[k] = out->centroids[3 * i + k] = c.in.centroid[k];
    mi.stability = c.in.stability;
    mi.point_count = c.in.point_count;
    mi.mean_min = c.scales.mean_min;
    mi.mean_step = c.scales.mean_step;
    mi.var_min = c.scales.var_min;
    mi.var_step = c.scales.var_step;
    mi.label = out->labels[i] = c.in.label;
    st->instances_by_class[c.in.label]++;
    st->field_points_dropped += c.field_points_dropped;
    if (!c.fit_ok) st->fields_failed++;
  }
  st->seconds_cluster = seconds_cluster;
  st->seconds_fields = seconds_fields;
  if (progress) progress("clustered instances", ni, ni);

  // Refinement points: already final, in cell order, in out->refine's chunks.
  st->refine_points = static_cast<uint32_t>(refine_floats / 3);

  // The semantic layer in key order, paletted tile by tile (a tile's palette depends on it alone).
  std::sort(semantic.begin(), semantic.end());
  out->semantic_keys.reserve(semantic.size());
  out->semantic_cells.reserve(semantic.size() * semantic_tile_size);
  if (!semantic.empty()) out->semantic_palette_offsets.reserve(semantic.size() + 1);
  for (const auto& [key, at] : semantic) {
    const SemanticChunk& chunk = semantic_chunks[at.first];
    const uint32_t k = at.second;
    if (out->semantic_palette_offsets.empty()) out->semantic_palette_offsets.push_back(0);
    out->semantic_keys.push_back(key);
    out->semantic_palette.insert(out->semantic_palette.end(), chunk.palette.begin() + chunk.offsets[k],
                                 chunk.palette.begin() + chunk.offsets[k + 1]);
    out->semantic_palette_offsets.push_back(static_cast<uint32_t>(out->semantic_palette.size()));
    out->semantic_cells.insert(out->semantic_cells.end(), chunk.cells.begin() + size_t(k) * semantic_tile_size,
                               chunk.cells.begin() + size_t(k + 1) * semantic_tile_size);
  }
  std::vector<SemanticChunk>().swap(semantic_chunks);
  // The neighbour masks read across tile edges, so they come once the layer is whole.
  const Status ns =
      add_semantic_neighbours(out->semantic_keys, options.semantic_layer.tile_cells, &out->semantic_palette_offsets,
                              &out->semantic_palette, &out->semantic_cells, &out->semantic_neighbours);
  if (ns != Status::Ok) return ns;
  out->semantic_palette.shrink_to_fit();
  st->semantic_tiles = static_cast<uint32_t>(out->semantic_keys.size());
  return Status::Ok;
}

}  // namespace gsf::mapping
