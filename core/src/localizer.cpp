#include "gsf/localizer.h"

#include <algorithm>
#include <cmath>
#include <new>

#include "gsf/bounded_hash_map.h"
#include "gsf/fixed_vector.h"
#include "gsf/gaussian_field.h"
#include "gsf/instance_clustering.h"
#include "gsf/max_clique.h"
#include "gsf/pose_solver.h"
#include "gsf/refine.h"
#include "gsf/triangle.h"
#include "gsf/triangle_index.h"
#include "gsf/voxel_layer.h"
#include "gsf/wasserstein.h"

namespace gsf {
namespace {

constexpr double kTwoPi = 6.283185307179586;

struct CorrespondenceAcc {
  uint32_t query, map;
  float weight;   // best GSF similarity seen for this pair (1 without GSF)
  uint32_t votes; // surviving triangle matches that produced it
};

}  // namespace

struct Localizer::Impl {
  VoxelLayer voxels;
  InstanceClustering clusters;
  FieldSolver solver;
  TriangleBuilder triangle_builder;
  FixedVector<Triangle> triangles;
  FixedVector<TriangleMatch> matches;
  MaxCliqueSolver clique_solver;
  Refiner refiner;
  ConsistencyGraph graph;
  FixedVector<uint32_t> clique;
  BoundedHashMap<uint32_t> probe_slot;   // (query instance, yaw bin) -> cache slot
  BoundedHashMap<float> similarity;      // (query instance, map instance, yaw bin) -> omega
  BoundedHashMap<uint32_t> corr_index;   // (query instance, map instance) -> correspondence id
  TriangleIndexView index;

