// Internal (gsf/detail): a pipeline stage or building block, not part of the stable interface; it may
// change between versions. The stable interface is localizer.h, config.h, map_format.h, scan.h, status.h,
// platform.h, class_table.h, georeference.h and the C API gsf.h.
// The GSF fine filter (paper Sec. III-B/C): the similarity omega in [0, 1] of a query instance's
// Gaussian semantic field and a map instance's, under the yaw hypothesis of a triangle match.
//
// The map stores each instance's posterior on its canonical (yaw 0) probe grid. The query field is
// probed on that grid rotated into the query frame by the hypothesis, so both describe the same
// physical neighbourhood; the map is never re-probed. Query probes are cached per (query instance,
// yaw bin) and similarities per (query instance, map instance, yaw bin): a lattice produces thousands
// of triangle matches but only hundreds of distinct comparisons. When a cache is full the value is
// computed into scratch (correct, just not remembered).
#pragma once
#include <cstdint>

#include "gsf/detail/arena.h"
#include "gsf/detail/bounded_hash_map.h"
#include "gsf/detail/gaussian_field.h"
#include "gsf/map_format.h"
#include "gsf/semantic_classes.h"
#include "gsf/status.h"

namespace gsf {

struct GsfFilterConfig {
  uint32_t yaw_bins = 36;                   // rotation hypotheses are binned for probe caching (10 deg)
  uint32_t probe_cache_slots = 1024;        // cached query-field probes (instance, yaw bin)
  uint32_t similarity_cache_slots = 65536;  // cached omega per (query instance, map instance, yaw bin)
  float observed_variance = 0.6f;           // grid points where the query field's variance exceeds this
                                            // fraction of the prior are unobserved and not compared
  float normalize_mass = 0.0f;              // >0: compare per-point class distributions (wasserstein.h)
  float covariance_weight = 0.0f;           // weight of the W2 covariance term (1 = the paper's W2)
  float tau = 0.2f;                         // omega = exp(-w2 / tau), w2 per compared grid point
};

// The query instances' fitted fields (arrays owned by the localizer's arena).
struct QueryFields {
  const float* inputs = nullptr;  // I x M x 3
  const float* alpha = nullptr;   // I x M x D
  const float* chol = nullptr;    // I x M x M
  const uint32_t* m = nullptr;    // I (0: no field)
  uint32_t stride_m = 0;          // M
};

// Yaw bin of the 2-D Procrustes rotation taking the query vertices qa, qb, qc onto the map vertices
// (xyz each); the vehicle is near level, the full 3-D pose comes later from the clique.
uint32_t triangle_yaw_bin(const float* q[3], const float* m[3], uint32_t yaw_bins);

class GsfFilter {
 public:
  static size_t required_bytes(const GsfFilterConfig& config, const FieldConfig& field);
  // `solver` (bound with the same FieldConfig) probes the query fields; it is shared with the stage
  // that fits them and must outlive the filter.
  Status bind(Arena& arena, const GsfFilterConfig& config, const FieldConfig& field, FieldSolver* solver);
  void reset();  // forget the caches (a new scan)
  // Class weights of the W2 sum (default after bind: stability_weight(), paper Table III); a label set
  // with its own stabilities sets them here (copied).
  void set_class_weights(const float* weights) {
    for (int c = 0; c < kNumClasses; ++c) weights_[c] = weights[c];
  }
  float similarity(const QueryFields& fields, uint32_t qi, const MapView& map, uint32_t mi, uint32_t yaw_bin);
  // What similarity() would cost, without doing it: the omega if it is cached (else nullptr), and
  // whether no new query probe is needed (the probe of (qi, yaw_bin) is cached or qi has no field), so
  // a caller that needs several similarities can evaluate the cheap ones first.
  const float* cached_similarity(uint32_t qi, uint32_t mi, uint32_t yaw_bin) const {
    return similarity_.find(similarity_key(qi, mi, yaw_bin));
  }
  bool probe_ready(const QueryFields& fields, uint32_t qi, uint32_t yaw_bin) const {
    return fields.m[qi] == 0 || probe_slot_.find((uint64_t(qi) << 32) | yaw_bin) != nullptr;
  }

  uint32_t probes() const { return probe_used_ + probe_overflow_; }
  uint32_t comparisons() const { return comparisons_; }

 private:
  static uint64_t similarity_key(uint32_t qi, uint32_t mi, uint32_t yaw_bin) {
    return (uint64_t(qi) << 44) | (uint64_t(yaw_bin) << 32) | mi;
  }
  GsfFilterConfig config_{};
  FieldConfig field_{};
  FieldSolver* solver_ = nullptr;
  BoundedHashMap<uint32_t> probe_slot_;  // (query instance, yaw bin) -> cache slot
  BoundedHashMap<float> similarity_;     // (query instance, map instance, yaw bin) -> omega
  float* grid_ = nullptr;                // G x 3
  float* map_mean_ = nullptr;            // G x D, the compared map instance's grid dequantised
  float* map_var_ = nullptr;             // G
  float* probe_mean_ = nullptr;          // (slots + 1) x G x D; the last slot is scratch when the cache is full
  float* probe_var_ = nullptr;           // (slots + 1) x G
  float weights_[kNumClasses];
  uint32_t probe_used_ = 0, probe_overflow_ = 0, comparisons_ = 0;
};

}  // namespace gsf
