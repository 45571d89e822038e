#include "gsf/detail/gsf_filter.h"

#include <cmath>

#include "gsf/detail/angles.h"
#include "gsf/detail/map_quantization.h"
#include "gsf/detail/wasserstein.h"

namespace gsf {
namespace {

uint64_t now(Clock* c) { return c ? c->now_ns() : 0; }
}  // namespace

size_t GsfFilter::required_bytes(const GsfFilterConfig& config, const FieldConfig& field, uint32_t max_triangles) {
  return counted_bytes<GsfFilter>(config, field, nullptr, max_triangles);
}

Status GsfFilter::bind(Arena& ar, const GsfFilterConfig& config, const FieldConfig& field, FieldSolver* solver,
                       uint32_t max_triangles) {
  config_ = config;
  field_ = field;
  solver_ = solver;
  max_triangles_ = max_triangles;
  below_gate_ = max_triangles > 0 ? ar.allocate<uint8_t>(max_triangles) : nullptr;
  const uint32_t G = grid_points(field);
  if (config.yaw_bins == 0 || config.probe_cache_slots == 0 || config.similarity_cache_slots == 0)
    return Status::InvalidArgument;
  const bool ok = probe_slot_.bind(ar, config.probe_cache_slots) && similarity_.bind(ar, config.similarity_cache_slots);
  grid_ = ar.allocate<float>(size_t(G) * 3);
  probe_mean_ = ar.allocate<float>(size_t(config.probe_cache_slots + 1) * G * kNumClasses);
  probe_var_ = ar.allocate<float>(size_t(config.probe_cache_slots + 1) * G);
  map_mean_ = ar.allocate<float>(size_t(kMapGridSlots) * G * kNumClasses);
  map_var_ = ar.allocate<float>(size_t(kMapGridSlots) * G);
  if (ar.counting()) return Status::Ok;
  if (!ok || !grid_ || !probe_mean_ || !probe_var_ || !map_mean_ || !map_var_ || !solver_ ||
      (max_triangles > 0 && !below_gate_))
    return Status::BufferTooSmall;
  stability_weights(weights_);
  reset();
  return Status::Ok;
}

void GsfFilter::reset() {
  probe_slot_.clear();
  similarity_.clear();
  probe_used_ = probe_overflow_ = comparisons_ = map_grids_ = 0;
  for (uint32_t& i : map_grid_instance_) i = UINT32_MAX;
}

// Map instance mi's grid dequantised (its variances into *var), from its slot or into it.
const float* GsfFilter::map_grid(const MapView& map, uint32_t mi, const float** var) {
  const uint32_t G = grid_points(field_), slot = mi % kMapGridSlots;
  float* mean = map_mean_ + size_t(slot) * G * kNumClasses;
  *var = map_var_ + size_t(slot) * G;
  if (map_grid_instance_[slot] != mi) {
    dequantize_instance_grid(map, mi, mean, map_var_ + size_t(slot) * G, nullptr);
    map_grid_instance_[slot] = mi;
    ++map_grids_;
  }
  return mean;
}

float GsfFilter::similarity(const QueryFields& qf, uint32_t qi, const MapView& map, uint32_t mi, uint32_t yaw_bin) {
  const uint64_t skey = similarity_key(qi, mi, yaw_bin);
  if (const float* cached = similarity_.find(skey)) return *cached;
  ++comparisons_;
  float omega = 0.0f;
  if (qf.m[qi] > 0) {
    const uint32_t G = grid_points(field_), M = qf.stride_m;
    const float max_var = observed_max_var();  // grid points above it are neither probed for a mean nor compared
    const uint64_t pkey = (uint64_t(qi) << 32) | yaw_bin;
    uint32_t slot;
    bool fresh = false;
    if (uint32_t* ps = probe_slot_.find(pkey)) {
      slot = *ps;
    } else {
      ps = probe_slot_.find_or_insert(pkey);
      if (ps) {
        slot = probe_used_++;
        *ps = slot;
      } else {
        slot = config_.probe_cache_slots;  // full cache: compute into scratch
        ++probe_overflow_;
      }
      fresh = true;
    }
    float* mean = probe_mean_ + size_t(slot) * G * kNumClasses;
    float* var = probe_var_ + size_t(slot) * G;
    if (fresh) {
      // Map grid offsets g (map frame) are R^T g = Rz(-yaw) g in the query frame.
      const float yaw = static_cast<float>(kTwoPi * yaw_bin / config_.yaw_bins);
      make_probe_grid(field_, -yaw, grid_);
      FieldView f;
      f.inputs = qf.inputs + size_t(qi) * M * 3;
      f.alpha = qf.alpha + size_t(qi) * M * kNumClasses;
      f.m = qf.m[qi];
      // The mean only at the observed points: the only ones compared.
      solver_->probe(f, qf.chol + size_t(qi) * M * M, grid_, G, mean, var, nullptr, max_var);
    }
    // The map's grid whole (compared where the query field is observed), once per map instance.
    const float* map_var = nullptr;
    const float* map_mean = map_grid(map, mi, &map_var);
    const ObservedW2 r =
        w2_squared_diag_observed(mean, var, map_mean, map_var, G, weights_, max_var, config_.covariance_weight);
    if (r.used >= 4) omega = static_cast<float>(std::exp(-(r.w2 / r.used) / config_.tau));
  }
  if (float* slot = similarity_.find_or_insert(skey)) *slot = omega;
  return omega;
}

MatchFilterStats GsfFilter::filter_matches(const FixedVector<Triangle>& triangles, const float* query_centroids,
                                           const QueryFields& qf, TriangleMatcher& matcher,
                                           const TriangleIndexView& index, const MapView& map,
                                           const TriangleConfig& triangle_config, const HeadingVotes& headings,
                                           const MatchFilterParams& params, Clock* clock, CorrespondenceSet& pairs) {
  reset();
  pairs.clear();
  MatchFilterStats st;
  const uint32_t T = triangles.size();
  const bool fill = params.use_gsf && params.fill_pairs > 0;
  // Which triangles the fill pass must match again (all of them when the filter has no room to say).
  const bool mark = fill && T <= max_triangles_;
  if (mark)
    for (uint32_t t = 0; t < T; ++t) below_gate_[t] = 0;
  for (int pass = 0; pass < (fill ? 2 : 1); ++pass) {
    if (pass == 1 && pairs.candidates() >= params.fill_pairs) break;
    for (uint32_t qt_id = 0; qt_id < T; ++qt_id) {
      if (pass == 1 && mark && !below_gate_[qt_id]) continue;  // it has no match below the gate
      const Triangle& qt = triangles[qt_id];
      const uint64_t t0 = now(clock);
      const TriangleMatchStats ms =
          matcher.match(qt, index, map.triangles, triangle_config, params.vertex_tie_tolerance);
      const uint64_t t1 = now(clock);
      st.match_ns += t1 - t0;
      if (pass == 0) {
        st.match_candidates += ms.accepted;
        st.match_dropped += ms.dropped();
        st.mirrored_matches += ms.mirrored;
        st.triangle_matches += ms.kept;
        if (ms.orders > 1) ++st.tie_ordered_triangles;
      }
      for (uint32_t k = 0; k < matcher.size(); ++k) {
        const RankedTriangleMatch& rm = matcher.match_at(k);
        const Triangle& mt = map.triangles[rm.map];
        uint32_t qv[3];
        const uint32_t bin = match_yaw_bin(qt, rm, query_centroids, map, config_.yaw_bins, qv);
        if (!headings.allowed(bin)) {
          if (pass == 0) ++st.heading_dropped;
          continue;
        }
        float omega[3] = {1.0f, 1.0f, 1.0f};
        // Pass 0 keeps the matches that pass the gate, pass 1 (the fill) the others, with all three omegas.
        if (params.use_gsf &&
            passes_gate(qf, qv, mt, map, bin, params.min_similarity, pass == 1, omega) == (pass == 1)) {
          if (pass == 0 && mark) below_gate_[qt_id] = 1;
          continue;
        }
        ++(pass == 0 ? st.survivors : st.below_gate_matches);
        for (int v = 0; v < 3; ++v)
          if (!pairs.add(qv[v], mt.v[v], omega[v], pass == 0 ? 1u : 0u)) ++st.candidate_pairs_dropped;
      }
      st.filter_ns += now(clock) - t1;
    }
  }
  st.field_probes = probes();
  st.field_comparisons = comparisons();
  st.candidate_pairs = pairs.candidates();
  return st;
}

// The cheapest omegas go first and the first failure stops: cached similarities (step 0), then
// comparisons against a cached probe (step 1), then those needing a new query probe (step 2). The
// decision and the passing matches' omegas are the vertex-order loop's; only fewer probes and
// comparisons are made.
bool GsfFilter::passes_gate(const QueryFields& qf, const uint32_t qv[3], const Triangle& mt, const MapView& map,
                            uint32_t bin, float min_similarity, bool all, float omega[3]) {
  bool keep = true;
  uint32_t done = 0;
  for (int step = 0; step < 3 && (keep || all); ++step)
    for (int v = 0; v < 3 && (keep || all); ++v) {
      if (done & (1u << v)) continue;
      if (step == 0) {
        const float* c = cached_similarity(qv[v], mt.v[v], bin);
        if (c == nullptr) continue;
        omega[v] = *c;
      } else {
        if (step == 1 && !probe_ready(qf, qv[v], bin)) continue;
        omega[v] = similarity(qf, qv[v], map, mt.v[v], bin);
      }
      done |= 1u << v;
      keep = keep && omega[v] >= min_similarity;
    }
  return keep;
}

}  // namespace gsf