  // Query instances and their fields.
  float* centroids = nullptr;   // I x 3
  uint8_t* labels = nullptr;    // I
  float* q_inputs = nullptr;    // I x M x 3
  float* q_alpha = nullptr;     // I x M x D
  float* q_chol = nullptr;      // I x M x M
  uint32_t* q_m = nullptr;      // I (0: no field)
  // Gather scratch for one field fit.
  uint32_t* gather_ids = nullptr;
  float* gather_xyz = nullptr;
  float* gather_targets = nullptr;
  uint8_t* gather_labels = nullptr;
  // Probe cache.
  float* grid = nullptr;        // G x 3
  float* probe_mean = nullptr;  // (slots + 1) x G x D; the last slot is scratch when the cache is full
  float* probe_var = nullptr;   // (slots + 1) x G
  uint32_t probe_used = 0;
  float weights[kNumClasses];
  // Correspondences.
  CorrespondenceAcc* corr = nullptr;  // candidates (capacity corr_capacity)
  uint32_t corr_count = 0;
  uint32_t corr_capacity = 0;
  uint32_t* order = nullptr;          // selection scratch (corr_capacity)
  float* a = nullptr;                 // C x 3 query positions
  float* b = nullptr;                 // C x 3 map positions
  float* w = nullptr;                 // C weights
  float* sub_a = nullptr;             // C x 3 (clique / disagreeing subsets)
  float* sub_b = nullptr;
  float* sub_w = nullptr;
  float* tls_weights = nullptr;       // C
  uint8_t* mask = nullptr;            // C
  uint8_t* in_clique = nullptr;       // C: membership in the answer's clique
  uint32_t selected = 0;              // correspondences given to the clique in the last call
};

// The one layout of the workspace: run on a counting arena by required_bytes and on the caller's
// buffer by init, so the two can never disagree.
static Status bind_workspace(Arena& ar, const LocalizerConfig& config, Localizer::Impl& im) {
  const uint32_t I = config.cluster.max_instances, M = config.field.inducing_points, G = grid_points(config.field);
  const uint32_t C = config.match.max_correspondences, P = config.match.max_field_points;
  const uint32_t corr_cap = config.match.max_triangle_matches < 65536 ? config.match.max_triangle_matches : 65536;
  if (im.voxels.bind(ar, config.voxel) != Status::Ok) return Status::InvalidArgument;
  if (im.clusters.bind(ar, config.cluster, config.voxel.max_voxels) != Status::Ok) return Status::InvalidArgument;
  if (im.solver.bind(ar, config.field, P) != Status::Ok) return Status::InvalidArgument;
  if (im.triangle_builder.bind(ar, config.triangle, I) != Status::Ok) return Status::InvalidArgument;
  im.triangles.bind(ar, config.triangle.max_triangles);
  im.matches.bind(ar, config.match.max_triangle_matches);
  if (im.clique_solver.bind(ar, C) != Status::Ok || im.graph.bind(ar, C) != Status::Ok) return Status::InvalidArgument;
  im.clique.bind(ar, C);
  im.probe_slot.bind(ar, config.match.probe_cache_slots);
  im.similarity.bind(ar, config.match.similarity_cache_slots);
  im.corr_index.bind(ar, corr_cap);
  im.centroids = ar.allocate<float>(size_t(I) * 3);
  im.labels = ar.allocate<uint8_t>(I);
  im.q_inputs = ar.allocate<float>(size_t(I) * M * 3);
  im.q_alpha = ar.allocate<float>(size_t(I) * M * kNumClasses);
  im.q_chol = ar.allocate<float>(size_t(I) * M * M);
  im.q_m = ar.allocate<uint32_t>(I);
  im.gather_ids = ar.allocate<uint32_t>(P);
  im.gather_xyz = ar.allocate<float>(size_t(P) * 3);
  im.gather_targets = ar.allocate<float>(size_t(P) * kNumClasses);
  im.gather_labels = ar.allocate<uint8_t>(P);
  im.grid = ar.allocate<float>(size_t(G) * 3);
  im.probe_mean = ar.allocate<float>(size_t(config.match.probe_cache_slots + 1) * G * kNumClasses);
  im.probe_var = ar.allocate<float>(size_t(config.match.probe_cache_slots + 1) * G);
  im.corr = ar.allocate<CorrespondenceAcc>(corr_cap);
  im.corr_capacity = corr_cap;
  im.order = ar.allocate<uint32_t>(corr_cap);
  im.a = ar.allocate<float>(size_t(C) * 3);
  im.b = ar.allocate<float>(size_t(C) * 3);
  im.sub_a = ar.allocate<float>(size_t(C) * 3);
  im.sub_b = ar.allocate<float>(size_t(C) * 3);
  im.w = ar.allocate<float>(C);
  im.sub_w = ar.allocate<float>(C);
  im.tls_weights = ar.allocate<float>(C);
  im.mask = ar.allocate<uint8_t>(C);
  im.in_clique = ar.allocate<uint8_t>(C);
  if (config.refine.enabled && im.refiner.bind(ar, config.refine) != Status::Ok) return Status::InvalidArgument;
  if (ar.overflowed()) return Status::BufferTooSmall;
  return Status::Ok;
}

Localizer::Budget Localizer::budget(const LocalizerConfig& c) {
  Budget b{};
  if (validate(c) != Status::Ok) return b;
  const uint32_t I = c.cluster.max_instances, M = c.field.inducing_points, G = grid_points(c.field);
  const uint32_t C = c.match.max_correspondences, P = c.match.max_field_points;
  const uint32_t corr_cap = c.match.max_triangle_matches < 65536 ? c.match.max_triangle_matches : 65536;
  auto bytes = [](auto&& bind) { Arena a; bind(a); return a.used(); };
  b.voxel = VoxelLayer::required_bytes(c.voxel);
  b.cluster = InstanceClustering::required_bytes(c.cluster, c.voxel.max_voxels);
  b.field = FieldSolver::required_bytes(c.field, P) + bytes([&](Arena& a) {
    a.allocate<float>(size_t(I) * M * 3); a.allocate<float>(size_t(I) * M * kNumClasses);
    a.allocate<float>(size_t(I) * M * M); a.allocate<uint32_t>(I); a.allocate<uint32_t>(P);
    a.allocate<float>(size_t(P) * 3); a.allocate<float>(size_t(P) * kNumClasses); a.allocate<uint8_t>(P);
  });
  b.triangle = TriangleBuilder::required_bytes(c.triangle, I) + bytes([&](Arena& a) {
    FixedVector<Triangle> t; t.bind(a, c.triangle.max_triangles);
    a.allocate<float>(size_t(I) * 3); a.allocate<uint8_t>(I);
  });
  b.match = bytes([&](Arena& a) { FixedVector<TriangleMatch> m; m.bind(a, c.match.max_triangle_matches); });
  b.gsf_cache = bytes([&](Arena& a) {
    BoundedHashMap<uint32_t> p; p.bind(a, c.match.probe_cache_slots);
    BoundedHashMap<float> s; s.bind(a, c.match.similarity_cache_slots);
    a.allocate<float>(size_t(G) * 3);
    a.allocate<float>(size_t(c.match.probe_cache_slots + 1) * G * kNumClasses);
    a.allocate<float>(size_t(c.match.probe_cache_slots + 1) * G);
  });
  b.correspondence = bytes([&](Arena& a) {
    BoundedHashMap<uint32_t> h; h.bind(a, corr_cap);
    a.allocate<CorrespondenceAcc>(corr_cap); a.allocate<uint32_t>(corr_cap);
    for (int k = 0; k < 4; ++k) a.allocate<float>(size_t(C) * 3);
    for (int k = 0; k < 3; ++k) a.allocate<float>(C);
    a.allocate<uint8_t>(C); a.allocate<uint8_t>(C);
  });
  b.clique = MaxCliqueSolver::required_bytes(C) + ConsistencyGraph::required_bytes(C) +
             bytes([&](Arena& a) { FixedVector<uint32_t> v; v.bind(a, C); });
  b.refine = c.refine.enabled ? Refiner::required_bytes(c.refine) : 0;
  b.total = required_bytes(c);
  const size_t parts = b.voxel + b.cluster + b.field + b.triangle + b.match + b.gsf_cache + b.correspondence + b.clique + b.refine;
  b.other = b.total > parts ? b.total - parts : 0;  // Impl object and alignment padding
  return b;
}

size_t Localizer::required_bytes(const LocalizerConfig& config) {
  if (validate(config) != Status::Ok) return 0;
  Arena counting;
  counting.allocate_bytes(sizeof(Impl), alignof(Impl) < 16 ? 16 : alignof(Impl));
  Impl scratch;
  if (bind_workspace(counting, config, scratch) != Status::Ok) return 0;
  return counting.used();
}

Status Localizer::init(const LocalizerConfig& config, const MapView& map, void* buffer, size_t bytes, Clock* clock) {
  initialized_ = false;
  impl_ = nullptr;
  Status s = validate(config);
  if (s != Status::Ok) return s;
  s = check_map_params(config, map.params);
  if (s != Status::Ok) return s;
  if ((map.instances == nullptr && map.counts.instances > 0) || map.index_offsets == nullptr) return Status::InvalidArgument;
  if (buffer == nullptr) return Status::InvalidArgument;
  if (bytes < required_bytes(config)) return Status::BufferTooSmall;
  config_ = config;
  map_ = map;
  clock_ = clock;
  arena_ = Arena(buffer, bytes);
  void* mem = arena_.allocate_bytes(sizeof(Impl), alignof(Impl) < 16 ? 16 : alignof(Impl));
  if (!mem) return Status::BufferTooSmall;
  Impl& im = *new (mem) Impl();
  s = bind_workspace(arena_, config, im);
  if (s != Status::Ok) return s;
  if (config.refine.enabled) {
    if (map.counts.refine_points > config.refine.max_map_points) return Status::CapacityExceeded;
    s = im.refiner.set_map(map.refine_points, map.counts.refine_points);
    if (s != Status::Ok) return s;
  }
  stability_weights(im.weights);
  im.index.keys = map.index_keys;
  im.index.offsets = map.index_offsets;
  im.index.entries = map.index_entries;
  im.index.key_count = map.counts.index_keys;
  im.index.entry_count = map.counts.triangles;
  impl_ = &im;
  initialized_ = true;
  return Status::Ok;
}

namespace {

uint64_t now(Clock* c) { return c ? c->now_ns() : 0; }

// GSF similarity omega in [0, 1] between query instance qi (probed on the map's canonical grid rotated
// into the query frame by the yaw hypothesis) and map instance mi, cached per (qi, mi, yaw bin).
float field_similarity(Localizer::Impl& im, const LocalizerConfig& cfg, const MapView& map, uint32_t qi, uint32_t mi,
                       uint32_t yaw_bin) {
  const uint64_t skey = (uint64_t(qi) << 44) | (uint64_t(yaw_bin) << 32) | mi;
  if (const float* cached = im.similarity.find(skey)) return *cached;
  float omega = 0.0f;
  if (im.q_m[qi] > 0) {
    const uint32_t G = grid_points(cfg.field), M = cfg.field.inducing_points;
    const uint64_t pkey = (uint64_t(qi) << 32) | yaw_bin;
    uint32_t slot;
    bool fresh = false;
    uint32_t* ps = im.probe_slot.find(pkey);
    if (ps) {
      slot = *ps;
    } else {
      ps = im.probe_slot.find_or_insert(pkey);
      slot = ps ? im.probe_used++ : cfg.match.probe_cache_slots;  // full cache: compute into scratch
      if (ps) *ps = slot;
      fresh = true;
    }
    float* mean = im.probe_mean + size_t(slot) * G * kNumClasses;
    float* var = im.probe_var + size_t(slot) * G;
    if (fresh) {
      // Map grid offsets g (map frame) are R^T g = Rz(-yaw) g in the query frame.
      const float yaw = static_cast<float>(kTwoPi * yaw_bin / cfg.match.yaw_bins);
      make_probe_grid(cfg.field, -yaw, im.grid);
      FieldView f;
      f.inputs = im.q_inputs + size_t(qi) * M * 3;
      f.alpha = im.q_alpha + size_t(qi) * M * kNumClasses;
      f.m = im.q_m[qi];
      im.solver.probe(f, im.q_chol + size_t(qi) * M * M, im.grid, G, mean, var, nullptr);
    }
    const ObservedW2 r = w2_squared_diag_observed(mean, var, map.grid_mean + size_t(mi) * G * kNumClasses,
                                                  map.grid_var + size_t(mi) * G, G, im.weights,
                                                  cfg.match.observed_variance * cfg.field.signal_variance,
                                                  cfg.match.normalize_mass, cfg.match.covariance_weight);
    if (r.used >= 4) omega = static_cast<float>(std::exp(-(r.w2 / r.used) / cfg.match.tau));
  }
  if (float* slot = im.similarity.find_or_insert(skey)) *slot = omega;
  return omega;
}

}  // namespace

Status Localizer::localize(const ScanView& scan, LocalizeResult* out_ptr) {
  LocalizeResult scratch_result;
  LocalizeResult& out = out_ptr ? *out_ptr : scratch_result;
  out = LocalizeResult();
  if (!initialized_) return out.status = Status::NotInitialized;
  Impl& im = *impl_;
  const LocalizerConfig& cfg = config_;
  const uint64_t t_start = now(clock_);
  uint64_t t = t_start;
  auto lap = [&](uint64_t* field) {
    const uint64_t n = now(clock_);
    *field = n - t;
    t = n;
  };
  auto finish = [&](Status s) {
    out.status = s;
    out.times.total = now(clock_) - t_start;
    return s;
  };
  if (scan.count > cfg.max_scan_points) return finish(Status::CapacityExceeded);

  // 1. Metric-semantic layer.
  Status s = im.voxels.build(scan, nullptr);
  lap(&out.times.voxel);
  if (s == Status::CapacityExceeded) out.capacity_truncated = true;
  else if (s != Status::Ok) return finish(s);

  // 2. Object layer.
  s = im.clusters.build(im.voxels, nullptr);
  if (s == Status::CapacityExceeded) out.capacity_truncated = true;
  else if (s != Status::Ok) return finish(s);
  const uint32_t n = im.clusters.size();
  out.query_instances = n;
  for (uint32_t i = 0; i < n; ++i) {
    const Instance& in = im.clusters.instance(i);
    for (int k = 0; k < 3; ++k) im.centroids[3 * i + k] = in.centroid[k];
    im.labels[i] = in.label;
  }
  lap(&out.times.cluster);
  if (n < 3) return finish(Status::NoSolution);

  // 3. Gaussian semantic fields of the query instances (only needed with the GSF filter).
  const uint32_t M = cfg.field.inducing_points;
  for (uint32_t i = 0; i < n; ++i) {
    im.q_m[i] = 0;
    if (!cfg.match.use_gsf) continue;
    uint32_t total = 0;
    const uint32_t got = collect_field_points(im.voxels, cfg.field, im.centroids + 3 * i, cfg.match.max_field_points,
                                              im.gather_ids, im.gather_xyz, im.gather_targets, im.gather_labels, &total);
    if (total > got) out.capacity_truncated = true;
    uint32_t m = 0;
    if (im.solver.fit(im.gather_xyz, im.gather_targets, im.gather_labels, got, im.q_inputs + size_t(i) * M * 3,
                      im.q_alpha + size_t(i) * M * kNumClasses, im.q_chol + size_t(i) * M * M, &m) == Status::Ok)
      im.q_m[i] = m;
  }
  lap(&out.times.field);

  // 4. Query triangles.
  s = im.triangle_builder.build(im.centroids, 3, im.labels, n, im.triangles);
  if (s == Status::CapacityExceeded) out.capacity_truncated = true;
  else if (s != Status::Ok) return finish(s);
  out.query_triangles = im.triangles.size();
  lap(&out.times.triangle);

  // 5. Coarse matching through the map's hash index.
  im.matches.clear();
  for (uint32_t q = 0; q < im.triangles.size(); ++q) {
    s = match_triangle(im.triangles[q], q, im.index, map_.triangles, cfg.triangle, cfg.match.max_matches_per_triangle,
                       im.matches);
    if (s == Status::CapacityExceeded) {
      out.capacity_truncated = true;
      if (im.matches.full()) break;
    }
  }
  out.triangle_matches = im.matches.size();
  lap(&out.times.match);

  // 6. GSF fine filter -> weighted, deduplicated vertex correspondences.
  im.probe_slot.clear();
  im.similarity.clear();
  im.corr_index.clear();
  im.probe_used = 0;
  im.corr_count = 0;
  im.selected = 0;
  uint32_t survivors = 0;
  for (uint32_t k = 0; k < im.matches.size(); ++k) {
    const Triangle& qt = im.triangles[im.matches[k].query];
    const Triangle& mt = map_.triangles[im.matches[k].map];
    float omega[3] = {1.0f, 1.0f, 1.0f};
    if (cfg.match.use_gsf) {
      // Yaw hypothesis of the match: closed-form 2-D Procrustes over the three centred vertex pairs
      // (the vehicle is near level; the full 3-D pose comes later from the clique).
      float qc[2] = {0, 0}, mc[2] = {0, 0};
      for (int v = 0; v < 3; ++v)
        for (int d = 0; d < 2; ++d) {
          qc[d] += im.centroids[3 * qt.v[v] + d] / 3.0f;
          mc[d] += map_.instances[mt.v[v]].centroid[d] / 3.0f;
        }
      float dot = 0.0f, cross = 0.0f;
      for (int v = 0; v < 3; ++v) {
        const float ax = im.centroids[3 * qt.v[v]] - qc[0], ay = im.centroids[3 * qt.v[v] + 1] - qc[1];
        const float bx = map_.instances[mt.v[v]].centroid[0] - mc[0], by = map_.instances[mt.v[v]].centroid[1] - mc[1];
        dot += ax * bx + ay * by;
        cross += ax * by - ay * bx;
      }
      const double yaw = std::atan2(static_cast<double>(cross), static_cast<double>(dot));
      const uint32_t bins = cfg.match.yaw_bins;
      int64_t bin = static_cast<int64_t>(std::llround(yaw / kTwoPi * bins));
      bin = ((bin % bins) + bins) % bins;
      bool keep = true;
      for (int v = 0; v < 3 && keep; ++v) {
        omega[v] = field_similarity(im, cfg, map_, qt.v[v], mt.v[v], static_cast<uint32_t>(bin));
        keep = omega[v] >= cfg.match.min_similarity;
      }
      if (!keep) continue;
    }
    ++survivors;
    for (int v = 0; v < 3; ++v) {
      const uint64_t key = (uint64_t(qt.v[v]) << 32) | mt.v[v];
      bool inserted = false;
      // corr_index and corr share one capacity, so the index refuses a new key (nullptr) exactly when
      // the array is full; the second test is a guard that can only fire if that invariant breaks.
      uint32_t* id = im.corr_index.find_or_insert(key, &inserted);
      if (!id || (inserted && im.corr_count >= im.corr_capacity)) { out.capacity_truncated = true; continue; }
      if (inserted) {
        *id = im.corr_count;
        im.corr[im.corr_count++] = CorrespondenceAcc{qt.v[v], mt.v[v], 0.0f, 0};
      }
      CorrespondenceAcc& c = im.corr[*id];
      c.weight = std::max(c.weight, omega[v]);
      c.votes += 1;
    }
  }
  out.gsf_survivors = survivors;
  out.field_probes = im.probe_used;
  out.field_comparisons = im.similarity.size();
  lap(&out.times.gsf);

  // 7. Keep the best-supported correspondences (votes x weight) up to the clique capacity.
  const uint32_t total = im.corr_count;
  for (uint32_t i = 0; i < total; ++i) im.order[i] = i;
  const CorrespondenceAcc* corr = im.corr;
  std::sort(im.order, im.order + total, [corr](uint32_t x, uint32_t y) {
    const float sx = corr[x].weight * float(corr[x].votes), sy = corr[y].weight * float(corr[y].votes);
    if (sx != sy) return sx > sy;
    if (corr[x].query != corr[y].query) return corr[x].query < corr[y].query;
    return corr[x].map < corr[y].map;
  });
  const uint32_t C = std::min(total, cfg.match.max_correspondences);
  if (total > C) out.capacity_truncated = true;
  for (uint32_t i = 0; i < C; ++i) {
    const CorrespondenceAcc& c = im.corr[im.order[i]];
    for (int d = 0; d < 3; ++d) {
      im.a[3 * i + d] = im.centroids[3 * c.query + d];
      im.b[3 * i + d] = map_.instances[c.map].centroid[d];
    }
    im.w[i] = c.weight;
  }
  out.correspondences = C;
  im.selected = C;
  for (uint32_t i = 0; i < C; ++i) im.in_clique[i] = 0;
  if (C < cfg.pose.min_inliers) return finish(Status::NoSolution);

  // 8. Maximum clique of the consistency graph.
  im.graph.build(im.a, im.b, C, cfg.clique.consistency_eps);
  CliqueStats cs;
  s = im.clique_solver.solve(im.graph, cfg.clique.node_budget, im.clique, &cs);
  out.clique_nodes = cs.nodes;
  out.budget_exhausted = s == Status::BudgetExhausted;
  out.clique_size = im.clique.size();
  lap(&out.times.clique);
  if (im.clique.size() < cfg.pose.min_inliers) return finish(Status::NoSolution);

  // 9. Weighted TLS pose on the clique.
  const uint32_t q = im.clique.size();
  for (uint32_t i = 0; i < q; ++i) im.in_clique[im.clique[i]] = 1;
  for (uint32_t i = 0; i < q; ++i) {
    const uint32_t id = im.clique[i];
    for (int d = 0; d < 3; ++d) { im.sub_a[3 * i + d] = im.a[3 * id + d]; im.sub_b[3 * i + d] = im.b[3 * id + d]; }
    im.sub_w[i] = im.w[id] > 1e-6f ? im.w[id] : 1e-6f;
  }
  TlsResult tls;
  s = solve_tls(im.sub_a, im.sub_b, im.sub_w, q, cfg.pose.tls_threshold, cfg.pose.max_iterations, &tls, im.mask,
                im.tls_weights);
  if (s != Status::Ok || tls.inliers < cfg.pose.min_inliers) {
    lap(&out.times.pose);
    return finish(Status::NoSolution);
  }
  out.map_T_scan = tls.b_T_a;
  out.inliers = tls.inliers;
  double best_score = 0.0;
  for (uint32_t i = 0; i < q; ++i) best_score += im.mask[i] ? im.sub_w[i] : 0.0;
  out.score = best_score;

  // 10. Ambiguity: the best clique among correspondences that disagree with the answer.
  const double far2 = 4.0 * double(cfg.pose.tls_threshold) * cfg.pose.tls_threshold;
  uint32_t nd = 0;
  for (uint32_t i = 0; i < C; ++i) {
    const Eigen::Vector3d pa(im.a[3 * i], im.a[3 * i + 1], im.a[3 * i + 2]);
    const Eigen::Vector3d pb(im.b[3 * i], im.b[3 * i + 1], im.b[3 * i + 2]);
    if ((pb - tls.b_T_a * pa).squaredNorm() <= far2) continue;
    for (int d = 0; d < 3; ++d) { im.sub_a[3 * nd + d] = im.a[3 * i + d]; im.sub_b[3 * nd + d] = im.b[3 * i + d]; }
    im.sub_w[nd] = im.w[i];
    ++nd;
  }
  double second = 0.0;
  if (nd >= 2) {
    im.graph.build(im.sub_a, im.sub_b, nd, cfg.clique.consistency_eps);
    im.clique_solver.solve(im.graph, cfg.clique.second_budget, im.clique, &cs);
    for (uint32_t i = 0; i < im.clique.size(); ++i) second += std::max(im.sub_w[im.clique[i]], 1e-6f);
  }
  // Weak support is ambiguity too: an answer resting on k inliers is at least min_inliers / k ambiguous
  // (a bare-minimum clique with nothing competing is still a guess).
  const double support = double(cfg.pose.min_inliers) / double(tls.inliers);
  out.ambiguity = best_score > 0 ? std::min(1.0, std::max(second / best_score, support)) : 1.0;
  lap(&out.times.pose);

  // 11. Optional refinement against the map's point layer.
  if (cfg.refine.enabled && map_.counts.refine_points > 0) {
    Eigen::Isometry3d refined;
    RefineStats rs;
    if (im.refiner.refine(im.voxels, out.map_T_scan, &refined, &rs) == Status::Ok && rs.accepted) {
      out.map_T_scan = refined;
      out.refined = true;
    }
    lap(&out.times.refine);
  }
  return finish(Status::Ok);
}

}  // namespace gsf

namespace gsf {

uint32_t Localizer::last_correspondences(Correspondence* out, uint32_t max) const {
  if (!impl_) return 0;
  const Impl& im = *impl_;
  for (uint32_t i = 0; i < im.selected && i < max; ++i) {
    const CorrespondenceAcc& c = im.corr[im.order[i]];
    out[i].query_instance = c.query;
    out[i].map_instance = c.map;
    for (int d = 0; d < 3; ++d) out[i].query_xyz[d] = im.a[3 * i + d];
    out[i].weight = c.weight;
    out[i].in_clique = im.in_clique[i] != 0;
  }
  return im.selected;
}

}  // namespace gsf
