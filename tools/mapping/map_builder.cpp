#include "mapping/map_builder.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <memory>

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
#include "mapping/map_writer.h"

namespace gsf::mapping {
namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// Key of the map-local voxel holding p: 21 bits per axis, so 2^20 voxels either side of the origin
// (419 km at 0.4 m) before keys wrap; add_scan keeps poses within kMaxMapLocalCoordinate of it.
uint64_t voxel_key(const Eigen::Vector3d& p, double size) {
  const int64_t x = static_cast<int64_t>(std::floor(p.x() / size)) + (1 << 20);
  const int64_t y = static_cast<int64_t>(std::floor(p.y() / size)) + (1 << 20);
  const int64_t z = static_cast<int64_t>(std::floor(p.z() / size)) + (1 << 20);
  return (uint64_t(x & 0x1FFFFF) << 42) | (uint64_t(y & 0x1FFFFF) << 21) | uint64_t(z & 0x1FFFFF);
}

// Per-scan voxel capacity of the builder (the localizer's default before the 16 MiB budget; 14 MB of
// host memory).
constexpr uint32_t kMapScanMaxVoxels = 100000;

// Arena-backed stage objects sized for a whole map.
struct Workspace {
  std::vector<uint64_t> memory;
  Arena arena;
  explicit Workspace(size_t bytes) : memory(bytes / 8 + 2), arena(memory.data(), memory.size() * 8) {}
};

}  // namespace

MapBuilder::MapBuilder(const MapBuildConfig& config)
    : config_(config.stages), classes_(label_set(config.stages)), options_(config), georef_(local_georeference()) {
  if (config_.classes) config_.classes = &classes_;
  // Map scans are voxelised on the host before accumulation: at least kMapScanMaxVoxels per scan, so the
  // on-board default (voxel.max_voxels 32k, sized for the 16 MiB workspace) never truncates a map scan.
  config_.voxel.max_voxels = std::max(config_.voxel.max_voxels, kMapScanMaxVoxels);
  scan_arena_.resize(VoxelLayer::required_bytes(config_.voxel) + 64);
  georef_valid_ = set_frame_name(&georef_, options_.frame.c_str());
  for (int k = 0; k < 3; ++k) georef_.origin[k] = options_.origin[k];
  georef_valid_ = georef_valid_ && valid_georeference(georef_);
  origin_fixed_ = options_.origin_given;
}

Status MapBuilder::add_scan(const ScanView& scan, const Eigen::Isometry3d& frame_T_lidar) {
  const auto t0 = std::chrono::steady_clock::now();
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
  const Eigen::Isometry3d map_T_lidar = to_map_local(georef_, frame_T_lidar);
  if (map_T_lidar.translation().cwiseAbs().maxCoeff() > kMaxMapLocalCoordinate) return Status::InvalidInput;
  void* base = reinterpret_cast<void*>((reinterpret_cast<uintptr_t>(scan_arena_.data()) + 15) & ~uintptr_t(15));
  Arena arena(base, scan_arena_.size() - 16);
  VoxelLayer layer;
  Status s = layer.bind(arena, config_.voxel);
  if (s != Status::Ok) return s;
  layer.set_classes(config_.classes);
  s = layer.build(scan, nullptr);
  if (s != Status::Ok && s != Status::CapacityExceeded) return s;
  const double vs = config_.voxel.voxel_size;
  for (uint32_t i = 0; i < layer.size(); ++i) {
    const Voxel& v = layer.voxel(i);
    const Eigen::Vector3d p = map_T_lidar * Eigen::Vector3d(v.centroid[0], v.centroid[1], v.centroid[2]);
    Accum& a = voxels_[voxel_key(p, vs)];
    for (int k = 0; k < 3; ++k) a.sum[k] += p[k] * v.count;
    for (int c = 0; c < kNumClasses; ++c) a.prob[c] += double(v.prob[c]) * v.count;
    a.count += v.count;
  }
  stats_.scans++;
  stats_.points += scan.count;
  stats_.seconds_accumulate += seconds_since(t0);
  return Status::Ok;
}

