// Internal (gsf/detail): a pipeline stage or building block, not part of the stable interface; it may
// change between versions. The stable interface is localizer.h, config.h, map_format.h, scan.h, status.h,
// platform.h, class_table.h, georeference.h, stage_configs.h, stage_results.h and the C API gsf.h.
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
#include "gsf/detail/correspondence_set.h"
#include "gsf/detail/fixed_vector.h"
#include "gsf/detail/gaussian_field.h"
#include "gsf/detail/heading_votes.h"
#include "gsf/detail/triangle.h"
#include "gsf/detail/triangle_index.h"
#include "gsf/detail/triangle_matcher.h"
#include "gsf/map_format.h"
#include "gsf/platform.h"
#include "gsf/semantic_classes.h"
#include "gsf/stage_configs.h"
#include "gsf/status.h"

namespace gsf {

// The query instances' fitted fields (arrays owned by the localizer's arena).
struct QueryFields {
  const float* inputs = nullptr;  // I x M x 3
  const float* alpha = nullptr;   // I x M x D
  const float* chol = nullptr;    // I x M x M
  const uint32_t* m = nullptr;    // I (0: no field)
  uint32_t stride_m = 0;          // M
};

// With fewer pairs than this from the matches that pass the gate, the matches below it fill the set
// (tier 0, ranked after every pair that passed; correspondence_set.h).
constexpr uint32_t kFillPairs = 64;

// How one scan's matches are found and gated (the localizer fills it from MatchConfig and GsfFilterConfig).
struct MatchFilterParams {
  float vertex_tie_tolerance = 0.06f;  // relative; query sides closer than this are tried in both orders
  bool use_gsf = true;                 // false: every match at a kept heading passes, with omega 1
  float min_similarity = 0.3f;         // a match passes when all three omegas reach this
  uint32_t fill_pairs = kFillPairs;    // fewer pairs than this: matches below the gate fill the set (tier 0)
};

// What one pass over a scan's matches saw (the localizer copies it into LocalizeResult).
struct MatchFilterStats {
  uint32_t match_candidates = 0;         // map triangles accepted by labels and sides, before the per-triangle cap
  uint32_t match_dropped = 0;            // ... dropped by the matcher's per-triangle limit
  uint32_t mirrored_matches = 0;         // candidates refused as mirror images
  uint32_t triangle_matches = 0;         // matches kept by the limit
  uint32_t tie_ordered_triangles = 0;    // query triangles also tried in a tied vertex order
  uint32_t heading_dropped = 0;          // kept matches whose heading the votes did not keep
  uint32_t survivors = 0;                // matches that passed the gate
  uint32_t below_gate_matches = 0;       // matches below the gate that filled a short pair set
  uint32_t candidate_pairs = 0;          // distinct (query, map) instance pairs accumulated
  uint32_t candidate_pairs_dropped = 0;  // pairs refused because the candidate set was full
  uint32_t field_probes = 0, field_comparisons = 0;  // GsfFilter::probes() and comparisons() after the pass
  uint64_t match_ns = 0;                             // time in index matching (the Clock's; 0 without one)
  uint64_t filter_ns = 0;                            // time in the heading check, the gate and the accumulation
};

class GsfFilter {
 public:
  static size_t required_bytes(const GsfFilterConfig& config, const FieldConfig& field, uint32_t max_triangles = 0);
  // `solver` (bound with the same FieldConfig) probes the query fields; it is shared with the stage
  // that fits them and must outlive the filter. max_triangles: the query triangles a scan can have, so
  // the fill pass re-matches only those with a match below the gate (0: it re-matches every one).
  Status bind(Arena& arena, const GsfFilterConfig& config, const FieldConfig& field, FieldSolver* solver,
              uint32_t max_triangles = 0);
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
    return fields.m[qi] == 0 || probe_slot_.find(probe_key(qi, yaw_bin)) != nullptr ||
           probe_slot_.find(probe_key(qi, yaw_bin % turn_bins_)) != nullptr;
  }

  // Query-field probes evaluated since reset() (the field's regressions; a probe a whole turn of the
  // grid away is a permuted copy, not counted).
  uint32_t probes() const { return probe_fits_; }
  uint32_t comparisons() const { return comparisons_; }
  uint32_t map_grids() const { return map_grids_; }  // map instances' grids dequantised since reset()

