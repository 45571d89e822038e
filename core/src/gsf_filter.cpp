#include "gsf/detail/gsf_filter.h"

#include <cmath>

#include "gsf/detail/map_quantization.h"
#include "gsf/detail/wasserstein.h"

namespace gsf {
namespace {
constexpr double kTwoPi = 6.283185307179586;
}  // namespace

uint32_t triangle_yaw_bin(const float* q[3], const float* m[3], uint32_t bins) {
  float qc[2] = {0, 0}, mc[2] = {0, 0};
  for (int v = 0; v < 3; ++v)
    for (int d = 0; d < 2; ++d) {
      qc[d] += q[v][d] / 3.0f;
      mc[d] += m[v][d] / 3.0f;
    }
  float dot = 0.0f, cross = 0.0f;
  for (int v = 0; v < 3; ++v) {
    const float ax = q[v][0] - qc[0], ay = q[v][1] - qc[1];
    const float bx = m[v][0] - mc[0], by = m[v][1] - mc[1];
    dot += ax * bx + ay * by;
    cross += ax * by - ay * bx;
  }
  const double yaw = std::atan2(static_cast<double>(cross), static_cast<double>(dot));
  int64_t bin = static_cast<int64_t>(std::llround(yaw / kTwoPi * bins));
  bin = ((bin % int64_t(bins)) + bins) % bins;
  return static_cast<uint32_t>(bin);
}

size_t GsfFilter::required_bytes(const GsfFilterConfig& config, const FieldConfig& field) {
  return counted_bytes<GsfFilter>(config, field, nullptr);
}

Status GsfFilter::bind(Arena& ar, const GsfFilterConfig& config, const FieldConfig& field, FieldSolver* solver) {
  config_ = config;
  field_ = field;
  solver_ = solver;
  const uint32_t G = grid_points(field);
  if (config.yaw_bins == 0 || config.probe_cache_slots == 0 || config.similarity_cache_slots == 0)
    return Status::InvalidArgument;
  const bool ok = probe_slot_.bind(ar, config.probe_cache_slots) && similarity_.bind(ar, config.similarity_cache_slots);
  grid_ = ar.allocate<float>(size_t(G) * 3);
  probe_mean_ = ar.allocate<float>(size_t(config.probe_cache_slots + 1) * G * kNumClasses);
  probe_var_ = ar.allocate<float>(size_t(config.probe_cache_slots + 1) * G);
  map_mean_ = ar.allocate<float>(size_t(G) * kNumClasses);
  map_var_ = ar.allocate<float>(G);
  if (ar.counting()) return Status::Ok;
  if (!ok || !grid_ || !probe_mean_ || !probe_var_ || !map_mean_ || !map_var_ || !solver_)
    return Status::BufferTooSmall;
  stability_weights(weights_);
  reset();
  return Status::Ok;
}

void GsfFilter::reset() {
  probe_slot_.clear();
  similarity_.clear();
  probe_used_ = probe_overflow_ = comparisons_ = 0;
}

float GsfFilter::similarity(const QueryFields& qf, uint32_t qi, const MapView& map, uint32_t mi, uint32_t yaw_bin) {
  const uint64_t skey = similarity_key(qi, mi, yaw_bin);
  if (const float* cached = similarity_.find(skey)) return *cached;
  ++comparisons_;
  float omega = 0.0f;
  if (qf.m[qi] > 0) {
    const uint32_t G = grid_points(field_), M = qf.stride_m;
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
      solver_->probe(f, qf.chol + size_t(qi) * M * M, grid_, G, mean, var, nullptr);
    }
    dequantize_instance_grid(map, mi, map_mean_, map_var_);
    const ObservedW2 r = w2_squared_diag_observed(mean, var, map_mean_, map_var_, G, weights_,
                                                  config_.observed_variance * field_.signal_variance,
                                                  config_.normalize_mass, config_.covariance_weight);
    if (r.used >= 4) omega = static_cast<float>(std::exp(-(r.w2 / r.used) / config_.tau));
  }
  if (float* slot = similarity_.find_or_insert(skey)) *slot = omega;
  return omega;
}

}  // namespace gsf
