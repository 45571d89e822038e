// Internal (gsf/detail): a pipeline stage or building block, not part of the stable interface; it may
// change between versions. The stable interface is localizer.h, config.h, map_format.h, scan.h, status.h,
// platform.h, class_table.h, georeference.h, stage_configs.h, stage_results.h and the C API gsf.h.
// Coarse matching of one query triangle against the map's triangle index, ranked and then capped.
//
// Every map triangle found under the 27 neighbouring keys (labels in vertex order, quantised sides +- 1
// bin; 9 contiguous key ranges, triangle_index.h) that passes Outram's acceptance rules (labels equal in
// vertex order, every side within the relative tolerance) is a candidate. Candidates are ranked by
// their side residual (the largest relative side difference), ties broken by a hash of the map
// triangle's instance ids and the vertex order (position-free), and only the best `cap` are kept. Storage order (key,
// then map x order) never decides what survives: in a lattice, where thousands of map triangles fit equally well, a cap
// that kept "the first N" would keep one corner of the map. The caller learns how many were accepted and dropped.
//
// Vertex order: the canonical order (triangle.h) sorts sides, so when two query sides tie within the
// tie tolerance (isosceles triangles are the rule in lattices) the order, and with it the vertex
// correspondence, is ambiguous. Every vertex order whose sides are sorted up to that tolerance is tried;
// each candidate records the order it matched in.
//
// Mirror images: equal sides do not make equal triangles; a triangle and its mirror image have the same
// sides and opposite senses (triangle.h, TriangleOrientation). With the mirror check on, a candidate whose
// sense contradicts the query's in the order tried is no candidate (counted in `mirrored`), before the
// cap: in a symmetric hall or lattice half the candidates are mirror twins, and a clique of them fits an
// upside-down pose that crowds out the true one. Maps without recorded senses are never rejected.
//
// Position prior (position_prior.h): with a region set, a candidate whose map vertices do not all lie
// within the prior's disc + the range of the query vertex each would match is no candidate (counted in
// outside_region()), before the cap, so the cap ranks the candidates near the prior only. It is checked
// after the mirror check, so accepted + outside is what the scan finds without a region. Three loads and
// compares per candidate that passed labels, sides and senses; no memory.
#pragma once
#include <cstdint>

#include "gsf/detail/arena.h"
#include "gsf/detail/triangle.h"
#include "gsf/detail/triangle_index.h"
#include "gsf/status.h"

namespace gsf {

struct MapInstance;
struct PriorRegion;

// The query vertex orders tried: order k maps matched position j to canonical query vertex kOrders[k][j].
constexpr uint8_t kTriangleVertexOrders[6][3] = {{0, 1, 2}, {2, 1, 0}, {1, 0, 2}, {0, 2, 1}, {1, 2, 0}, {2, 0, 1}};

// A scan whose triangles find fewer map candidates than this (summed over its triangles, before the
// caps, as the heading votes' matching counts them: HeadingVotes::scan_candidates) is matched at
// TriangleConfig::sparse_side_tolerance instead. A 32-beam scan on the suite's worlds mostly finds
// hundreds to tens of thousands; the 16-beam scans that failed for want of a true correspondence found
// 3-40 (bench/suite_failures.py, CHANGELOG.md 2026-12-04). 64, 128 and 256 gave the same answers on
// seeds 7-8 of the cheap family and within one on b16.
constexpr uint32_t kSparseScanCandidates = 128;

struct RankedTriangleMatch {
  uint32_t map;    // map triangle id
  float residual;  // max over sides of |d_q - d_m| / d_q
  uint32_t tie;    // deterministic, position-free tie breaker (hash of the map triangle's vertices and order)
  uint8_t order;   // query vertex order (kTriangleVertexOrders row)
  uint8_t pad[3];
};

struct TriangleMatchStats {
  uint32_t accepted = 0;  // candidates passing labels and sides (all vertex orders)
  uint32_t kept = 0;      // after the cap
  uint32_t orders = 0;    // vertex orders tried for this query triangle (1 without side ties)
  uint32_t mirrored = 0;  // candidates of the right sides refused as mirror images (mirror check)
  uint32_t outside = 0;   // candidates of the right sides refused as outside the region (position prior)
  uint32_t dropped() const { return accepted - kept; }
};

class TriangleMatcher {
 public:
  static size_t required_bytes(uint32_t cap);
  Status bind(Arena& arena, uint32_t cap);
  // Ranks the candidates of query triangle `q`; afterwards size() best-first entries are in match(i).
  // tie_tolerance: relative side difference under which two query sides count as tied (0: canonical
  // order only).
  TriangleMatchStats match(const Triangle& q, const TriangleIndexView& index, const Triangle* map_triangles,
                           const TriangleConfig& config, float tie_tolerance);
  uint32_t size() const { return size_; }
  // Keep at most `n` (1 <= n; at most the bound capacity) of the ranked matches from the next match()
  // on; returns the limit in effect.
  uint32_t set_limit(uint32_t n) {
    limit_ = n == 0 ? 1 : (n < cap_ ? n : cap_);
    return limit_;
  }
  // Refuse mirror-image candidates from the next match() on (default on).
  void set_mirror_check(bool on) { mirror_check_ = on; }
  // Restrict the next match() calls to map triangles near a position prior (nullptr: the whole map, the
  // default). map_instances: the map's; query_centroids: the query instances' (scan frame, xyz each).
  // The pointers must stay valid while the region is set. Resets outside_region().
  void set_region(const PriorRegion* region, const MapInstance* map_instances, const float* query_centroids) {
    region_ = region;
    map_instances_ = map_instances;
    query_centroids_ = query_centroids;
    outside_ = 0;
  }
  // Candidates refused as outside the region since set_region (all match() calls).
  uint32_t outside_region() const { return outside_; }
  const RankedTriangleMatch& match_at(uint32_t i) const { return heap_[i]; }
  // The query triangle's vertex (instance id) at matched position j for the order of match i.
  static uint32_t query_vertex(const Triangle& q, uint8_t order, int j) { return q.v[kTriangleVertexOrders[order][j]]; }

 private:
  // The steps of match(): per possible vertex order the map triangles of the neighbouring keys a match
  // can have (of the 27) are offered to the heap, which is then sorted best first.
  void search_order(const Triangle& q, uint8_t order, const float side[3], const uint8_t label[3],
                    const TriangleIndexView& index, const Triangle* map, const TriangleConfig& config,
                    TriangleMatchStats* st);
  void offer_range(const Triangle& q, uint8_t order, const float side[3], uint32_t begin, uint32_t end,
                   const Triangle* map, const TriangleConfig& config, TriangleMatchStats* st);
  void offer(const RankedTriangleMatch& m);
  void sort_best_first();
  void set_vertex_ranges(const Triangle& q, uint8_t order);
  bool in_region(const Triangle& m) const;
  RankedTriangleMatch* heap_ = nullptr;  // max-heap on (residual, tie) while collecting; sorted after
  uint32_t cap_ = 0;
  uint32_t limit_ = 0;  // <= cap_: what match() keeps (set_limit)
  uint32_t size_ = 0;
  bool mirror_check_ = true;
  const PriorRegion* region_ = nullptr;  // set_region
  const MapInstance* map_instances_ = nullptr;
  const float* query_centroids_ = nullptr;
  float range_[3] = {};  // bird's-eye range of the query vertex at matched position j (order being searched)
  uint32_t outside_ = 0;
};

}  // namespace gsf
