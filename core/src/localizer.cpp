#include "gsf/localizer.h"

#include <algorithm>
#include <cmath>
#include <new>

#include "gsf/detail/bounded_hash_map.h"
#include "gsf/detail/fixed_vector.h"
#include "gsf/detail/gaussian_field.h"
#include "gsf/detail/gsf_filter.h"
#include "gsf/detail/instance_clustering.h"
#include "gsf/detail/pole_extraction.h"
#include "gsf/detail/pose_hypotheses.h"
#include "gsf/detail/refine.h"
#include "gsf/detail/semantic_grid.h"
#include "gsf/detail/triangle.h"
#include "gsf/detail/triangle_index.h"
#include "gsf/detail/triangle_matcher.h"
#include "gsf/detail/voxel_layer.h"
#include "gsf/detail/wasserstein.h"

namespace gsf {
namespace {

struct CorrespondenceAcc {
  uint32_t query, map;
  float weight;    // best GSF similarity seen for this pair (1 without GSF)
  uint32_t votes;  // surviving triangle matches that produced it
};

constexpr double kRadToDeg = 57.29577951308232;

// Indices of the best `cap` hypotheses by verification score (eligible[h] != 0, or all when null),
// best first, ties to the earlier hypothesis. Returns how many (<= cap).
uint32_t top_by_score(const PoseHypotheses& hyps, uint32_t H, const uint8_t* eligible, uint32_t cap, uint32_t* out) {
  uint32_t n = 0;
  for (uint32_t h = 0; h < H; ++h) {
    if (eligible && !eligible[h]) continue;
    const float sc = hyps[h].verification.score;
    uint32_t pos = n < cap ? n++ : cap;
    while (pos > 0 && hyps[out[pos - 1]].verification.score < sc) {
      if (pos < cap) out[pos] = out[pos - 1];
      --pos;
    }
    if (pos < cap) out[pos] = h;
  }
  return n;
}

}  // namespace

struct Localizer::Impl {
  ClassTable classes;  // the label set in effect (a copy: the caller's table need not outlive init)
  VoxelLayer voxels;
  InstanceClustering clusters;
  PoleExtraction poles;  // bound only when the label set has pole / trunk hosts
  bool poles_on = false;
  uint32_t* pole_order = nullptr;  // poles.max_instances: kept poles by score
  FieldSolver solver;
  TriangleBuilder triangle_builder;
  FixedVector<Triangle> triangles;
  TriangleMatcher matcher;
  GsfFilter gsf;
  BoundedHashMap<uint32_t> corr_index;  // (query instance, map instance) -> correspondence id
  PoseHypotheses hypotheses;
  Refiner refiner;
  TriangleIndexView index;
  SemanticGridView semantic;

  // Query instances and their fields.
  float* centroids = nullptr;  // I x 3
  uint8_t* labels = nullptr;   // I
  float* q_inputs = nullptr;   // I x M x 3
  float* q_alpha = nullptr;    // I x M x D
  float* q_chol = nullptr;     // I x M x M
  uint32_t* q_m = nullptr;     // I (0: no field)
  // Gather scratch for one field fit.
  uint32_t* gather_ids = nullptr;
  float* gather_xyz = nullptr;
  float* gather_targets = nullptr;
  uint8_t* gather_labels = nullptr;
  float weights[kNumClasses];
  float verify_weights[kNumClasses];   // weights with this scan's rarity weighting (verification)
  uint32_t* heading_votes = nullptr;   // yaw bins
  uint8_t* heading_allowed = nullptr;  // yaw bins
  // Correspondences.
  CorrespondenceAcc* corr = nullptr;  // candidates (capacity corr_capacity)
  uint32_t corr_count = 0;
  uint32_t corr_capacity = 0;
  uint32_t* order = nullptr;                  // selection scratch (corr_capacity)
  float* a = nullptr;                         // C x 3 query positions
  float* b = nullptr;                         // C x 3 map positions
  float* w = nullptr;                         // C weights
  uint32_t selected = 0;                      // correspondences given to the hypothesis stage in the last call
  uint32_t chosen = 0;                        // the answer's hypothesis in the last call (UINT32_MAX: none)
  uint32_t instance_count = 0;                // query instances of the last call
  Eigen::Isometry3d* refined_pose = nullptr;  // verify.refine_top: poses the pattern search chose
  uint32_t* refined_id = nullptr;             // verify.refine_top: their hypotheses

