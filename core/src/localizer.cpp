#include "gsf/localizer.h"

#include <algorithm>
#include <cmath>
#include <new>

#include "gsf/bounded_hash_map.h"
#include "gsf/fixed_vector.h"
#include "gsf/gaussian_field.h"
#include "gsf/gsf_filter.h"
#include "gsf/instance_clustering.h"
#include "gsf/pose_hypotheses.h"
#include "gsf/refine.h"
#include "gsf/semantic_grid.h"
#include "gsf/triangle.h"
#include "gsf/triangle_index.h"
#include "gsf/triangle_matcher.h"
#include "gsf/voxel_layer.h"
#include "gsf/wasserstein.h"

namespace gsf {
namespace {

struct CorrespondenceAcc {
  uint32_t query, map;
  float weight;   // best GSF similarity seen for this pair (1 without GSF)
  uint32_t votes; // surviving triangle matches that produced it
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
  VoxelLayer voxels;
  InstanceClustering clusters;
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
  float weights[kNumClasses];
  uint32_t* heading_votes = nullptr;  // yaw bins
  uint8_t* heading_allowed = nullptr; // yaw bins
  // Correspondences.
  CorrespondenceAcc* corr = nullptr;  // candidates (capacity corr_capacity)
  uint32_t corr_count = 0;
  uint32_t corr_capacity = 0;
  uint32_t* order = nullptr;          // selection scratch (corr_capacity)
  float* a = nullptr;                 // C x 3 query positions
  float* b = nullptr;                 // C x 3 map positions
  float* w = nullptr;                 // C weights
  uint32_t selected = 0;              // correspondences given to the hypothesis stage in the last call
  uint32_t chosen = 0;                // the answer's hypothesis in the last call (UINT32_MAX: none)
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
  if (im.clusters.bind(ar, config.cluster, config.voxel.max_voxels) != Status::Ok) return Status::InvalidArgument;
  record(&b.cluster);
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
  if (im.gsf.bind(ar, config.gsf, config.field, &im.solver) != Status::Ok && !ar.counting()) return Status::InvalidArgument;
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
  const size_t parts = b.voxel + b.cluster + b.field + b.triangle + b.match + b.gsf_cache + b.correspondence + b.clique + b.refine;
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
  if ((map.instances == nullptr && map.counts.instances > 0) || map.index_offsets == nullptr) return Status::InvalidArgument;
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
  im.semantic = map.semantic_grid();
  im.chosen = UINT32_MAX;
  impl_ = &im;
  initialized_ = true;
  return Status::Ok;
}

namespace {

uint64_t now(Clock* c) { return c ? c->now_ns() : 0; }

}  // namespace

Status Localizer::localize(const ScanView& scan, LocalizeResult* out_ptr) {
  LocalizeResult scratch_result;
  LocalizeResult& out = out_ptr ? *out_ptr : scratch_result;
  out = LocalizeResult();
  if (!initialized_) return out.status = Status::NotInitialized;
  Impl& im = *impl_;
  const LocalizerConfig& cfg = config_;
  im.selected = 0;
  im.chosen = UINT32_MAX;
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

  // 5 + 6. Per query triangle: ranked index matches, then the GSF filter, accumulating weighted,
  // deduplicated vertex correspondences. Nothing is stored per triangle match, so no global cap on
  // matches exists that could cut in storage order.
  im.gsf.reset();
  im.corr_index.clear();
  im.corr_count = 0;
  const QueryFields qf{im.q_inputs, im.q_alpha, im.q_chol, im.q_m, M};
  uint64_t t_match = 0, t_gsf = 0;
  uint32_t survivors = 0;
  const uint32_t T = im.triangles.size();
  auto match_bin = [&](const Triangle& qt, const RankedTriangleMatch& rm, uint32_t* qv) {
    const Triangle& mt = map_.triangles[rm.map];
    for (int v = 0; v < 3; ++v) qv[v] = TriangleMatcher::query_vertex(qt, rm.order, v);
    const float* qp[3] = {im.centroids + 3 * qv[0], im.centroids + 3 * qv[1], im.centroids + 3 * qv[2]};
    const float* mp[3] = {map_.instances[mt.v[0]].centroid, map_.instances[mt.v[1]].centroid,
                          map_.instances[mt.v[2]].centroid};
    return triangle_yaw_bin(qp, mp, cfg.gsf.yaw_bins);
  };
  // 5a. Heading votes: the matches of an evenly spaced sample of query triangles vote for their yaw
  // bin; only the best-supported headings (and their neighbour bins) go on. True matches agree on one
  // heading (a lattice's symmetries add a few more), wrong ones spread over all of them; this bounds
  // the distinct (instance, heading) probes of the GSF filter by instances x kept bins.
  const uint32_t B = cfg.gsf.yaw_bins;
  for (uint32_t b = 0; b < B; ++b) im.heading_allowed[b] = cfg.match.heading_bins == 0 ? 1 : 0;
  if (cfg.match.heading_bins > 0 && T > 0) {
    for (uint32_t b = 0; b < B; ++b) im.heading_votes[b] = 0;
    const uint32_t stride = (T + cfg.match.heading_sample_triangles - 1) / cfg.match.heading_sample_triangles;
    uint32_t qv[3];
    for (uint32_t qt_id = 0; qt_id < T; qt_id += stride) {
      const Triangle& qt = im.triangles[qt_id];
      im.matcher.match(qt, im.index, map_.triangles, cfg.triangle, cfg.match.vertex_tie_tolerance);
      for (uint32_t k = 0; k < im.matcher.size(); ++k) ++im.heading_votes[match_bin(qt, im.matcher.match_at(k), qv)];
    }
    for (uint32_t pick = 0; pick < cfg.match.heading_bins && pick < B; ++pick) {
      uint32_t best = UINT32_MAX;
      for (uint32_t b = 0; b < B; ++b)
        if (im.heading_votes[b] > 0 && (best == UINT32_MAX || im.heading_votes[b] > im.heading_votes[best])) best = b;
      if (best == UINT32_MAX) break;
      im.heading_votes[best] = 0;
      im.heading_allowed[best] = im.heading_allowed[(best + 1) % B] = im.heading_allowed[(best + B - 1) % B] = 1;
    }
  }
  for (uint32_t b = 0; b < B; ++b) out.headings_kept += im.heading_allowed[b];
  t_match = now(clock_) - t;  // the heading votes (and the per-scan resets above) are index matching too
  for (uint32_t qt_id = 0; qt_id < T; ++qt_id) {
    const Triangle& qt = im.triangles[qt_id];
    const uint64_t t0 = now(clock_);
    const TriangleMatchStats ms = im.matcher.match(qt, im.index, map_.triangles, cfg.triangle, cfg.match.vertex_tie_tolerance);
    const uint64_t t1 = now(clock_);
    t_match += t1 - t0;
    out.match_candidates += ms.accepted;
    out.match_dropped += ms.dropped();
    out.triangle_matches += ms.kept;
    if (ms.orders > 1) ++out.tie_ordered_triangles;
    for (uint32_t k = 0; k < im.matcher.size(); ++k) {
      const RankedTriangleMatch& rm = im.matcher.match_at(k);
      const Triangle& mt = map_.triangles[rm.map];
      uint32_t qv[3];
      const uint32_t bin = match_bin(qt, rm, qv);
      if (!im.heading_allowed[bin]) {
        ++out.heading_dropped;
        continue;
      }
      float omega[3] = {1.0f, 1.0f, 1.0f};
      if (cfg.match.use_gsf) {
        bool keep = true;
        for (int v = 0; v < 3 && keep; ++v) {
          omega[v] = im.gsf.similarity(qf, qv[v], map_, mt.v[v], bin);
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
        uint32_t* id = im.corr_index.find_or_insert(key, &inserted);
        if (!id || (inserted && im.corr_count >= im.corr_capacity)) { ++out.candidate_pairs_dropped; continue; }
        if (inserted) {
          *id = im.corr_count;
          im.corr[im.corr_count++] = CorrespondenceAcc{qv[v], mt.v[v], 0.0f, 0};
        }
        CorrespondenceAcc& c = im.corr[*id];
        c.weight = std::max(c.weight, omega[v]);
        c.votes += 1;
      }
    }
    t_gsf += now(clock_) - t1;
  }
  out.times.match = t_match;
  out.times.gsf = t_gsf;
  t = now(clock_);
  out.gsf_survivors = survivors;
  out.field_probes = im.gsf.probes();
  out.field_comparisons = im.gsf.comparisons();
  out.candidate_pairs = im.corr_count;
  if (out.match_dropped > 0 || out.candidate_pairs_dropped > 0 || out.heading_dropped > 0) out.capacity_truncated = true;

  // 7. Keep the best-supported correspondences (votes x weight) up to the clique capacity; equal
  // support is broken by a hash of the pair, never by instance id (map ids follow map x order).
  const uint32_t total = im.corr_count;
  for (uint32_t i = 0; i < total; ++i) im.order[i] = i;
  const CorrespondenceAcc* corr = im.corr;
  std::sort(im.order, im.order + total, [corr](uint32_t x, uint32_t y) {
    const float sx = corr[x].weight * float(corr[x].votes), sy = corr[y].weight * float(corr[y].votes);
    if (sx != sy) return sx > sy;
    const uint64_t hx = mix64((uint64_t(corr[x].query) << 32) | corr[x].map);
    const uint64_t hy = mix64((uint64_t(corr[y].query) << 32) | corr[y].map);
    if (hx != hy) return hx < hy;
    return x < y;
  });
  const uint32_t C = std::min(total, cfg.match.max_correspondences);
  out.correspondences_dropped = total - C;
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
  if (C < cfg.hypotheses.min_inliers) return finish(Status::NoSolution);

  // 8. Pose hypotheses: peeled maximum cliques, each with its weighted TLS pose.
  HypothesisStats hs;
  s = im.hypotheses.generate(im.a, im.b, im.w, C, cfg.hypotheses, &hs);
  out.clique_nodes = hs.nodes;
  out.clique_searches = hs.searches;
  out.budget_exhausted = hs.budget_exhausted;
  out.hypotheses = im.hypotheses.size();
  lap(&out.times.clique);
  if (s != Status::Ok) return finish(Status::NoSolution);

  // 9. Whole-scan verification against the map's semantic layer picks among the hypotheses; the
  // ambiguity is how clearly the chosen one beats the runner-up.
  const uint32_t H = im.hypotheses.size();
  const bool verify = cfg.verify.enabled && !im.semantic.empty();
  uint32_t best = 0, second = UINT32_MAX;
  if (verify) {
    // Coarse score for every hypothesis, the full score for the best `full_top`, then the best
    // `refine_top` at their best local alignment. Each step ranks, then caps.
    uint8_t full[PoseHypotheses::kMaxHypotheses];
    uint32_t top[PoseHypotheses::kMaxHypotheses];
    const uint32_t coarse_points = std::max<uint32_t>(1, cfg.verify.max_points / cfg.verify.coarse_divisor);
    for (uint32_t h = 0; h < H; ++h) {
      im.hypotheses[h].verification =
          verify_pose(im.voxels, im.semantic, im.hypotheses[h].map_T_scan, coarse_points, im.weights);
      full[h] = 0;
    }
    uint32_t nt = top_by_score(im.hypotheses, H, nullptr, cfg.verify.full_top, top);
    for (uint32_t k = 0; k < nt; ++k) {
      im.hypotheses[top[k]].verification =
          verify_pose(im.voxels, im.semantic, im.hypotheses[top[k]].map_T_scan, cfg.verify.max_points, im.weights);
      full[top[k]] = 1;
    }
    nt = cfg.verify.refine_rounds > 0 ? top_by_score(im.hypotheses, H, full, cfg.verify.refine_top, top) : 0;
    for (uint32_t k = 0; k < nt; ++k)
      im.hypotheses[top[k]].verification =
          verify_pose_refined(im.voxels, im.semantic, im.hypotheses[top[k]].map_T_scan, cfg.verify.max_points,
                              im.weights, cfg.verify.refine_rounds, cfg.verify.refine_step_m,
                              cfg.verify.refine_step_deg, nullptr);
    nt = top_by_score(im.hypotheses, H, full, 2, top);  // answer and runner-up among fully scored ones
    best = nt > 0 ? top[0] : 0;
    second = nt > 1 ? top[1] : UINT32_MAX;
  } else {
    second = H > 1 ? 1 : UINT32_MAX;
  }
  const PoseHypothesis& answer = im.hypotheses[best];
  out.map_T_scan = answer.map_T_scan;
  out.inliers = answer.inliers;
  out.clique_size = answer.clique_size;
  out.score = answer.support;
  out.chosen_hypothesis = best;
  out.verified = verify;
  im.chosen = best;
  // Report the best hypotheses by verified score (the order found without verification).
  uint32_t shown[kMaxReportedHypotheses];
  uint32_t reported = std::min(H, kMaxReportedHypotheses);
  if (verify) reported = top_by_score(im.hypotheses, H, nullptr, kMaxReportedHypotheses, shown);
  else for (uint32_t k = 0; k < reported; ++k) shown[k] = k;
  for (uint32_t k = 0; k < reported; ++k) {
    const PoseHypothesis& p = im.hypotheses[shown[k]];
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
  }
  // Weak support is ambiguity too: an answer resting on k inliers is at least min_inliers / k ambiguous
  // (a bare-minimum clique with nothing competing is still a guess).
  const double support = double(cfg.hypotheses.min_inliers) / double(answer.inliers);
  double rival = 0.0;
  if (second != UINT32_MAX) {
    if (verify) {
      const double margin = double(answer.verification.score) - im.hypotheses[second].verification.score;
      const double scale = double(cfg.verify.margin_scale) * std::max<uint32_t>(answer.verification.scored, 1);
      rival = std::exp(-std::max(0.0, margin) / scale);
    } else {
      rival = answer.support > 0 ? im.hypotheses[second].support / answer.support : 1.0;
    }
  }
  // A verified answer that agrees poorly with the map is doubtful even without a rival (its true
  // competitor may simply not be among the hypotheses): agreement per scored voxel below
  // quality_high adds ambiguity, reaching 1 at quality_low.
  double quality = 0.0;
  if (verify && answer.verification.scored > 0) {
    const double q = double(answer.verification.score) / answer.verification.scored;
    quality = (double(cfg.verify.quality_high) - q) / (double(cfg.verify.quality_high) - cfg.verify.quality_low);
  }
  out.ambiguity = std::min(1.0, std::max({rival, support, quality}));
  lap(&out.times.pose);

  // 10. Optional refinement against the map's point layer.
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

PoseVerification Localizer::score_pose(const Eigen::Isometry3d& map_T_scan) const {
  if (!impl_) return PoseVerification();
  return verify_pose(impl_->voxels, impl_->semantic, map_T_scan, config_.verify.max_points, impl_->weights);
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
