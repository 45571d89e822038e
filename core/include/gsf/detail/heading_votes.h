// Internal (gsf/detail): a pipeline stage or building block, not part of the stable interface; it may
// change between versions. The stable interface is localizer.h, config.h, map_format.h, scan.h, status.h,
// platform.h, class_table.h, georeference.h, stage_configs.h, stage_results.h and the C API gsf.h.
// Heading votes (before the GSF filter): the ranked index matches of an evenly spaced sample of query
// triangles vote for the yaw bin that takes the query triangle onto the map triangle; only the
// best-supported headings (each with its two neighbour bins) go on. True matches agree on one heading
// (a lattice's symmetries add a few more), wrong ones spread over all of them. This bounds the distinct
// (instance, heading) probes of the GSF filter by instances x kept bins.
#pragma once
#include <cstdint>

#include "gsf/detail/arena.h"
#include "gsf/detail/fixed_vector.h"
#include "gsf/detail/triangle.h"
#include "gsf/detail/triangle_matcher.h"
#include "gsf/map_format.h"
#include "gsf/status.h"

namespace gsf {

// Yaw bin of the 2-D Procrustes rotation taking the query vertices qa, qb, qc onto the map vertices
// (xyz each); the vehicle is near level, the full 3-D pose comes later from the clique.
uint32_t triangle_yaw_bin(const float* q[3], const float* m[3], uint32_t yaw_bins);

// Yaw bin of ranked match `rm` of query triangle `qt` (the heading that maps it onto the map
// triangle); the query vertices in the map triangle's vertex order go to qv.
uint32_t match_yaw_bin(const Triangle& qt, const RankedTriangleMatch& rm, const float* query_centroids,
                       const MapView& map, uint32_t yaw_bins, uint32_t* qv);

struct HeadingVoteParams {
  uint32_t kept_bins = 6;           // best-voted bins kept (each with its neighbours); 0 = every bin
  uint32_t sample_triangles = 256;  // query triangles sampled (evenly spaced) for the votes
  float vertex_tie_tolerance = 0.06f;
};

class HeadingVotes {
 public:
  static size_t required_bytes(uint32_t yaw_bins);
  Status bind(Arena& arena, uint32_t yaw_bins);
  // Votes with the matches of the sampled query triangles (`matcher` is used as scratch). Returns the
  // number of bins kept. Without votes (kept_bins 0) every bin is kept and nothing is matched.
  uint32_t vote(const FixedVector<Triangle>& triangles, const float* query_centroids, TriangleMatcher& matcher,
                const TriangleIndexView& index, const MapView& map, const TriangleConfig& triangle_config,
                const HeadingVoteParams& params);
  bool allowed(uint32_t bin) const { return allowed_[bin] != 0; }
  // The map candidates the last vote's sample found (accepted by labels and sides, or refused only as
  // outside a prior's region), scaled by the sampling stride: the whole scan's count when it has at
  // most sample_triangles triangles, an estimate beyond. 0 without votes.
  uint32_t scan_candidates() const { return scan_candidates_; }
  uint32_t bins() const { return bins_; }

 private:
  uint32_t* votes_ = nullptr;  // per yaw bin
  uint8_t* allowed_ = nullptr;
  uint32_t bins_ = 0;
  uint32_t scan_candidates_ = 0;
};

}  // namespace gsf