Status MapBuilder::build(std::vector<uint64_t>* blob, size_t* bytes_out, MapBuildStats* stats_out,
                         const Progress& progress) {
  *bytes_out = 0;
  MapBuildStats st = stats_;
  st.georef = georef_;
  // Deterministic voxel order (unordered_map iteration order is not).
  std::vector<uint64_t> keys;
  keys.reserve(voxels_.size());
  for (const auto& kv : voxels_) keys.push_back(kv.first);
  std::sort(keys.begin(), keys.end());
  const uint32_t nv = static_cast<uint32_t>(keys.size());
  st.map_voxels = nv;
  if (nv == 0) return Status::InvalidInput;

  // The map as one "scan" of voxel centroids with log-probabilities as logits: the same VoxelLayer then
  // reproduces the accumulated voxels (same grid, one point each) and the localizer's stages apply.
  std::vector<float> pts(size_t(nv) * 4), logits(size_t(nv) * kNumClasses);
  std::vector<uint32_t> labels(nv);
  for (uint32_t i = 0; i < nv; ++i) {
    const Accum& a = voxels_[keys[i]];
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
  VoxelConfig vc = config_.voxel;
  vc.min_range = 0.0f;
  vc.max_range = 1e7f;
  vc.max_voxels = nv + 16;
  vc.max_columns = nv + 16;
  ClusterConfig cc = config_.cluster;
  cc.max_instances = options_.max_instances;
  cc.instance_classes = classes_.instance_classes();
  if (!config_.classes) cc.instance_classes = config_.cluster.instance_classes;
  PoleConfig pc = effective_pole_config(config_);
  pc.max_instances = options_.max_pole_instances;
  const bool poles_on = (pc.pole_hosts | pc.trunk_hosts) != 0;
  const auto t_cluster = std::chrono::steady_clock::now();
  Workspace ws(VoxelLayer::required_bytes(vc) + InstanceClustering::required_bytes(cc, vc.max_voxels) +
               (poles_on ? PoleExtraction::required_bytes(pc, vc.max_voxels) : 0) + 4096);
  VoxelLayer layer;  // reads the accumulated voxels' library classes as SemanticKITTI ids (below)
  InstanceClustering clusters;
  PoleExtraction poles;
  if (layer.bind(ws.arena, vc) != Status::Ok || clusters.bind(ws.arena, cc, vc.max_voxels) != Status::Ok ||
      (poles_on && poles.bind(ws.arena, pc, vc.max_voxels) != Status::Ok))
    return Status::InvalidArgument;
  clusters.set_classes(&classes_);
  ScanView sv;
  sv.points = pts.data();
  sv.stride = 4;
  sv.labels = labels.data();
  sv.logits = logits.data();
  sv.logit_dim = kNumClasses;
  sv.count = nv;
  Status s = layer.build(sv, nullptr);
  if (s != Status::Ok) return s;
  ClusterStats cs;
  s = clusters.build(layer, &cs);
  if (s != Status::Ok && s != Status::CapacityExceeded) return s;
  st.instances_dropped += cs.dropped_capacity;
  // All map instances: the clustered ones, then the geometric poles / trunks in discovery order.
  std::vector<Instance> found(clusters.instances(), clusters.instances() + clusters.size());
  if (poles_on) {
    PoleStats ps;
    s = poles.build(layer, &ps);
    if (s != Status::Ok && s != Status::CapacityExceeded) return s;
    st.instances_dropped += ps.dropped_capacity;
    found.insert(found.end(), poles.instances(), poles.instances() + poles.size());
    st.pole_instances = poles.size();
  }
  const uint32_t ni = static_cast<uint32_t>(found.size());
  st.instances = ni;
  st.seconds_cluster = seconds_since(t_cluster);
  if (progress) progress("clustered instances", ni, ni);

  // Fields: fit each instance's GP on its neighbourhood, probe the canonical grid.
  const auto t_fields = std::chrono::steady_clock::now();
  const FieldConfig& fc = config_.field;
  const uint32_t M = fc.inducing_points, G = grid_points(fc), D = kNumClasses;
  const uint32_t max_pts = options_.max_field_points;
  Workspace fws(FieldSolver::required_bytes(fc, max_pts) + 4096);
  FieldSolver solver;
  if (solver.bind(fws.arena, fc, max_pts) != Status::Ok) return Status::InvalidArgument;
  std::vector<MapInstance> instances(ni);
  // Each field's inducing inputs and weights are needed only to probe its grid (the map stores the grid).
  std::vector<float> inputs(size_t(M) * 3), alpha(size_t(M) * D);
  std::vector<float> mean(size_t(ni) * G * D, 0.0f), var(size_t(ni) * G, fc.signal_variance);
  std::vector<uint32_t> ids(max_pts);
  std::vector<float> xyz(size_t(max_pts) * 3), targets(size_t(max_pts) * D), chol(size_t(M) * M), grid(size_t(G) * 3);
  std::vector<uint8_t> gl(max_pts);
  std::vector<float> centroids(size_t(ni) * 3);
  std::vector<uint8_t> inst_labels(ni);
  make_probe_grid(fc, 0.0f, grid.data());
  for (uint32_t i = 0; i < ni; ++i) {
    const Instance& in = found[i];
    MapInstance& mi = instances[i];
    std::memset(&mi, 0, sizeof(mi));
    for (int k = 0; k < 3; ++k) mi.centroid[k] = centroids[3 * i + k] = in.centroid[k];
    mi.stability = in.stability;
    mi.point_count = in.point_count;
    mi.label = inst_labels[i] = in.label;
    st.instances_by_class[in.label]++;
    // The same per-instance fit as the localizer's query fields (gaussian_field.h).
    const FieldGather gather{max_pts, ids.data(), xyz.data(), targets.data(), gl.data()};
    uint32_t m = 0, got = 0, total = 0;
    float* in_i = inputs.data();
    float* al_i = alpha.data();
    const Status fit =
        fit_instance_field(solver, layer, in.centroid, gather, in_i, al_i, chol.data(), &m, &got, &total);
    st.field_points_dropped += total - got;
    if (fit == Status::Ok) {
      FieldView f{in_i, al_i, m};
      solver.probe(f, chol.data(), grid.data(), G, mean.data() + size_t(i) * G * D, var.data() + size_t(i) * G,
                   nullptr);
    } else {
      st.fields_failed++;
    }
    if (progress && (i % 200 == 0 || i + 1 == ni)) progress("fields", i + 1, ni);
  }
  st.seconds_fields = seconds_since(t_fields);

  // Triangles and the hash index over all map instances.
  const auto t_tri = std::chrono::steady_clock::now();
  TriangleConfig tc = config_.triangle;
  tc.neighbours = tc.map_k();  // the map's K (TriangleConfig::map_neighbours)
  tc.map_neighbours = 0;
  const uint64_t tri_cap = std::min<uint64_t>(uint64_t(ni) * tc.neighbours * (tc.neighbours - 1) / 2 + 16, 1u << 30);
  tc.max_triangles = static_cast<uint32_t>(tri_cap);
  Workspace tws(TriangleBuilder::required_bytes(tc, ni + 1) + size_t(tri_cap) * sizeof(Triangle) + 4096);
  TriangleBuilder tb;
  FixedVector<Triangle> tris;
  if (tb.bind(tws.arena, tc, ni + 1) != Status::Ok || !tris.bind(tws.arena, tc.max_triangles))
    return Status::InvalidArgument;
  s = tb.build(centroids.data(), 3, inst_labels.data(), ni, tris);
  if (s != Status::Ok) return s;
  const uint32_t nt = tris.size();
  std::vector<uint64_t> ikeys(nt + 1), scratch(nt + 1);
  std::vector<uint32_t> offsets(nt + 2), entries(nt + 1);
  uint32_t key_count = 0;
  build_triangle_index(tris.data(), nt, tc.side_bin, ikeys.data(), offsets.data(), entries.data(), &key_count,
                       scratch.data());
  st.triangles = nt;
  st.index_keys = key_count;
  st.seconds_triangles = seconds_since(t_tri);
  if (progress) progress("triangles", nt, nt);

  // Refinement layer: long-term structure downsampled to refine_voxel.
  std::vector<float> refine;
  if (options_.refine_voxel > 0.0f) {
    std::unordered_map<uint64_t, std::pair<Eigen::Vector3d, uint32_t>> cells;
    std::vector<uint64_t> order;
    for (uint32_t i = 0; i < layer.size(); ++i) {
      const Voxel& v = layer.voxel(i);
      if (classes_.stability(v.label) < 1.0f) continue;
      const Eigen::Vector3d p(v.centroid[0], v.centroid[1], v.centroid[2]);
      const uint64_t k = voxel_key(p, options_.refine_voxel);
      auto it = cells.find(k);
      if (it == cells.end()) {
        cells.emplace(k, std::make_pair(p, uint32_t(v.label)));
        order.push_back(k);
      }
    }
    std::sort(order.begin(), order.end());
    for (uint64_t k : order) {
      const auto& c = cells[k];
      refine.insert(refine.end(), {float(c.first.x()), float(c.first.y()), float(c.first.z())});
    }
  }
  st.refine_points = static_cast<uint32_t>(refine.size() / 3);

  // Semantic layer for whole-scan verification of pose hypotheses.
  std::vector<uint32_t> sem_keys, sem_cells;
  if (options_.semantic_layer.cell > 0.0f) build_semantic_layer(layer, options_.semantic_layer, &sem_keys, &sem_cells);
  st.semantic_tiles = static_cast<uint32_t>(sem_keys.size());

  MapContents view;
  view.georef = georef_;
  view.params = map_params_from(config_);
  view.counts.instances = ni;
  view.counts.triangles = nt;
  view.counts.index_keys = key_count;
  view.counts.road_length_m = options_.road_length_m;
  view.counts.semantic_tiles = st.semantic_tiles;
  if (st.semantic_tiles > 0) {
    view.params.semantic_cell = options_.semantic_layer.cell;
    view.params.semantic_tile_cells = options_.semantic_layer.tile_cells;
  }
  view.semantic_tile_keys = sem_keys.empty() ? nullptr : sem_keys.data();
  view.semantic_cells = sem_cells.empty() ? nullptr : sem_cells.data();
  for (int k = 0; k < 3; ++k) {
    view.counts.bounds_min[k] = 1e30f;
    view.counts.bounds_max[k] = -1e30f;
  }
  for (uint32_t i = 0; i < ni; ++i)
    for (int k = 0; k < 3; ++k) {
      view.counts.bounds_min[k] = std::min(view.counts.bounds_min[k], instances[i].centroid[k]);
      view.counts.bounds_max[k] = std::max(view.counts.bounds_max[k], instances[i].centroid[k]);
    }
  if (ni == 0)
    for (int k = 0; k < 3; ++k) view.counts.bounds_min[k] = view.counts.bounds_max[k] = 0.0f;
  view.instances = instances.data();
  view.grid_mean = mean.data();
  view.grid_var = var.data();
  view.triangles = tris.data();
  view.index_keys = ikeys.data();
  view.index_offsets = offsets.data();
  view.index_entries = entries.data();
  view.refine_xyz = refine.empty() ? nullptr : refine.data();
  view.refine_points = st.refine_points;
  view.refine_cell = config_.refine.cell;
  size_t written = 0;
  s = write_compact_map(view, blob, &written, &st.refine_tiles);
  if (s != Status::Ok) return s;
  *bytes_out = written;
  st.bytes = written;
  if (stats_out) *stats_out = st;
  return Status::Ok;
}

}  // namespace gsf::mapping