  // The stages of localize(), in order (defined below, each with its comment).
  Status build_voxels(const ScanView& scan, LocalizeResult& out);
  Status find_instances(const LocalizerConfig& cfg, LocalizeResult& out);
  void fit_query_fields(const LocalizerConfig& cfg, LocalizeResult& out);
  Status build_query_triangles(LocalizeResult& out);
  void vote_headings(const LocalizerConfig& cfg, const MapView& map, LocalizeResult& out);
  void match_and_filter(const LocalizerConfig& cfg, const MapView& map, Clock* clock, LocalizeResult& out);
  uint32_t select_correspondences(const LocalizerConfig& cfg, const MapView& map, LocalizeResult& out);
  Status generate_hypotheses(const LocalizerConfig& cfg, uint32_t C, LocalizeResult& out);
  void set_verify_weights(const LocalizerConfig& cfg);
  void choose_answer(const LocalizerConfig& cfg, LocalizeResult& out);
  void refine_answer(LocalizeResult& out);
  uint32_t heading_bin(const Triangle& qt, const RankedTriangleMatch& rm, const MapView& map, uint32_t yaw_bins,
                       uint32_t* qv) const;
};

// The one layout of the workspace: run on a counting arena by required_bytes and budget, and on the
// caller's buffer by init, so sizes can never disagree. Each stage's bytes are recorded as it binds.
Status Localizer::bind_workspace(Arena& ar, const LocalizerConfig& config, Impl& im, Budget* parts) {
  const uint32_t I = config.cluster.max_instances, M = config.field.inducing_points;
  const uint32_t C = config.match.max_correspondences, P = config.match.max_field_points;
  const uint32_t corr_cap = config.match.max_candidates;
  Budget b{};
  size_t mark = ar.used();
  auto record = [&](size_t* field) {
    *field += ar.used() - mark;
    mark = ar.used();
  };
  if (im.voxels.bind(ar, config.voxel) != Status::Ok) return Status::InvalidArgument;
  record(&b.voxel);
  ClusterConfig cluster = config.cluster;
  cluster.instance_classes = config.classes ? config.classes->instance_classes() : config.cluster.instance_classes;
  if (im.clusters.bind(ar, cluster, config.voxel.max_voxels) != Status::Ok) return Status::InvalidArgument;
  record(&b.cluster);
  const PoleConfig poles = effective_pole_config(config);
  im.poles_on = (poles.pole_hosts | poles.trunk_hosts) != 0;
  if (im.poles_on) {
    if (im.poles.bind(ar, poles, config.voxel.max_voxels) != Status::Ok) return Status::InvalidArgument;
    im.pole_order = ar.allocate<uint32_t>(poles.max_instances);
  }
  record(&b.poles);
  if (im.solver.bind(ar, config.field, P) != Status::Ok) return Status::InvalidArgument;
  im.q_inputs = ar.allocate<float>(size_t(I) * M * 3);
  im.q_alpha = ar.allocate<float>(size_t(I) * M * kNumClasses);
  im.q_chol = ar.allocate<float>(size_t(I) * M * M);
  im.q_m = ar.allocate<uint32_t>(I);
  im.gather_ids = ar.allocate<uint32_t>(P);
  im.gather_xyz = ar.allocate<float>(size_t(P) * 3);
  im.gather_targets = ar.allocate<float>(size_t(P) * kNumClasses);
  im.gather_labels = ar.allocate<uint8_t>(P);
  record(&b.field);
  if (im.triangle_builder.bind(ar, config.triangle, I) != Status::Ok) return Status::InvalidArgument;
  im.triangles.bind(ar, config.triangle.max_triangles);
  im.centroids = ar.allocate<float>(size_t(I) * 3);
  im.labels = ar.allocate<uint8_t>(I);
  record(&b.triangle);
  if (im.matcher.bind(ar, config.match.max_matches_per_triangle) != Status::Ok) return Status::InvalidArgument;
  im.heading_votes = ar.allocate<uint32_t>(config.gsf.yaw_bins);
  im.heading_allowed = ar.allocate<uint8_t>(config.gsf.yaw_bins);
  record(&b.match);
  if (im.gsf.bind(ar, config.gsf, config.field, &im.solver) != Status::Ok && !ar.counting())
    return Status::InvalidArgument;
  record(&b.gsf_cache);
  im.corr_index.bind(ar, corr_cap);
  im.corr = ar.allocate<CorrespondenceAcc>(corr_cap);
  im.corr_capacity = corr_cap;
  im.order = ar.allocate<uint32_t>(corr_cap);
  im.a = ar.allocate<float>(size_t(C) * 3);
  im.b = ar.allocate<float>(size_t(C) * 3);
  im.w = ar.allocate<float>(C);
  record(&b.correspondence);
  if (im.hypotheses.bind(ar, C, config.hypotheses.max_hypotheses) != Status::Ok) return Status::InvalidArgument;
  im.refined_pose = ar.allocate<Eigen::Isometry3d>(config.verify.refine_top);
  im.refined_id = ar.allocate<uint32_t>(config.verify.refine_top);
  record(&b.clique);
  if (config.refine.enabled && im.refiner.bind(ar, config.refine) != Status::Ok) return Status::InvalidArgument;
  record(&b.refine);
  if (ar.overflowed()) return Status::BufferTooSmall;
  if (parts) *parts = b;
  return Status::Ok;
}

namespace {
constexpr size_t kImplAlign = alignof(std::max_align_t) < 16 ? 16 : alignof(std::max_align_t);
}  // namespace

Localizer::Budget Localizer::budget(const LocalizerConfig& c) {
  Budget b{};
  if (validate(c) != Status::Ok) return b;
  Arena counting;
  counting.allocate_bytes(sizeof(Impl), kImplAlign);
  Impl scratch;
  if (bind_workspace(counting, c, scratch, &b) != Status::Ok) return Budget{};
  b.total = counting.used();
  const size_t parts = b.voxel + b.cluster + b.poles + b.field + b.triangle + b.match + b.gsf_cache + b.correspondence +
                       b.clique + b.refine;
  b.other = b.total - parts;  // the Impl object and its alignment
  return b;
}

size_t Localizer::required_bytes(const LocalizerConfig& config) {
  if (validate(config) != Status::Ok) return 0;
  Arena counting;
  counting.allocate_bytes(sizeof(Impl), kImplAlign);
  Impl scratch;
  if (bind_workspace(counting, config, scratch, nullptr) != Status::Ok) return 0;
  return counting.used();
}

Status Localizer::init(const LocalizerConfig& config, const MapView& map, void* buffer, size_t bytes, Clock* clock) {
  initialized_ = false;
  impl_ = nullptr;
  Status s = validate(config);
  if (s != Status::Ok) return s;
  s = check_map_params(config, map.params);
  if (s != Status::Ok) return s;
  if ((map.instances == nullptr && map.counts.instances > 0) || map.index_offsets == nullptr)
    return Status::InvalidArgument;
  if (buffer == nullptr || (reinterpret_cast<uintptr_t>(buffer) % 16) != 0) return Status::InvalidArgument;
  if (bytes < required_bytes(config)) return Status::BufferTooSmall;
  config_ = config;
  map_ = map;
  clock_ = clock;
  arena_ = Arena(buffer, bytes);
  void* mem = arena_.allocate_bytes(sizeof(Impl), kImplAlign);
  if (!mem) return Status::BufferTooSmall;
  Impl& im = *new (mem) Impl();
  s = bind_workspace(arena_, config, im, nullptr);
  if (s != Status::Ok) return s;
  if (config.refine.enabled) {
    s = im.refiner.set_map(map.refine_layer());
    if (s != Status::Ok) return s;
  }
  im.classes = label_set(config);
  if (config.classes) {
    // Stages read the label set from the workspace copy; config() must not point at the caller's table.
    config_.classes = &im.classes;
    im.voxels.set_classes(&im.classes);
    im.clusters.set_classes(&im.classes);
    im.refiner.set_classes(&im.classes);
  }
  for (int c = 0; c < kNumClasses; ++c) im.verify_weights[c] = im.weights[c] = im.classes.stability(c);
  im.gsf.set_class_weights(im.weights);
  im.index.keys = map.index_keys;
  im.index.offsets = map.index_offsets;
  im.index.entries = map.index_entries;
  im.index.key_count = map.counts.index_keys;
  im.index.entry_count = map.counts.triangles;
  im.semantic = map.semantic_grid();
  im.chosen = UINT32_MAX;
  impl_ = &im;
  initialized_ = true;
  return Status::Ok;
}

namespace {

uint64_t now(Clock* c) { return c ? c->now_ns() : 0; }

}  // namespace

// ---- The query pipeline, one stage per function; localize() below calls them in order. ----

// 1. Metric-semantic layer.
Status Localizer::Impl::build_voxels(const ScanView& scan, LocalizeResult& out) {
  const Status s = voxels.build(scan, nullptr);
  out.scan_voxels = voxels.size();
  if (s == Status::CapacityExceeded) out.capacity_truncated = true;
  return s == Status::CapacityExceeded ? Status::Ok : s;
}

// 2. Object layer: clustered instances, then geometric poles / trunks (label sets without pole and
// trunk classes), best score first into the instance slots clustering left free; the rest are counted,
// never cut in storage order.
Status Localizer::Impl::find_instances(const LocalizerConfig& cfg, LocalizeResult& out) {
  Status s = clusters.build(voxels, nullptr);
  if (s == Status::CapacityExceeded) out.capacity_truncated = true;
  else if (s != Status::Ok) return s;
  uint32_t n = clusters.size();
  for (uint32_t i = 0; i < n; ++i) {
    const Instance& in = clusters.instance(i);
    for (int k = 0; k < 3; ++k) centroids[3 * i + k] = in.centroid[k];
    labels[i] = in.label;
  }
  // 2b. Geometric pole / trunk instances (label sets without pole and trunk classes), best score first
  // into the instance slots clustering left free; the rest are counted, never cut in storage order.
  if (poles_on) {
    s = poles.build(voxels, nullptr);
    if (s == Status::CapacityExceeded) out.capacity_truncated = true;
    else if (s != Status::Ok) return s;
    const uint32_t np = poles.size();
    for (uint32_t i = 0; i < np; ++i) {  // insertion sort by score (np <= poles.max_instances, small)
      uint32_t pos = i;
      while (pos > 0 && poles.info(pole_order[pos - 1]).score < poles.info(i).score) {
        pole_order[pos] = pole_order[pos - 1];
        --pos;
      }
      pole_order[pos] = i;
    }
    for (uint32_t k = 0; k < np; ++k) {
      if (n >= cfg.cluster.max_instances) {
        ++out.pole_instances_dropped;
        out.capacity_truncated = true;
        continue;
      }
      const Instance& in = poles.instance(pole_order[k]);
      for (int c = 0; c < 3; ++c) centroids[3 * n + c] = in.centroid[c];
      labels[n++] = in.label;
      ++out.pole_instances;
    }
  }
  out.query_instances = instance_count = n;
  return Status::Ok;
}

// 3. Gaussian semantic fields of the query instances (only needed with the GSF filter).
void Localizer::Impl::fit_query_fields(const LocalizerConfig& cfg, LocalizeResult& out) {
  const uint32_t n = instance_count;
  const uint32_t M = cfg.field.inducing_points;
  for (uint32_t i = 0; i < n; ++i) {
    q_m[i] = 0;
    if (!cfg.match.use_gsf) continue;
    uint32_t total = 0;
    const FieldGather gather{cfg.match.max_field_points, gather_ids, gather_xyz, gather_targets, gather_labels};
    uint32_t m = 0, got = 0;
    if (fit_instance_field(solver, voxels, centroids + 3 * i, gather, q_inputs + size_t(i) * M * 3,
                           q_alpha + size_t(i) * M * kNumClasses, q_chol + size_t(i) * M * M, &m, &got,
                           &total) == Status::Ok)
      q_m[i] = m;
    if (total > got) out.capacity_truncated = true;
  }
}

// 4. Query triangles.
Status Localizer::Impl::build_query_triangles(LocalizeResult& out) {
  const uint32_t n = instance_count;
  const Status s = triangle_builder.build(centroids, 3, labels, n, triangles);
  if (s == Status::CapacityExceeded) out.capacity_truncated = true;
  else if (s != Status::Ok) return s;
  out.query_triangles = triangles.size();
  return Status::Ok;
}

// Yaw bin of a ranked match (the heading that maps the query triangle onto the map triangle); its
// query vertices in the map triangle's vertex order go to qv.
uint32_t Localizer::Impl::heading_bin(const Triangle& qt, const RankedTriangleMatch& rm, const MapView& map,
                                      uint32_t yaw_bins, uint32_t* qv) const {
  const Triangle& mt = map.triangles[rm.map];
  for (int v = 0; v < 3; ++v) qv[v] = TriangleMatcher::query_vertex(qt, rm.order, v);
  const float* qp[3] = {centroids + 3 * qv[0], centroids + 3 * qv[1], centroids + 3 * qv[2]};
  const float* mp[3] = {map.instances[mt.v[0]].centroid, map.instances[mt.v[1]].centroid,
                        map.instances[mt.v[2]].centroid};
  return triangle_yaw_bin(qp, mp, yaw_bins);
}

// 5a. Heading votes: the matches of an evenly spaced sample of query triangles vote for their yaw
// bin; only the best-supported headings (and their neighbour bins) go on. True matches agree on one
// heading (a lattice's symmetries add a few more), wrong ones spread over all of them; this bounds
// the distinct (instance, heading) probes of the GSF filter by instances x kept bins.
void Localizer::Impl::vote_headings(const LocalizerConfig& cfg, const MapView& map, LocalizeResult& out) {
  const uint32_t B = cfg.gsf.yaw_bins, T = triangles.size();
  for (uint32_t b = 0; b < B; ++b) heading_allowed[b] = cfg.match.heading_bins == 0 ? 1 : 0;
  if (cfg.match.heading_bins > 0 && T > 0) {
    for (uint32_t b = 0; b < B; ++b) heading_votes[b] = 0;
    const uint32_t stride = (T + cfg.match.heading_sample_triangles - 1) / cfg.match.heading_sample_triangles;
    uint32_t qv[3];
    for (uint32_t qt_id = 0; qt_id < T; qt_id += stride) {
      const Triangle& qt = triangles[qt_id];
      matcher.match(qt, index, map.triangles, cfg.triangle, cfg.match.vertex_tie_tolerance);
      for (uint32_t k = 0; k < matcher.size(); ++k)
        ++heading_votes[heading_bin(qt, matcher.match_at(k), map, cfg.gsf.yaw_bins, qv)];
    }
    for (uint32_t pick = 0; pick < cfg.match.heading_bins && pick < B; ++pick) {
      uint32_t best = UINT32_MAX;
      for (uint32_t b = 0; b < B; ++b)
        if (heading_votes[b] > 0 && (best == UINT32_MAX || heading_votes[b] > heading_votes[best])) best = b;
      if (best == UINT32_MAX) break;
      heading_votes[best] = 0;
      heading_allowed[best] = heading_allowed[(best + 1) % B] = heading_allowed[(best + B - 1) % B] = 1;
    }
  }
  for (uint32_t b = 0; b < B; ++b) out.headings_kept += heading_allowed[b];
}

// 5b + 6. Per query triangle: ranked index matches, then the GSF filter, accumulating weighted,
// deduplicated vertex correspondences. Nothing is stored per triangle match, so no global cap on
// matches exists that could cut in storage order. Adds its time to out.times.match and .gsf.
void Localizer::Impl::match_and_filter(const LocalizerConfig& cfg, const MapView& map, Clock* clock,
                                       LocalizeResult& out) {
  gsf.reset();
  corr_index.clear();
  corr_count = 0;
  const QueryFields qf{q_inputs, q_alpha, q_chol, q_m, cfg.field.inducing_points};
  uint64_t t_match = 0, t_gsf = 0;
  uint32_t survivors = 0;
  const uint32_t T = triangles.size();
  for (uint32_t qt_id = 0; qt_id < T; ++qt_id) {
    const Triangle& qt = triangles[qt_id];
    const uint64_t t0 = now(clock);
    const TriangleMatchStats ms = matcher.match(qt, index, map.triangles, cfg.triangle, cfg.match.vertex_tie_tolerance);
    const uint64_t t1 = now(clock);
    t_match += t1 - t0;
    out.match_candidates += ms.accepted;
    out.match_dropped += ms.dropped();
    out.triangle_matches += ms.kept;
    if (ms.orders > 1) ++out.tie_ordered_triangles;
    for (uint32_t k = 0; k < matcher.size(); ++k) {
      const RankedTriangleMatch& rm = matcher.match_at(k);
      const Triangle& mt = map.triangles[rm.map];
      uint32_t qv[3];
      const uint32_t bin = heading_bin(qt, rm, map, cfg.gsf.yaw_bins, qv);
      if (!heading_allowed[bin]) {
        ++out.heading_dropped;
        continue;
      }
      float omega[3] = {1.0f, 1.0f, 1.0f};
      if (cfg.match.use_gsf) {
        bool keep = true;
        for (int v = 0; v < 3 && keep; ++v) {
          omega[v] = gsf.similarity(qf, qv[v], map, mt.v[v], bin);
          keep = omega[v] >= cfg.match.min_similarity;
        }
        if (!keep) continue;
      }
      ++survivors;
      for (int v = 0; v < 3; ++v) {
        const uint64_t key = (uint64_t(qv[v]) << 32) | mt.v[v];
        bool inserted = false;
        // corr_index and corr share one capacity, so the index refuses a new key (nullptr) exactly when
        // the array is full; the second test is a guard that can only fire if that invariant breaks.
        uint32_t* id = corr_index.find_or_insert(key, &inserted);
        if (!id || (inserted && corr_count >= corr_capacity)) {
          ++out.candidate_pairs_dropped;
          continue;
        }
        if (inserted) {
          *id = corr_count;
          corr[corr_count++] = CorrespondenceAcc{qv[v], mt.v[v], 0.0f, 0};
        }
        CorrespondenceAcc& c = corr[*id];
        c.weight = std::max(c.weight, omega[v]);
        c.votes += 1;
      }
    }
    t_gsf += now(clock) - t1;
  }
  out.times.match += t_match;
  out.times.gsf += t_gsf;
  out.gsf_survivors = survivors;
  out.field_probes = gsf.probes();
  out.field_comparisons = gsf.comparisons();
  out.candidate_pairs = corr_count;
  if (out.match_dropped > 0 || out.candidate_pairs_dropped > 0 || out.heading_dropped > 0)
    out.capacity_truncated = true;
}

// 7. Keep the best-supported correspondences (votes x weight) up to the clique capacity; equal
// support is broken by a hash of the pair, never by instance id (map ids follow map x order).
// Returns how many were kept (a, b and w hold them).
uint32_t Localizer::Impl::select_correspondences(const LocalizerConfig& cfg, const MapView& map, LocalizeResult& out) {
  const uint32_t total = corr_count;
  for (uint32_t i = 0; i < total; ++i) order[i] = i;
  const CorrespondenceAcc* acc = corr;
  std::sort(order, order + total, [acc](uint32_t x, uint32_t y) {
    const float sx = acc[x].weight * float(acc[x].votes), sy = acc[y].weight * float(acc[y].votes);
    if (sx != sy) return sx > sy;
    const uint64_t hx = mix64((uint64_t(acc[x].query) << 32) | acc[x].map);
    const uint64_t hy = mix64((uint64_t(acc[y].query) << 32) | acc[y].map);
    if (hx != hy) return hx < hy;
    return x < y;
  });
  const uint32_t C = std::min(total, cfg.match.max_correspondences);
  out.correspondences_dropped = total - C;
  if (total > C) out.capacity_truncated = true;
  for (uint32_t i = 0; i < C; ++i) {
    const CorrespondenceAcc& c = corr[order[i]];
    for (int d = 0; d < 3; ++d) {
      a[3 * i + d] = centroids[3 * c.query + d];
      b[3 * i + d] = map.instances[c.map].centroid[d];
    }
    w[i] = c.weight;
  }
  out.correspondences = C;
  return C;
}

// 8. Pose hypotheses: peeled maximum cliques, each with its weighted TLS pose, and translation votes.
Status Localizer::Impl::generate_hypotheses(const LocalizerConfig& cfg, uint32_t C, LocalizeResult& out) {
  HypothesisStats hs;
  const Status s = hypotheses.generate(a, b, w, C, cfg.hypotheses, &hs);
  out.clique_nodes = hs.nodes;
  out.clique_searches = hs.searches;
  out.budget_exhausted = hs.budget_exhausted;
  out.hypotheses = hypotheses.size();
  return s;
}

// Verification weights for this scan: the stability weights, each class scaled by (its share of the
// sampled voxels)^-rarity_exponent and all rescaled to keep the total (VerifyConfig::rarity_exponent).
void Localizer::Impl::set_verify_weights(const LocalizerConfig& cfg) {
  for (int c = 0; c < kNumClasses; ++c) verify_weights[c] = weights[c];
  if (cfg.verify.rarity_exponent > 0.0f && voxels.size() > 0) {
    uint32_t counts[kNumClasses] = {};
    const uint32_t nv = voxels.size(), stride = (nv + cfg.verify.max_points - 1) / cfg.verify.max_points;
    uint32_t total = 0;
    for (uint32_t i = 0; i < nv; i += stride, ++total) ++counts[voxels.voxel(i).label];
    double mass = 0.0, scaled = 0.0;
    for (int c = 0; c < kNumClasses; ++c) {
      if (counts[c] == 0) continue;
      verify_weights[c] =
          weights[c] * static_cast<float>(std::pow(double(counts[c]) / total, -double(cfg.verify.rarity_exponent)));
      mass += double(weights[c]) * counts[c];
      scaled += double(verify_weights[c]) * counts[c];
    }
    if (scaled > 0.0)
      for (int c = 0; c < kNumClasses; ++c) verify_weights[c] = static_cast<float>(verify_weights[c] * (mass / scaled));
  }
}

// 9. Whole-scan verification against the map's semantic layer picks among the hypotheses; the
// ambiguity is how clearly the chosen one beats the runner-up, the answer's support and its agreement.
void Localizer::Impl::choose_answer(const LocalizerConfig& cfg, LocalizeResult& out) {
  const uint32_t H = hypotheses.size();
  const bool verify = cfg.verify.enabled && !semantic.empty();
  uint32_t best = 0, second = UINT32_MAX;
  uint8_t full_scored[PoseHypotheses::kMaxHypotheses] = {};
  uint32_t refined_count = 0;
  set_verify_weights(cfg);
  if (verify) {
    // Coarse score for every hypothesis, the full score for the best `full_top`, then the best
    // `refine_top` at their best local alignment. Each step ranks, then caps.
    uint8_t* full = full_scored;
    uint32_t top[PoseHypotheses::kMaxHypotheses];
    const uint32_t coarse_points = std::max<uint32_t>(1, cfg.verify.max_points / cfg.verify.coarse_divisor);
    for (uint32_t h = 0; h < H; ++h) {
      hypotheses[h].verification =
          verify_pose(voxels, semantic, hypotheses[h].map_T_scan, coarse_points, verify_weights);
      full[h] = 0;
    }
    uint32_t nt = top_by_score(hypotheses, H, nullptr, cfg.verify.full_top, top);
    for (uint32_t k = 0; k < nt; ++k) {
      hypotheses[top[k]].verification =
          verify_pose(voxels, semantic, hypotheses[top[k]].map_T_scan, cfg.verify.max_points, verify_weights);
      full[top[k]] = 1;
    }
    nt = cfg.verify.refine_rounds > 0 ? top_by_score(hypotheses, H, full, cfg.verify.refine_top, top) : 0;
    refined_count = nt;
    for (uint32_t k = 0; k < nt; ++k) {
      refined_id[k] = top[k];
      hypotheses[top[k]].verification = verify_pose_refined(
          voxels, semantic, hypotheses[top[k]].map_T_scan, cfg.verify.max_points, verify_weights,
          cfg.verify.refine_rounds, cfg.verify.refine_step_m, cfg.verify.refine_step_deg, &refined_pose[k]);
    }
    // The answer, and as runner-up the best fully scored hypothesis at another place or heading: a
    // near-twin of the answer (within hypotheses.same_pose_m and same_pose_deg in the bird's-eye view
    // the verification sees) is the same answer, not a rival.
    nt = top_by_score(hypotheses, H, full, H, top);
    best = nt > 0 ? top[0] : 0;
    const Eigen::Isometry3d& a = hypotheses[best].map_T_scan;
    const double yaw_a = std::atan2(a.linear()(1, 0), a.linear()(0, 0));
    const double same_rad = double(cfg.hypotheses.same_pose_deg) / kRadToDeg;
    for (uint32_t k = 1; k < nt && second == UINT32_MAX; ++k) {
      const Eigen::Isometry3d& b = hypotheses[top[k]].map_T_scan;
      const double dx = b.translation().x() - a.translation().x(), dy = b.translation().y() - a.translation().y();
      double dyaw = std::fabs(std::atan2(b.linear()(1, 0), b.linear()(0, 0)) - yaw_a);
      if (dyaw > 3.14159265358979323846) dyaw = 2.0 * 3.14159265358979323846 - dyaw;
      if (std::sqrt(dx * dx + dy * dy) > cfg.hypotheses.same_pose_m || dyaw > same_rad) second = top[k];
    }
  } else {
    second = H > 1 ? 1 : UINT32_MAX;
  }
  const PoseHypothesis& answer = hypotheses[best];
  out.map_T_scan = answer.map_T_scan;
  out.inliers = answer.inliers;
  out.clique_size = answer.clique_size;
  out.score = answer.support;
  out.chosen_hypothesis = best;
  out.verified = verify;
  chosen = best;
  // Report the best hypotheses by verified score (the order found without verification).
  uint32_t shown[kMaxReportedHypotheses];
  uint32_t reported = std::min(H, kMaxReportedHypotheses);
  if (verify) reported = top_by_score(hypotheses, H, nullptr, kMaxReportedHypotheses, shown);
  else
    for (uint32_t k = 0; k < reported; ++k) shown[k] = k;
  for (uint32_t k = 0; k < reported; ++k) {
    const PoseHypothesis& p = hypotheses[shown[k]];
    HypothesisReport& r = out.hypothesis[k];
    r.x = static_cast<float>(p.map_T_scan.translation().x());
    r.y = static_cast<float>(p.map_T_scan.translation().y());
    const Eigen::Matrix3d R = p.map_T_scan.linear();
    r.yaw_deg = static_cast<float>(std::atan2(R(1, 0), R(0, 0)) * kRadToDeg);
    r.clique_size = p.clique_size;
    r.inliers = p.inliers;
    r.support = static_cast<float>(p.support);
    r.verified_score = p.verification.score;
    r.verified_voxels = p.verification.scored;
    r.verified_agree = p.verification.agree;
    r.verified_disagree = p.verification.disagree;
    r.verified_unknown = p.verification.unknown;
    r.fully_verified = verify && full_scored[shown[k]];
  }
  // Weak support is ambiguity too: an answer resting on k inliers is at least min_inliers / k ambiguous
  // (a bare-minimum clique with nothing competing is still a guess).
  const double support = double(cfg.hypotheses.min_inliers) / double(answer.inliers);
  double rival = 0.0;
  if (second != UINT32_MAX) {
    if (verify) {
      const double margin = double(answer.verification.score) - hypotheses[second].verification.score;
      const double scale = double(cfg.verify.margin_scale) * std::max<uint32_t>(answer.verification.scored, 1);
      rival = std::exp(-std::max(0.0, margin) / scale);
    } else {
      rival = answer.support > 0 ? hypotheses[second].support / answer.support : 1.0;
    }
  }
  // A verified answer that agrees poorly with the map is doubtful even without a rival (its true
  // competitor may simply not be among the hypotheses): its agreement below quality_high adds
  // ambiguity, reaching 1 at quality_low. Agreement is (agree - disagree) / (agree + disagree) of the
  // stability weights, 1 when every scored voxel agrees: a share, so a scan of mostly half-weight
  // classes (vegetation, cars, terrain) is not judged worse than one of buildings and road.
  // With rarity weighting the agreement is taken with the plain stability weights (at the pose the
  // verification chose), so rare classes' label noise does not read as disagreement.
  double quality = 0.0;
  PoseVerification plain = answer.verification;
  if (verify && cfg.verify.rarity_exponent > 0.0f) {
    const Eigen::Isometry3d* at = &answer.map_T_scan;
    for (uint32_t k = 0; k < refined_count; ++k)
      if (refined_id[k] == best) at = &refined_pose[k];
    plain = verify_pose(voxels, semantic, *at, cfg.verify.max_points, weights);
  }
  const double weight = double(plain.agree) + plain.disagree;
  if (verify && plain.scored > 0) {
    const double q = weight > 0 ? (double(plain.agree) - plain.disagree) / weight : -1.0;
    quality = (double(cfg.verify.quality_high) - q) / (double(cfg.verify.quality_high) - cfg.verify.quality_low);
  }
  out.ambiguity = std::min(1.0, std::max({rival, support, quality}));
}

// 10. Refinement against the map's point layer (accepted only within its correction limit).
void Localizer::Impl::refine_answer(LocalizeResult& out) {
  Eigen::Isometry3d refined;
  RefineStats rs;
  if (refiner.refine(voxels, out.map_T_scan, &refined, &rs) == Status::Ok && rs.accepted) {
    out.map_T_scan = refined;
    out.refined = true;
  }
}

Status Localizer::localize(const ScanView& scan, LocalizeResult* out_ptr) {
  LocalizeResult scratch_result;
  LocalizeResult& out = out_ptr ? *out_ptr : scratch_result;
  out = LocalizeResult();
  if (!initialized_) return out.status = Status::NotInitialized;
  Impl& im = *impl_;
  const LocalizerConfig& cfg = config_;
  im.selected = 0;
  im.chosen = UINT32_MAX;
  im.instance_count = 0;
  const uint64_t t_start = now(clock_);
  uint64_t t = t_start;
  auto lap = [&](uint64_t* field) {
    const uint64_t n = now(clock_);
    *field += n - t;
    t = n;
  };
  auto finish = [&](Status s) {
    out.status = s;
    out.map_frame_T_scan = to_map_frame(map_.georef, out.map_T_scan);
    out.times.total = now(clock_) - t_start;
    return s;
  };
  if (scan.count > cfg.max_scan_points) return finish(Status::CapacityExceeded);

  Status s = im.build_voxels(scan, out);
  lap(&out.times.voxel);
  if (s != Status::Ok) return finish(s);
  s = im.find_instances(cfg, out);
  lap(&out.times.cluster);
  if (s != Status::Ok) return finish(s);
  if (im.instance_count < 3) return finish(Status::NoSolution);
  im.fit_query_fields(cfg, out);
  lap(&out.times.field);
  s = im.build_query_triangles(out);
  lap(&out.times.triangle);
  if (s != Status::Ok) return finish(s);
  im.vote_headings(cfg, map_, out);
  lap(&out.times.match);  // the heading votes are index matching too
  im.match_and_filter(cfg, map_, clock_, out);
  t = now(clock_);
  const uint32_t C = im.selected = im.select_correspondences(cfg, map_, out);
  if (C < cfg.hypotheses.min_inliers) return finish(Status::NoSolution);
  s = im.generate_hypotheses(cfg, C, out);
  lap(&out.times.clique);  // with the correspondence selection
  if (s != Status::Ok) return finish(Status::NoSolution);
  im.choose_answer(cfg, out);
  lap(&out.times.pose);
  if (cfg.refine.enabled && map_.counts.refine_points > 0) {
    im.refine_answer(out);
    lap(&out.times.refine);
  }
  return finish(Status::Ok);
}

PoseVerification Localizer::score_pose(const Eigen::Isometry3d& map_T_scan) const {
  if (!impl_) return PoseVerification();
  return verify_pose(impl_->voxels, impl_->semantic, map_T_scan, config_.verify.max_points, impl_->verify_weights);
}

uint32_t Localizer::last_instances(float* xyz, uint8_t* labels, uint32_t max) const {
  if (!impl_) return 0;
  const Impl& im = *impl_;
  for (uint32_t i = 0; i < im.instance_count && i < max; ++i) {
    for (int k = 0; k < 3; ++k) xyz[3 * i + k] = im.centroids[3 * i + k];
    labels[i] = im.labels[i];
  }
  return im.instance_count;
}

uint32_t Localizer::last_correspondences(Correspondence* out, uint32_t max) const {
  if (!impl_) return 0;
  const Impl& im = *impl_;
  for (uint32_t i = 0; i < im.selected && i < max; ++i) {
    const CorrespondenceAcc& c = im.corr[im.order[i]];
    out[i].query_instance = c.query;
    out[i].map_instance = c.map;
    for (int d = 0; d < 3; ++d) out[i].query_xyz[d] = im.a[3 * i + d];
    out[i].weight = c.weight;
    out[i].in_clique = im.chosen != UINT32_MAX && im.hypotheses.in_clique(im.chosen, i);
  }
  return im.selected;
}

}  // namespace gsf