  // The filter over one scan's matches (the localizer's steps 5b and 6): per query triangle its ranked
  // index matches (`matcher`, its limit set by the caller), those at a heading `headings` kept, then the
  // gate; each passing match adds its three vertex pairs to `pairs` (cleared first) with their omegas.
  // Nothing is stored per match, so no cap on matches can cut in storage order. Forgets the caches first.
  //
  // The gate is absolute, and a scan whose instances are far and sparsely seen (an approach road) can
  // have its true matches all below it: with fewer than fill_pairs pairs, a second pass adds the matches
  // below the gate as tier-0 pairs, ranked after every pair that passed and taken only up to fill_pairs
  // in all (correspondence_set.h). A scan with enough pairs never runs it, so the filter decides exactly
  // as before wherever it has candidates to spare.
  MatchFilterStats filter_matches(const FixedVector<Triangle>& triangles, const float* query_centroids,
                                  const QueryFields& fields, TriangleMatcher& matcher, const TriangleIndexView& index,
                                  const MapView& map, const TriangleConfig& triangle_config,
                                  const HeadingVotes& headings, const MatchFilterParams& params, Clock* clock,
                                  CorrespondenceSet& pairs);

 private:
  // Whether all three omegas of a match (query vertices qv, map triangle mt, yaw bin) reach
  // min_similarity; omega[v] gets each one evaluated. `all`: evaluate all three even after a failure.
  bool passes_gate(const QueryFields& fields, const uint32_t qv[3], const Triangle& mt, const MapView& map,
                   uint32_t bin, float min_similarity, bool all, float omega[3]);
  // Grid points where the query field's variance exceeds this are not compared.
  float observed_max_var() const { return config_.observed_variance * field_.signal_variance; }
  static uint64_t similarity_key(uint32_t qi, uint32_t mi, uint32_t yaw_bin) {
    return (uint64_t(qi) << 44) | (uint64_t(yaw_bin) << 32) | mi;
  }
  static uint64_t probe_key(uint32_t qi, uint32_t yaw_bin) { return (uint64_t(qi) << 32) | yaw_bin; }
  // The probe of (qi, yaw_bin) into a cache slot (the scratch slot `scratch` when the cache is full);
  // returns the slot and whether it is new (to be filled).
  uint32_t probe_slot(uint32_t qi, uint32_t yaw_bin, uint32_t scratch, bool* fresh);
  // Fills the probe of (qi, yaw_bin) into `slot`: the field's regression at the grid turned by the
  // bin's angle, or for a bin a whole turn of the grid past a base bin, the base's probe permuted.
  void fill_probe(const QueryFields& qf, uint32_t qi, uint32_t yaw_bin, uint32_t slot, float max_var);
  // The field's regression at the grid turned by yaw_bin's angle, into `slot`.
  void regress_probe(const QueryFields& qf, uint32_t qi, uint32_t yaw_bin, uint32_t slot, float max_var);
  GsfFilterConfig config_{};
  FieldConfig field_{};
  FieldSolver* solver_ = nullptr;
  BoundedHashMap<uint32_t> probe_slot_;  // (query instance, yaw bin) -> cache slot
  BoundedHashMap<float> similarity_;     // (query instance, map instance, yaw bin) -> omega
  float* grid_ = nullptr;                // G x 3
  // The map instances' grids dequantised, direct-mapped by instance: a zone's scan compares some 70 map
  // instances 13,000 times (query instances x yaw bins), and dequantising each time was a third of the
  // filter's instructions there.
  static constexpr uint32_t kMapGridSlots = 128;
  const float* map_grid(const MapView& map, uint32_t mi, const float** var);
  float* map_mean_ = nullptr;                  // kMapGridSlots x G x D
  float* map_var_ = nullptr;                   // kMapGridSlots x G
  uint32_t map_grid_instance_[kMapGridSlots];  // the instance in each slot (UINT32_MAX: none)
  uint32_t map_grids_ = 0;                     // grids dequantised since reset()
  float* probe_mean_ = nullptr;                // (slots + 2) x G x D; the last two are scratch when the cache is full
  float* probe_var_ = nullptr;                 // (slots + 2) x G
  // The grid's symmetry: a square grid turned a quarter (a rectangle: a half) turn is the same points,
  // re-indexed. Bins turn_bins_ apart share one regression (yaw_bins when neither applies).
  uint32_t turn_bins_ = 1;
  uint16_t* turn_index_ = nullptr;  // (yaw_bins / turn_bins_) x G: point g of the grid turned t times is
                                    // point turn_index_[t G + g] of the grid itself
  float weights_[kNumClasses];
  uint8_t* below_gate_ = nullptr;  // max_triangles_: 1 where pass 0 saw a match below the gate
  uint32_t max_triangles_ = 0;
  uint32_t probe_used_ = 0, probe_fits_ = 0, comparisons_ = 0;
};

}  // namespace gsf
