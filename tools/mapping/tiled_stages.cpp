#include "mapping/tiled_stages.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <unordered_map>

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

// A refinement cell's owned voxels in one tile: the sum of their centroids. Sums of a cell's few
// float centroids (one cell's magnitudes, far fewer than 2^29 of them) are exact in double, so the
// cell's mean is the same whatever tiles its voxels came through, in whatever order.
struct RefineCandidate {
  uint64_t cell;   // refinement cell key
  uint64_t voxel;  // the tile's first voxel key in the cell (orders the candidates)
  double sum[3];   // x, y, z
  uint32_t count;
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

namespace {

// Per semantic tile its place in the per-map-tile chunks; each chunk is paletted when built
// (palette_semantic_layer: a tile's palette depends on it alone).
struct SemanticChunk {
  std::vector<uint32_t> offsets, palette;
  std::vector<uint8_t> cells;
};

// A candidate's field: the same per-instance fit as the localizer's query fields (gaussian_field.h),
// into rows initialised as a whole-map build initialises them, then quantised (map_quantization.h).
// Holds the solver and one fit's scratch, reused for every instance.
class FieldFitter {
 public:
  FieldFitter(const FieldConfig& fc, uint32_t max_pts)
      : fc_(fc),
        M_(fc.inducing_points),
        G_(grid_points(fc)),
        max_pts_(max_pts),
        ws_(FieldSolver::required_bytes(fc, max_pts) + 4096) {}

  // Binds the solver and sizes the scratch; false when the field config does not fit.
  bool bind() {
    if (solver_.bind(ws_.arena, fc_, max_pts_) != Status::Ok) return false;
    const uint32_t D = kNumClasses;
    std::vector<uint32_t>(max_pts_).swap(ids_);
    std::vector<float>(size_t(M_) * M_).swap(chol_);
    std::vector<float>(size_t(G_) * 3).swap(grid_);
    std::vector<float>(size_t(M_) * 3).swap(field_inputs_);
    std::vector<float>(size_t(M_) * D).swap(field_alpha_);
    std::vector<float>(size_t(G_) * D).swap(row_mean_);
    std::vector<float>(G_).swap(row_var_);
    std::vector<uint8_t>(max_pts_).swap(gl_);
    make_probe_grid(fc_, 0.0f, grid_.data());
    return true;
  }

  // Fits c's field and appends its quantised grid as the next row of the last chunk.
  void fit(const VoxelLayer& layer, std::vector<FieldChunk>* fields, Candidate* c) {
    const uint32_t G = G_, D = kNumClasses;
    FieldChunk& chunk = fields->back();
    c->chunk = static_cast<uint32_t>(fields->size() - 1);
    c->row = static_cast<uint32_t>(chunk.var.size() / G);
    std::fill(row_mean_.begin(), row_mean_.end(), 0.0f);
    std::fill(row_var_.begin(), row_var_.end(), fc_.signal_variance);
    float* in_i = field_inputs_.data();  // needed only to probe the grid
    float* al_i = field_alpha_.data();
    const FieldGather gather{max_pts_, ids_.data(), gl_.data()};
    uint32_t m = 0, got = 0, total = 0;
    const Status fit =
        fit_instance_field(solver_, layer, c->in.centroid, gather, in_i, al_i, chol_.data(), &m, &got, &total);
    c->field_points_dropped = total - got;
    c->fit_ok = fit == Status::Ok;
    if (c->fit_ok) {
      c->inducing = m;
      FieldView f{in_i, al_i, m};
      solver_.probe(f, chol_.data(), grid_.data(), G, row_mean_.data(), row_var_.data(), nullptr);
    }
    chunk.mean.resize(chunk.mean.size() + size_t(G) * D);
    chunk.var.resize(chunk.var.size() + G);
    quantize_instance_grid(row_mean_.data(), row_var_.data(), G, D, &c->scales,
                           chunk.mean.data() + size_t(c->row) * G * D, chunk.var.data() + size_t(c->row) * G);
  }

