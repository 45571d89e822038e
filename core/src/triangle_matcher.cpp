#include "gsf/detail/triangle_matcher.h"

#include <algorithm>
#include <cmath>

#include "gsf/detail/bounded_hash_map.h"
#include "gsf/map_format.h"
#include "gsf/position_prior.h"

namespace gsf {
namespace {

// Worse = larger residual, then larger tie value.
inline bool worse(const RankedTriangleMatch& a, const RankedTriangleMatch& b) {
  return a.residual > b.residual || (a.residual == b.residual && a.tie > b.tie);
}

void sift_down(RankedTriangleMatch* h, uint32_t n, uint32_t i) {
  for (;;) {
    uint32_t m = i;
    const uint32_t l = 2 * i + 1, r = l + 1;
    if (l < n && worse(h[l], h[m])) m = l;
    if (r < n && worse(h[r], h[m])) m = r;
    if (m == i) return;
    const RankedTriangleMatch t = h[i];
    h[i] = h[m];
    h[m] = t;
    i = m;
  }
}

// The query's sides and labels in vertex order o (kTriangleVertexOrders). False when the order is not
// possible: its sides must be sorted up to the tie tolerance (order 0 always is).
bool order_sides(const Triangle& q, uint8_t o, float tie_tolerance, float side[3], uint8_t label[3]) {
  // Distances between canonical vertices: d(0,1) = side[0], d(1,2) = side[1], d(2,0) = side[2].
  auto dist = [&q](uint8_t i, uint8_t j) {
    const uint8_t lo = i < j ? i : j, hi = i < j ? j : i;
    return lo == 0 ? (hi == 1 ? q.side[0] : q.side[2]) : q.side[1];
  };
  const uint8_t* p = kTriangleVertexOrders[o];
  for (int k = 0; k < 3; ++k) {
    side[k] = dist(p[k], p[(k + 1) % 3]);
    label[k] = q.label[p[k]];
  }
  return o == 0 || (tie_tolerance > 0.0f && side[0] <= side[1] * (1.0f + tie_tolerance) &&
                    side[1] <= side[2] * (1.0f + tie_tolerance));
}

}  // namespace

size_t TriangleMatcher::required_bytes(uint32_t cap) { return counted_bytes<TriangleMatcher>(cap); }

Status TriangleMatcher::bind(Arena& arena, uint32_t cap) {
  cap_ = 0;
  size_ = 0;
  if (cap == 0) return Status::InvalidArgument;
  heap_ = arena.allocate<RankedTriangleMatch>(cap);
  if (arena.counting()) return Status::Ok;
  if (!heap_) return Status::BufferTooSmall;
  cap_ = limit_ = cap;
  return Status::Ok;
}

void TriangleMatcher::offer(const RankedTriangleMatch& m) {
  if (size_ < limit_) {  // sift up
    uint32_t i = size_++;
    heap_[i] = m;
    while (i > 0) {
      const uint32_t p = (i - 1) / 2;
      if (!worse(heap_[i], heap_[p])) break;
      const RankedTriangleMatch t = heap_[i];
      heap_[i] = heap_[p];
      heap_[p] = t;
      i = p;
    }
  } else if (worse(heap_[0], m)) {  // replace the worst kept
    heap_[0] = m;
    sift_down(heap_, size_, 0);
  }
}

TriangleMatchStats TriangleMatcher::match(const Triangle& q, const TriangleIndexView& index, const Triangle* map,
                                          const TriangleConfig& config, float tie_tolerance) {
  TriangleMatchStats st;
  size_ = 0;
  if (limit_ == 0) return st;
  for (uint8_t o = 0; o < 6; ++o) {
    float side[3];
    uint8_t label[3];
    if (!order_sides(q, o, tie_tolerance, side, label)) continue;
    ++st.orders;
    if (region_) set_vertex_ranges(q, o);
    search_order(q, o, side, label, index, map, config, &st);
  }
  sort_best_first();
  st.kept = size_;
  return st;
}

// The neighbouring keys (q0 +- 1, q1 +- 1, q2 +- 1) of this label triple that a map side within the
// tolerance can have: a side's key bin is floor(side / side_bin), so only the bins of [side - tol, side +
// tol] (widened by kBinMargin against rounding) can hold a match, 1-2 of the 3 per side at the default
// 3% tolerance (at most 8 of the 27 keys, 1 where no side is near a bin edge). q2 is the key's lowest
// field, so its neighbours are contiguous, and so are their triangles (stored in key order). Quantised
// sides below 0 or above the key's field do not exist. The exact test is offer_range's: the bins left
// out hold no match.
void TriangleMatcher::search_order(const Triangle& q, uint8_t o, const float side[3], const uint8_t label[3],
                                   const TriangleIndexView& index, const Triangle* map, const TriangleConfig& config,
                                   TriangleMatchStats* st) {
  constexpr int32_t kMax = int32_t(kTriangleKeyMaxBin);
  constexpr float kBinMargin = 1e-3f;  // m; float rounding of the tolerance test is far below this
  int32_t lo[3], hi[3];
  for (int i = 0; i < 3; ++i) {
    const int32_t qk = static_cast<int32_t>(std::floor(side[i] / config.side_bin));
    const float tol = config.relative_side_tolerance * side[i] + kBinMargin;
    const int32_t lo_tol = static_cast<int32_t>(std::floor((side[i] - tol) / config.side_bin));
    const int32_t hi_tol = static_cast<int32_t>(std::floor((side[i] + tol) / config.side_bin));
    lo[i] = std::max({qk - 1, lo_tol, int32_t(0)});
    hi[i] = std::min({qk + 1, hi_tol, kMax});
    if (lo[i] > hi[i]) return;
  }
  // The ranges come in increasing key order (same labels; (q0, q1) lexicographic), so each search
  // continues from where the previous one ended.
  uint32_t from = 0;
  for (int32_t a0 = lo[0]; a0 <= hi[0]; ++a0)
    for (int32_t a1 = lo[1]; a1 <= hi[1]; ++a1) {
      uint32_t b, e;
      if (!index.range_from(triangle_key(label, uint32_t(a0), uint32_t(a1), uint32_t(lo[2])),
                            triangle_key(label, uint32_t(a0), uint32_t(a1), uint32_t(hi[2])), &from, &b, &e))
        continue;
      offer_range(q, o, side, b, e, map, config, st);
    }
}

// Map triangles [begin, end) (a contiguous run, read sequentially) with every side within the relative
// tolerance, and not a mirror image (when checked), ranked by their largest relative side residual. The
// run shares the query's labels: they are in the key, and a loaded map's index is validated to store each
// triangle under its own key (TriangleIndexView::validate). A zone scan examines ~650 k map triangles
// here, so the loop tests the sides before it divides, and a candidate the full heap would refuse on its
// residual alone is refused before its tie hash is computed.
void TriangleMatcher::offer_range(const Triangle& q, uint8_t o, const float side[3], uint32_t begin, uint32_t end,
                                  const Triangle* map, const TriangleConfig& config, TriangleMatchStats* st) {
  // Orders 1-3 swap two vertices (odd permutations): the query's sense in them is reversed.
  const bool flip = o >= 1 && o <= 3;
  const uint8_t refused = mirror_check_ ? contradicting_orientation(q.orientation, flip) : uint8_t(0);
  const float s0 = side[0], s1 = side[1], s2 = side[2];
  const float t0 = config.relative_side_tolerance * s0, t1 = config.relative_side_tolerance * s1,
              t2 = config.relative_side_tolerance * s2;
  for (uint32_t mid = begin; mid < end; ++mid) {
    const Triangle& m = map[mid];
    const float r0 = std::fabs(s0 - m.side[0]), r1 = std::fabs(s1 - m.side[1]), r2 = std::fabs(s2 - m.side[2]);
    if (!(r0 < t0 && r1 < t1 && r2 < t2)) continue;
    if (refused != 0 && m.orientation == refused) {
      ++st->mirrored;
      continue;
    }
    // After the mirror check: outside + accepted is then what the scan finds without a region, which
    // decides the sparse rematch (localizer.cpp match_scan), so a prior does not change whether it happens.
    if (region_ && !in_region(m)) {
      ++outside_;
      ++st->outside;
      continue;
    }
    ++st->accepted;
    // Every side passed, so each is > 0 (r < tolerance x side).
    float residual = r0 / s0;
    const float rel1 = r1 / s1, rel2 = r2 / s2;
    residual = rel1 > residual ? rel1 : residual;
    residual = rel2 > residual ? rel2 : residual;
    if (size_ == limit_ && residual > heap_[0].residual) continue;  // offer() would refuse it
    RankedTriangleMatch c{};
    c.map = mid;
    c.residual = residual;
    // Position-free: a hash of the map triangle's instance ids and the order, not of where the
    // triangle is stored.
    c.tie =
        static_cast<uint32_t>(mix64(mix64((uint64_t(m.v[0]) << 32) | m.v[1]) ^ ((uint64_t(m.v[2]) << 3) | o)) >> 32);
    c.order = o;
    offer(c);
  }
}

// The bird's-eye range from the sensor of the query vertex each matched position takes in order o.
void TriangleMatcher::set_vertex_ranges(const Triangle& q, uint8_t o) {
  for (int j = 0; j < 3; ++j) {
    const float* c = query_centroids_ + 3 * size_t(query_vertex(q, o, j));
    range_[j] = std::sqrt(c[0] * c[0] + c[1] * c[1]);
  }
}

// Every vertex of map triangle m near enough the prior to be seen from a sensor inside it.
bool TriangleMatcher::in_region(const Triangle& m) const {
  for (int j = 0; j < 3; ++j) {
    const float* p = map_instances_[m.v[j]].centroid;
    if (!region_->reaches(p[0], p[1], range_[j])) return false;
  }
  return true;
}

// Best first (heap sort: repeatedly move the worst to the end).
void TriangleMatcher::sort_best_first() {
  for (uint32_t n = size_; n > 1; --n) {
    const RankedTriangleMatch t = heap_[0];
    heap_[0] = heap_[n - 1];
    heap_[n - 1] = t;
    sift_down(heap_, n - 1, 0);
  }
}

}  // namespace gsf
