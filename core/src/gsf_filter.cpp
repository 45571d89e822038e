#include "gsf/detail/gsf_filter.h"

#include <algorithm>
#include <cmath>

#include "gsf/detail/angles.h"
#include "gsf/detail/map_quantization.h"
#include "gsf/detail/wasserstein.h"

namespace gsf {
namespace {

uint64_t now(Clock* c) { return c ? c->now_ns() : 0; }

// How many whole turns map the probe grid onto itself: the grid is centred, so a half turn re-indexes
// it; a square one (and the same spacing on both axes) a quarter turn too. Only turns that are whole
// numbers of yaw bins count.
uint32_t grid_turns(const FieldConfig& field, uint32_t yaw_bins) {
  if (yaw_bins % 4 == 0 && field.grid_nx == field.grid_ny) return 4;
  return yaw_bins % 2 == 0 ? 2 : 1;
}

// index[t G + g]: the point of the grid (layer by layer, row j by column i) that the grid's point g
// turned by -t whole turns lands on (make_probe_grid turns by -yaw). A quarter turn by -90 deg takes
// (x_i, y_j) to (y_j, -x_i) = (x_j, y_{n-1-i}) on a centred square grid; a half turn to
// (x_{nx-1-i}, y_{ny-1-j}).
void fill_turn_index(const FieldConfig& field, uint32_t turns, uint16_t* index) {
  const uint32_t nx = field.grid_nx, ny = field.grid_ny, layer = nx * ny, G = grid_points(field);
  for (uint32_t g = 0; g < G; ++g) index[g] = static_cast<uint16_t>(g);
  for (uint32_t t = 1; t < turns; ++t)
    for (uint32_t g = 0; g < G; ++g) {
      const uint32_t l = g / layer, j = (g % layer) / nx, i = g % nx;
      const uint32_t turned =
          turns == 4 ? l * layer + (nx - 1 - i) * nx + j : l * layer + (ny - 1 - j) * nx + (nx - 1 - i);
      index[t * G + g] = index[(t - 1) * G + turned];
    }
}

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
  probe_mean_ = ar.allocate<float>(size_t(config.probe_cache_slots + 2) * G * kNumClasses);
  probe_var_ = ar.allocate<float>(size_t(config.probe_cache_slots + 2) * G);
  const uint32_t turns = grid_turns(field, config.yaw_bins);
  turn_bins_ = config.yaw_bins / turns;
  turn_index_ = ar.allocate<uint16_t>(size_t(turns) * G);
  map_mean_ = ar.allocate<float>(size_t(kMapGridSlots) * G * kNumClasses);
  map_var_ = ar.allocate<float>(size_t(kMapGridSlots) * G);
  if (ar.counting()) return Status::Ok;
  if (!ok || !grid_ || !probe_mean_ || !probe_var_ || !map_mean_ || !map_var_ || !solver_ || !turn_index_ ||
      (max_triangles > 0 && !below_gate_))
    return Status::BufferTooSmall;
  fill_turn_index(field, turns, turn_index_);
  stability_weights(weights_);
  reset();
  return Status::Ok;
}

void GsfFilter::reset() {
  probe_slot_.clear();
  similarity_.clear();
  probe_used_ = probe_fits_ = comparisons_ = map_grids_ = 0;
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

uint32_t GsfFilter::probe_slot(uint32_t qi, uint32_t yaw_bin, uint32_t scratch, bool* fresh) {
  const uint64_t key = probe_key(qi, yaw_bin);
  if (const uint32_t* cached = probe_slot_.find(key)) {
    *fresh = false;
    return *cached;
  }
  *fresh = true;
  uint32_t* ps = probe_slot_.find_or_insert(key);
  if (!ps) return scratch;  // full cache: compute into scratch
  *ps = probe_used_++;
  return *ps;
}

void GsfFilter::fill_probe(const QueryFields& qf, uint32_t qi, uint32_t yaw_bin, uint32_t slot, float max_var) {
  const uint32_t base = yaw_bin % turn_bins_, turn = yaw_bin / turn_bins_;
  if (turn == 0) {
    regress_probe(qf, qi, yaw_bin, slot, max_var);
    return;
  }
  // The base bin's probe (cached, or into the other scratch slot), its points re-indexed.
  const uint32_t G = grid_points(field_), D = kNumClasses;
  bool base_fresh = false;
  const uint32_t from = probe_slot(qi, base, config_.probe_cache_slots, &base_fresh);
  if (base_fresh) regress_probe(qf, qi, base, from, max_var);
  const float* base_mean = probe_mean_ + size_t(from) * G * D;
  const float* base_var = probe_var_ + size_t(from) * G;
  float* mean = probe_mean_ + size_t(slot) * G * D;
  float* var = probe_var_ + size_t(slot) * G;
  const uint16_t* index = turn_index_ + size_t(turn) * G;
  for (uint32_t g = 0; g < G; ++g) {
    var[g] = base_var[index[g]];
    std::copy(base_mean + size_t(index[g]) * D, base_mean + size_t(index[g] + 1) * D, mean + size_t(g) * D);
  }
}

void GsfFilter::regress_probe(const QueryFields& qf, uint32_t qi, uint32_t yaw_bin, uint32_t slot, float max_var) {
  const uint32_t G = grid_points(field_), D = kNumClasses, M = qf.stride_m;
  float* mean = probe_mean_ + size_t(slot) * G * D;
  float* var = probe_var_ + size_t(slot) * G;
  // Map grid offsets g (map frame) are R^T g = Rz(-yaw) g in the query frame.
  const float yaw = static_cast<float>(kTwoPi * yaw_bin / config_.yaw_bins);
  make_probe_grid(field_, -yaw, grid_);
  FieldView f;
  f.inputs = qf.inputs + size_t(qi) * M * 3;
  f.alpha = qf.alpha + size_t(qi) * M * D;
  f.m = qf.m[qi];
  // The mean only at the observed points: the only ones compared.
  solver_->probe(f, qf.chol + size_t(qi) * M * M, grid_, G, mean, var, nullptr, max_var);
  ++probe_fits_;
}

float GsfFilter::similarity(const QueryFields& qf, uint32_t qi, const MapView& map, uint32_t mi, uint32_t yaw_bin) {
  const uint64_t skey = similarity_key(qi, mi, yaw_bin);
  if (const float* cached = similarity_.find(skey)) return *cached;
  ++comparisons_;
  float omega = 0.0f;
  if (qf.m[qi] > 0) {
    const uint32_t G = grid_points(field_);
    const float max_var = observed_max_var();  // grid points above it are neither probed for a mean nor compared
    bool fresh = false;
    const uint32_t slot = probe_slot(qi, yaw_bin, config_.probe_cache_slots + 1, &fresh);
    if (fresh) fill_probe(qf, qi, yaw_bin, slot, max_var);
    const float* mean = probe_mean_ + size_t(slot) * G * kNumClasses;
    const float* var = probe_var_ + size_t(slot) * G;
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