 private:
  const FieldConfig& fc_;
  const uint32_t M_, G_, max_pts_;
  Workspace ws_;
  FieldSolver solver_;
  std::vector<uint32_t> ids_;
  std::vector<float> chol_, grid_, field_inputs_, field_alpha_;
  std::vector<float> row_mean_, row_var_;  // one instance's grid before quantisation
  std::vector<uint8_t> gl_;
};

// One tile and its halo as one "scan" of voxel centroids with log-probabilities as logits: the same
// VoxelLayer then reproduces the accumulated voxels (same grid, one point each) and the localizer's
// stages apply. Point i is the accumulated voxel of key keys[i] (points in key order).
struct TileScan {
  std::vector<uint64_t> keys;
  std::vector<float> pts, logits;
  std::vector<uint32_t> labels;
  uint32_t size() const { return static_cast<uint32_t>(keys.size()); }
};

// The localizer's stage settings for one tile of nv voxels: capacities for every voxel and component
// it can hold, and the workspace they need.
struct TileConfigs {
  VoxelConfig voxel;
  ClusterConfig cluster;
  PoleConfig poles;
  size_t bytes = 0;
};

// The localizer's stages over one tile's scan, in one workspace sized for it.
struct TileLayer {
  TileLayer(size_t bytes, const std::vector<uint64_t>& scan_keys) : ws(bytes), keys(scan_keys) {}
  // The map voxel key of layer voxel i.
  uint64_t key_of_voxel(uint32_t i) const { return keys[creator.empty() ? i : creator[i]]; }

  Workspace ws;
  VoxelLayer layer;  // reads the accumulated voxels' library classes as SemanticKITTI ids (TileScan)
  InstanceClustering clusters;
  PoleExtraction poles;
  const std::vector<uint64_t>& keys;
  // Layer voxel -> the scan point that created it (voxels are stored in first-insertion order; two
  // accumulated voxels whose float centroids round into one cell make one layer voxel); empty when
  // every point made its own voxel.
  std::vector<uint32_t> creator;
};

// Keeps the best `cap` of *v by `better` (in no particular order); returns how many it dropped.
template <typename Better>
uint32_t keep_best(std::vector<Candidate>* v, uint32_t cap, Better better) {
  if (v->size() <= cap) return 0;
  std::vector<Candidate> ranked = *v;
  std::nth_element(ranked.begin(), ranked.begin() + cap, ranked.end(), better);
  ranked.resize(cap);
  const uint32_t dropped = static_cast<uint32_t>(v->size() - cap);
  v->swap(ranked);
  return dropped;
}

// The whole-map stages run tile by tile (tiled_stages.h): each tile adds what it owns (instances with
// their field rows, refinement candidates, semantic tiles); finish() applies the whole-map capacities
// and orders and fills the content.
class TiledStages {
 public:
  // `exists`: every tile of the map, sorted (the blocked build's store holds one block); nullptr: the store's.
  TiledStages(TileStore& store, const LocalizerConfig& config, const ClassTable& classes, const MapBuildConfig& options,
              MapContent* out, const std::vector<uint64_t>* exists = nullptr);
  // Binds the field solver; false when the field config does not fit.
  bool bind() { return fitter_.bind(); }
  // Runs the stages on tile tiles[t] (tiles in id order, x-major) and keeps what it owns.
  Status add_tile(const std::vector<uint64_t>& tiles, size_t t, const Progress& progress);
  // Runs the stages on tile `id` (its voxels and its halo's in the store) and keeps what it owns.
  Status run_tile(uint64_t id);
  // Every tile left of tile column tx_end is done: the refinement cells left of it are final.
  void flush_left_of(int32_t tx_end);
  // After the last tile: the whole-map capacities and orders, into the content and *st.
  Status finish(MapBuildStats* st, const Progress& progress);

 private:
  Status load_tile(uint64_t id, TileScan* scan);
  TileConfigs tile_configs(uint32_t nv) const;
  Status build_layer(const TileScan& scan, const TileConfigs& tc, TileLayer* tl) const;
  Status collect_instances(uint64_t id, TileLayer* tl);
  void fit_fields(const VoxelLayer& layer, size_t clustered_before, size_t poles_before);
  void collect_refine(uint64_t id, const TileLayer& tl);
  Status collect_semantic(uint64_t id, const VoxelLayer& layer);
  bool owns_semantic_tile(uint64_t id, int64_t fx, int64_t fy, std::unordered_map<uint64_t, bool>* owned) const;
  void flush_finished_column(const std::vector<uint64_t>& tiles, size_t t);
  bool has_tile(uint64_t id) const {
    return exists_ ? std::binary_search(exists_->begin(), exists_->end(), id) : store_.has_tile(id);
  }
  void flush_refine(uint64_t limit);
  std::vector<Candidate> apply_capacities(MapBuildStats* st);
  void write_instances(const std::vector<Candidate>& found, MapBuildStats* st);
  Status write_semantic_layer(MapBuildStats* st);

