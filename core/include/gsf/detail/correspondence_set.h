// Internal (gsf/detail): a pipeline stage or building block, not part of the stable interface; it may
// change between versions. The stable interface is localizer.h, config.h, map_format.h, scan.h, status.h,
// platform.h, class_table.h, georeference.h, stage_configs.h, stage_results.h and the C API gsf.h.
// Correspondence accumulation and selection (between the GSF filter and the max clique). Every
// triangle match that survives the filter adds its three vertex pairs (query instance, map instance):
// a pair seen again gains a vote and keeps its best GSF similarity. Selection then keeps the pairs with
// the most support (votes x weight) up to the clique's capacity; equal support is broken by a hash of
// the pair, never by instance id (map ids follow the map's x order, so id order would favour one side
// of the map). Both caps count what they refused.
//
// Pairs come in two tiers: 1 from matches that passed the GSF filter, 0 from matches below it that
// only fill a short set up to kFillPairs (gsf_filter.h). Every tier-1 pair ranks before every tier-0 pair, and a pair
// keeps only the votes and weight of its highest tier, so tier-0 votes never change how the tier-1 pairs rank.
#pragma once
#include <cstdint>

#include "gsf/detail/arena.h"
#include "gsf/detail/bounded_hash_map.h"
#include "gsf/map_format.h"
#include "gsf/status.h"

namespace gsf {

struct CandidatePair {
  uint32_t query, map;
  float weight;    // best GSF similarity seen for this pair (1 without GSF)
  uint32_t votes;  // surviving triangle matches that produced it
  uint32_t tier;   // 1: from matches that passed the GSF filter; 0: from matches below it
};

class CorrespondenceSet {
 public:
  // candidate_capacity: distinct pairs accumulated per scan; max_selected: pairs selection may keep.
  static size_t required_bytes(uint32_t candidate_capacity, uint32_t max_selected);
  Status bind(Arena& arena, uint32_t candidate_capacity, uint32_t max_selected);

  void clear();
  // Forgets the last selection only (selected() = 0), O(1): what a new scan needs before it matches.
  void forget_selection() { selected_ = 0; }
  // Adds one vote of `tier` for (query, map) with similarity omega (a vote below the pair's tier is
  // ignored; one above it restarts the pair's votes and weight). False (nothing stored) when the pair is
  // new and the candidate capacity is full; the caller counts it.
  bool add(uint32_t query, uint32_t map, float omega, uint32_t tier = 1);
  uint32_t candidates() const { return count_; }

  // Keeps the best min(candidates, max_selected) pairs by tier, then votes x weight, tier-0 pairs only
  // while fewer than fill_to are kept (0: none), and writes their positions
  // (query centroids from query_centroids, I x 3; map centroids from map_instances) to query_xyz(),
  // map_xyz() and their weights to weights(). Returns how many were kept.
  uint32_t select(uint32_t max_selected, const float* query_centroids, const MapInstance* map_instances,
                  uint32_t fill_to = 0);
  uint32_t selected() const { return selected_; }
  const float* query_xyz() const { return a_; }  // selected x 3
  const float* map_xyz() const { return b_; }    // selected x 3
  const float* weights() const { return w_; }    // selected
  // The k-th selected pair (k < selected()).
  const CandidatePair& selected_pair(uint32_t k) const { return pairs_[order_[k]]; }

 private:
  BoundedHashMap<uint32_t> index_;  // (query, map) -> pair id
  CandidatePair* pairs_ = nullptr;
  uint32_t* order_ = nullptr;  // selection order (candidate capacity)
  float* a_ = nullptr;
  float* b_ = nullptr;
  float* w_ = nullptr;
  uint32_t capacity_ = 0, max_selected_ = 0, count_ = 0, selected_ = 0;
};

}  // namespace gsf