  TileStore& store_;
  const LocalizerConfig& config_;
  const ClassTable& classes_;
  const MapBuildConfig& options_;
  MapContent* out_;
  const double vs_;     // m, the voxel size
  const int32_t tile_;  // voxels a tile's side; 0: one tile, everything loaded
  int32_t halo_ = 0;    // voxels read around a tile
  int32_t ring_ = 0;    // tiles read around a tile (covering the halo)
  ClusterConfig cc0_;
  uint32_t min_cluster_voxels_ = UINT32_MAX;
  PoleConfig pc0_;
  bool poles_on_ = false;
  const uint32_t G_;  // probed grid points per field
  FieldFitter fitter_;

  std::vector<Candidate> clustered_, poles_;
  std::vector<FieldChunk> fields_;  // per map tile with candidates
  // Refinement candidates not yet final; the final points go in cell order to out_->refine (chunks of
  // a fixed capacity, so the layer never sits in a doubled vector capacity; handed to the map as chunks).
  std::vector<RefineCandidate> refine_;
  size_t refine_floats_ = 0;
  // Per semantic tile: its key, and its place in the per-map-tile chunks (chunk, tile in the chunk).
  std::vector<std::pair<uint32_t, std::pair<uint32_t, uint32_t>>> semantic_;
  std::vector<SemanticChunk> semantic_chunks_;
  uint64_t map_voxels_ = 0;
  const std::vector<uint64_t>* exists_ = nullptr;
  double seconds_cluster_ = 0, seconds_fields_ = 0;
};

TiledStages::TiledStages(TileStore& store, const LocalizerConfig& config, const ClassTable& classes,
                         const MapBuildConfig& options, MapContent* out, const std::vector<uint64_t>* exists)
    : store_(store),
      config_(config),
      classes_(classes),
      options_(options),
      out_(out),
      vs_(config.voxel.voxel_size),
      tile_(store.tile_voxels()),
      cc0_(config.cluster),
      pc0_(effective_pole_config(config)),
      G_(grid_points(config.field)),
      fitter_(config.field, options.max_field_points),
      exists_(exists) {
  if (tile_ != 0) {
    halo_ = static_cast<int32_t>(std::ceil(tile_halo_m(config, classes, options) / vs_));
    ring_ = (halo_ + tile_ - 1) / tile_;
  }
  cc0_.instance_classes = classes.instance_classes();
  if (!config.classes) cc0_.instance_classes = config.cluster.instance_classes;
  for (int c = 0; c < kNumClasses; ++c) min_cluster_voxels_ = std::min(min_cluster_voxels_, cc0_.min_voxels[c]);
  poles_on_ = (pc0_.pole_hosts | pc0_.trunk_hosts) != 0;
}

Status TiledStages::add_tile(const std::vector<uint64_t>& tiles, size_t t, const Progress& progress) {
  const Status s = run_tile(tiles[t]);
  if (s != Status::Ok) return s;
  flush_finished_column(tiles, t);
  if (progress) progress("tiles", t + 1, tiles.size());
  return Status::Ok;
}

Status TiledStages::run_tile(uint64_t id) {
  const auto t_cluster = std::chrono::steady_clock::now();
  TileScan scan;
  Status s = load_tile(id, &scan);
  if (s != Status::Ok) return s;
  if (scan.size() == 0) return Status::Ok;
  const TileConfigs tc = tile_configs(scan.size());
  TileLayer tl(tc.bytes, scan.keys);
  s = build_layer(scan, tc, &tl);
  if (s != Status::Ok) return s;
  const size_t clustered_before = clustered_.size(), poles_before = poles_.size();
  s = collect_instances(id, &tl);
  if (s != Status::Ok) return s;
  seconds_cluster_ += seconds_since(t_cluster);

  const auto t_fields = std::chrono::steady_clock::now();
  fit_fields(tl.layer, clustered_before, poles_before);
  seconds_fields_ += seconds_since(t_fields);

  collect_refine(id, tl);
  s = collect_semantic(id, tl.layer);
  if (s != Status::Ok) return s;
#if defined(__GLIBC__)
  // The tile's temporaries (tens of MB) were freed between the map's growing arrays: hand their pages
  // back, or the heap's high-water mark grows with the map by the fragments.
  malloc_trim(0);
#endif
  return Status::Ok;
}

// The tile and its halo, sorted by key (the order a whole-map build would hold them in), as one scan;
// counts the tile's own voxels into map_voxels_.
Status TiledStages::load_tile(uint64_t id, TileScan* scan) {
  const int32_t tx = TileStore::tile_x(id), ty = TileStore::tile_y(id);
  std::vector<std::pair<uint64_t, VoxelAccum>> loaded;
  const int32_t x0 = tx * tile_ - halo_, x1 = (tx + 1) * tile_ + halo_;
  const int32_t y0 = ty * tile_ - halo_, y1 = (ty + 1) * tile_ + halo_;
  for (int32_t dx = -ring_; dx <= ring_; ++dx)
    for (int32_t dy = -ring_; dy <= ring_; ++dy) {
      const Status s = store_.append_voxels(TileStore::tile_id(tx + dx, ty + dy), x0, x1, y0, y1, &loaded);
      if (s != Status::Ok) return s;
    }
  std::sort(loaded.begin(), loaded.end(),
            [](const std::pair<uint64_t, VoxelAccum>& a, const std::pair<uint64_t, VoxelAccum>& b) {
              return a.first < b.first;
            });
  const uint32_t nv = static_cast<uint32_t>(loaded.size());
  if (nv == 0) return Status::Ok;
  scan->keys.resize(nv);
  scan->pts.resize(size_t(nv) * 4);
  scan->logits.resize(size_t(nv) * kNumClasses);
  scan->labels.resize(nv);
  for (uint32_t i = 0; i < nv; ++i) {
    const VoxelAccum& a = loaded[i].second;
    scan->keys[i] = loaded[i].first;
    if (store_.tile_of(scan->keys[i]) == id) ++map_voxels_;
    int best = 0;
    for (int k = 0; k < 3; ++k) scan->pts[4 * i + k] = static_cast<float>(a.sum[k] / a.count);
    scan->pts[4 * i + 3] = 0.0f;
    for (int c = 0; c < kNumClasses; ++c) {
      const double p = a.prob[c] / a.count;
      scan->logits[size_t(i) * kNumClasses + c] = static_cast<float>(std::log(p + 1e-6));
      if (a.prob[c] > a.prob[best]) best = c;
    }
    scan->labels[i] = kitti_from_class(best);
  }
  return Status::Ok;
}

TileConfigs TiledStages::tile_configs(uint32_t nv) const {
  TileConfigs tc;
  tc.voxel = config_.voxel;
  tc.voxel.min_range = 0.0f;
  tc.voxel.max_range = 1e7f;
  tc.voxel.max_voxels = nv + 16;
  tc.voxel.max_columns = nv + 16;
  tc.cluster = cc0_;
  tc.cluster.max_instances = nv / std::max(1u, min_cluster_voxels_) + 1;  // every component the tile can hold
  tc.poles = pc0_;
  tc.poles.max_instances = nv / std::max(1u, pc0_.min_levels) + 1;
  tc.bytes = VoxelLayer::required_bytes(tc.voxel) +
             InstanceClustering::required_bytes(tc.cluster, tc.voxel.max_voxels) +
             (poles_on_ ? PoleExtraction::required_bytes(tc.poles, tc.voxel.max_voxels) : 0) + 4096;
  return tc;
}

// Binds the stages and builds the voxel layer over the scan, with each layer voxel's creator.
Status TiledStages::build_layer(const TileScan& scan, const TileConfigs& tc, TileLayer* tl) const {
  if (tl->layer.bind(tl->ws.arena, tc.voxel) != Status::Ok ||
      tl->clusters.bind(tl->ws.arena, tc.cluster, tc.voxel.max_voxels) != Status::Ok ||
      (poles_on_ && tl->poles.bind(tl->ws.arena, tc.poles, tc.voxel.max_voxels) != Status::Ok))
    return Status::InvalidArgument;
  tl->clusters.set_classes(&classes_);
  const uint32_t nv = scan.size();
  ScanView sv;
  sv.points = scan.pts.data();
  sv.stride = 4;
  sv.labels = scan.labels.data();
  sv.logits = scan.logits.data();
  sv.logit_dim = kNumClasses;
  sv.count = nv;
  const Status s = tl->layer.build(sv, nullptr);
  if (s != Status::Ok) return s;
  if (tl->layer.size() != nv) {
    tl->creator.assign(tl->layer.size(), UINT32_MAX);
    for (uint32_t j = 0; j < nv; ++j) {
      const uint32_t i = tl->layer.find(&scan.pts[4 * size_t(j)]);
      if (i != UINT32_MAX && tl->creator[i] == UINT32_MAX) tl->creator[i] = j;
    }
  }
  return Status::Ok;
}

// Clusters and (when on) pole chains of the layer; keeps as candidates those the tile owns (it holds
// their lowest voxel key).
Status TiledStages::collect_instances(uint64_t id, TileLayer* tl) {
  ClusterStats cs;
  Status s = tl->clusters.build(tl->layer, &cs);
  if (s != Status::Ok) return s;
  for (uint32_t k = 0; k < tl->clusters.size(); ++k) {
    Candidate c;
    c.key = tl->key_of_voxel(tl->clusters.instance(k).first_voxel);
    if (store_.tile_of(c.key) != id) continue;  // another tile's (it holds its lowest voxel)
    c.in = tl->clusters.instance(k);
    clustered_.push_back(c);
  }
  if (!poles_on_) return Status::Ok;
  PoleStats ps;
  s = tl->poles.build(tl->layer, &ps);
  if (s != Status::Ok) return s;
  for (uint32_t k = 0; k < tl->poles.size(); ++k) {
    Candidate c;
    c.key = tl->key_of_voxel(tl->poles.instance(k).first_voxel);
    if (store_.tile_of(c.key) != id) continue;
    c.in = tl->poles.instance(k);
    c.score = tl->poles.info(k).score;
    poles_.push_back(c);
  }
  return Status::Ok;
}

// The fields of the tile's new candidates, in one new chunk.
void TiledStages::fit_fields(const VoxelLayer& layer, size_t clustered_before, size_t poles_before) {
  if (clustered_.size() > clustered_before || poles_.size() > poles_before) fields_.emplace_back();
  for (size_t k = clustered_before; k < clustered_.size(); ++k) fitter_.fit(layer, &fields_, &clustered_[k]);
  for (size_t k = poles_before; k < poles_.size(); ++k) fitter_.fit(layer, &fields_, &poles_[k]);
}

// Refinement candidates: long-term structure, per cell the sum of the owned voxels' centroids.
void TiledStages::collect_refine(uint64_t id, const TileLayer& tl) {
  if (options_.refine_voxel <= 0.0f) return;
  std::unordered_map<uint64_t, size_t> slot;  // cell -> its candidate in refine_
  for (uint32_t i = 0; i < tl.layer.size(); ++i) {
    const Voxel& v = tl.layer.voxel(i);
    if (classes_.stability(v.label) < 1.0f) continue;
    const uint64_t vk = tl.key_of_voxel(i);
    if (store_.tile_of(vk) != id) continue;
    const uint64_t cell = voxel_key(v.centroid[0], v.centroid[1], v.centroid[2], options_.refine_voxel);
    const auto found = slot.emplace(cell, refine_.size());
    if (found.second) refine_.push_back({cell, vk, {0, 0, 0}, 0});
    RefineCandidate& c = refine_[found.first->second];
    c.voxel = std::min(c.voxel, vk);
    for (int k = 0; k < 3; ++k) c.sum[k] += double(v.centroid[k]);
    ++c.count;
  }
}

// The semantic tiles this map tile owns, paletted into one new chunk.
Status TiledStages::collect_semantic(uint64_t id, const VoxelLayer& layer) {
  if (options_.semantic_layer.cell <= 0.0f) return Status::Ok;
  std::unordered_map<uint64_t, bool> owned;
  auto keep = [&](int64_t fx, int64_t fy) { return owns_semantic_tile(id, fx, fy, &owned); };
  std::vector<uint32_t> sem_keys, sem_cells;
  build_semantic_layer(layer, options_.semantic_layer, &sem_keys, &sem_cells, keep);
  if (sem_keys.empty()) return Status::Ok;
  for (size_t k = 0; k < sem_keys.size(); ++k)
    semantic_.push_back({sem_keys[k], {uint32_t(semantic_chunks_.size()), uint32_t(k)}});
  SemanticChunk chunk;
  const Status ps = palette_semantic_layer(sem_cells, uint32_t(sem_keys.size()), options_.semantic_layer.tile_cells,
                                           &chunk.offsets, &chunk.palette, &chunk.cells);
  if (ps != Status::Ok) return ps;
  chunk.palette.shrink_to_fit();
  semantic_chunks_.push_back(std::move(chunk));
  return Status::Ok;
}

// Whether map tile `id` owns semantic tile (fx, fy): the first existing map tile (id order) it
// overlaps, with a voxel of slack for centroids rounded onto a border. Memoised in *owned.
bool TiledStages::owns_semantic_tile(uint64_t id, int64_t fx, int64_t fy,
                                     std::unordered_map<uint64_t, bool>* owned) const {
  if (tile_ == 0) return true;
  const double side = double(options_.semantic_layer.cell) * options_.semantic_layer.tile_cells;
  const double vs = vs_;
  const int32_t tile = tile_;
  const uint64_t k = (uint64_t(uint32_t(fx)) << 32) | uint32_t(fy);
  auto it = owned->find(k);
  if (it != owned->end()) return it->second;
  const int32_t ax = static_cast<int32_t>(floor_div(int64_t(std::floor((fx * side - vs) / vs)), tile));
  const int32_t bx = static_cast<int32_t>(floor_div(int64_t(std::floor(((fx + 1) * side + vs) / vs)), tile));
  const int32_t ay = static_cast<int32_t>(floor_div(int64_t(std::floor((fy * side - vs) / vs)), tile));
  const int32_t by = static_cast<int32_t>(floor_div(int64_t(std::floor(((fy + 1) * side + vs) / vs)), tile));
  uint64_t first = UINT64_MAX;
  for (int32_t x = ax; x <= bx && first == UINT64_MAX; ++x)
    for (int32_t y = ay; y <= by; ++y)
      if (has_tile(TileStore::tile_id(x, y))) {
        first = TileStore::tile_id(x, y);
        break;
      }
  return (*owned)[k] = first == id;
}

// Tiles come x-major: once a column of tiles is done, no later tile owns a voxel left of its right
// edge (less a voxel for rounding), so the refinement cells left of it are final.
void TiledStages::flush_finished_column(const std::vector<uint64_t>& tiles, size_t t) {
  const int32_t tx = TileStore::tile_x(tiles[t]);
  if (t + 1 < tiles.size() && TileStore::tile_x(tiles[t + 1]) != tx) flush_left_of(tx + 1);
}

void TiledStages::flush_left_of(int32_t tx_end) {
  if (tile_ > 0 && options_.refine_voxel > 0.0f) {
    const double edge = (double(tx_end) * tile_ - 1.0) * vs_;  // m, a voxel inside the columns' right edge
    const int64_t cell_x = static_cast<int64_t>(std::floor(edge / options_.refine_voxel)) + (1 << 20);
    if (cell_x > 0 && cell_x < (1 << 21)) flush_refine(uint64_t(cell_x) << 42);
  }
}

// Emits the refinement cells below `limit` (cell keys are x-major too): per cell the mean of its owned
// voxels' centroids over every tile, in cell order. Only a column's candidates wait. The mean, not one
// voxel of the cell: the first voxel in key order sat on the cell's low-x side, so a column's point
// was off its arc by up to a voxel, and ICP's pole rows (core/src/refine.cpp) pulled scans that way.
void TiledStages::flush_refine(uint64_t limit) {
  constexpr size_t kRefineChunkFloats = size_t(3) << 18;  // 3 MB
  std::vector<std::vector<float>>& refine_chunks = out_->refine;
  std::sort(refine_.begin(), refine_.end(), [](const RefineCandidate& a, const RefineCandidate& b) {
    return a.cell != b.cell ? a.cell < b.cell : a.voxel < b.voxel;
  });
  size_t k = 0;
  while (k < refine_.size() && refine_[k].cell < limit) {
    double sum[3] = {0, 0, 0};
    uint64_t count = 0;
    const uint64_t cell = refine_[k].cell;
    for (; k < refine_.size() && refine_[k].cell == cell; ++k) {
      for (int a = 0; a < 3; ++a) sum[a] += refine_[k].sum[a];
      count += refine_[k].count;
    }
    if (refine_chunks.empty() || refine_chunks.back().size() + 3 > kRefineChunkFloats) {
      refine_chunks.emplace_back();
      refine_chunks.back().reserve(kRefineChunkFloats);
    }
    for (int a = 0; a < 3; ++a) refine_chunks.back().push_back(float(sum[a] / double(count)));
    refine_floats_ += 3;
  }
  refine_.erase(refine_.begin(), refine_.begin() + k);
}

Status TiledStages::finish(MapBuildStats* st, const Progress& progress) {
  flush_refine(UINT64_MAX);
  std::vector<RefineCandidate>().swap(refine_);
  if (map_voxels_ == 0) return Status::InvalidInput;
  st->map_voxels = static_cast<uint32_t>(map_voxels_);
  const std::vector<Candidate> found = apply_capacities(st);
  const uint32_t ni = static_cast<uint32_t>(found.size());
  write_instances(found, st);
  st->seconds_cluster = seconds_cluster_;
  st->seconds_fields = seconds_fields_;
  if (progress) progress("clustered instances", ni, ni);
  // Refinement points: already final, in cell order, in out_->refine's chunks.
  st->refine_points = static_cast<uint32_t>(refine_floats_ / 3);
  return write_semantic_layer(st);
}

// Whole-map capacities with the stages' own rules, then discovery (lowest voxel key) order: the
// clustered instances, then the poles.
std::vector<Candidate> TiledStages::apply_capacities(MapBuildStats* st) {
  st->instances_dropped += keep_best(&clustered_, options_.max_instances, [](const Candidate& a, const Candidate& b) {
    return a.in.point_count != b.in.point_count ? a.in.point_count > b.in.point_count : a.key < b.key;
  });
  st->instances_dropped += keep_best(&poles_, options_.max_pole_instances, [](const Candidate& a, const Candidate& b) {
    if (a.score != b.score) return a.score > b.score;
    if (a.in.point_count != b.in.point_count) return a.in.point_count > b.in.point_count;
    return a.key < b.key;
  });
  auto by_key = [](const Candidate& a, const Candidate& b) { return a.key < b.key; };
  std::sort(clustered_.begin(), clustered_.end(), by_key);
  std::sort(poles_.begin(), poles_.end(), by_key);
  std::vector<Candidate> found = std::move(clustered_);
  found.insert(found.end(), poles_.begin(), poles_.end());
  st->pole_instances = static_cast<uint32_t>(poles_.size());
  std::vector<Candidate>().swap(poles_);
  st->instances = static_cast<uint32_t>(found.size());
  return found;
}

// The instances' records and their field rows in map order (rows of dropped instances are left out).
void TiledStages::write_instances(const std::vector<Candidate>& found, MapBuildStats* st) {
  const uint32_t ni = static_cast<uint32_t>(found.size());
  std::vector<std::pair<uint32_t, uint32_t>> rows(ni);
  for (uint32_t i = 0; i < ni; ++i) rows[i] = {found[i].chunk, found[i].row};
  gather_rows(&fields_, &FieldChunk::mean, size_t(G_) * kNumClasses, rows, &out_->mean);
  gather_rows(&fields_, &FieldChunk::var, G_, rows, &out_->var);
  std::vector<FieldChunk>().swap(fields_);
  out_->instances.resize(ni);
  out_->centroids.resize(size_t(ni) * 3);
  out_->labels.resize(ni);
  for (uint32_t i = 0; i < ni; ++i) {
    const Candidate& c = found[i];
    MapInstance& mi = out_->instances[i];
    std::memset(&mi, 0, sizeof(mi));
    for (int k = 0; k < 3; ++k) mi.centroid[k] = out_->centroids[3 * i + k] = c.in.centroid[k];
    mi.stability = c.in.stability;
    mi.point_count = c.in.point_count;
    mi.mean_min = c.scales.mean_min;
    mi.mean_step = c.scales.mean_step;
    mi.var_min = c.scales.var_min;
    mi.var_step = c.scales.var_step;
    mi.label = out_->labels[i] = c.in.label;
    st->instances_by_class[c.in.label]++;
    st->field_points_dropped += c.field_points_dropped;
    if (!c.fit_ok) st->fields_failed++;
  }
}

// The semantic layer in key order, paletted tile by tile (a tile's palette depends on it alone), then
// the neighbour masks, which read across tile edges and so come once the layer is whole.
Status TiledStages::write_semantic_layer(MapBuildStats* st) {
  const size_t semantic_tile_size = size_t(options_.semantic_layer.tile_cells) * options_.semantic_layer.tile_cells;
  MapContent* out = out_;
  std::sort(semantic_.begin(), semantic_.end());
  out->semantic_keys.reserve(semantic_.size());
  out->semantic_cells.reserve(semantic_.size() * semantic_tile_size);
  if (!semantic_.empty()) out->semantic_palette_offsets.reserve(semantic_.size() + 1);
  for (const auto& [key, at] : semantic_) {
    const SemanticChunk& chunk = semantic_chunks_[at.first];
    const uint32_t k = at.second;
    if (out->semantic_palette_offsets.empty()) out->semantic_palette_offsets.push_back(0);
    out->semantic_keys.push_back(key);
    out->semantic_palette.insert(out->semantic_palette.end(), chunk.palette.begin() + chunk.offsets[k],
                                 chunk.palette.begin() + chunk.offsets[k + 1]);
    out->semantic_palette_offsets.push_back(static_cast<uint32_t>(out->semantic_palette.size()));
    out->semantic_cells.insert(out->semantic_cells.end(), chunk.cells.begin() + size_t(k) * semantic_tile_size,
                               chunk.cells.begin() + size_t(k + 1) * semantic_tile_size);
  }
  std::vector<SemanticChunk>().swap(semantic_chunks_);
  const Status ns =
      add_semantic_neighbours(out->semantic_keys, options_.semantic_layer.tile_cells, &out->semantic_palette_offsets,
                              &out->semantic_palette, &out->semantic_cells, &out->semantic_neighbours);
  if (ns != Status::Ok) return ns;
  out->semantic_palette.shrink_to_fit();
  st->semantic_tiles = static_cast<uint32_t>(out->semantic_keys.size());
  return Status::Ok;
}

}  // namespace

// Per tile in id order (x-major) the stages over the tile and its halo, then the whole-map capacities
// and orders.
Status build_map_content(TileStore& store, const LocalizerConfig& config, const ClassTable& classes,
                         const MapBuildConfig& options, MapContent* out, MapBuildStats* st, const Progress& progress) {
  *out = MapContent();
  TiledStages stages(store, config, classes, options, out);
  if (!stages.bind()) return Status::InvalidArgument;
  const std::vector<uint64_t> tiles = store.tile_ids();
  for (size_t t = 0; t < tiles.size(); ++t) {
    const Status s = stages.add_tile(tiles, t, progress);
    if (s != Status::Ok) return s;
  }
  return stages.finish(st, progress);
}

// Per block (x-major) the store filled with the block and its halo, the stages over the block's tiles
// (id order); the refinement cells left of a block column once it is done, then the whole-map
// capacities and orders.
Status build_map_content_blocked(const std::vector<MapBlock>& blocks, const std::vector<uint64_t>& tiles,
                                 int32_t block_tiles, const FillBlock& fill, TileStore& store,
                                 const LocalizerConfig& config, const ClassTable& classes,
                                 const MapBuildConfig& options, MapContent* out, MapBuildStats* st,
                                 const Progress& progress) {
  *out = MapContent();
  TiledStages stages(store, config, classes, options, out, &tiles);
  if (!stages.bind()) return Status::InvalidArgument;
  size_t done = 0;
  for (size_t b = 0; b < blocks.size(); ++b) {
    Status s = fill(blocks[b], &store);
    for (size_t t = 0; s == Status::Ok && t < blocks[b].tiles.size(); ++t) s = stages.run_tile(blocks[b].tiles[t]);
    if (s != Status::Ok) return s;
    store.clear();
    if (b + 1 < blocks.size() && blocks[b + 1].bx != blocks[b].bx)
      stages.flush_left_of((blocks[b].bx + 1) * block_tiles);
    done += blocks[b].tiles.size();
    if (progress) progress("tiles", done, tiles.size());
  }
  return stages.finish(st, progress);
}

}  // namespace gsf::mapping
