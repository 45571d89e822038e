#include "gsf/detail/correspondence_set.h"

#include <algorithm>

namespace gsf {

size_t CorrespondenceSet::required_bytes(uint32_t candidate_capacity, uint32_t max_selected) {
  return counted_bytes<CorrespondenceSet>(candidate_capacity, max_selected);
}

Status CorrespondenceSet::bind(Arena& arena, uint32_t candidate_capacity, uint32_t max_selected) {
  if (candidate_capacity == 0 || max_selected == 0) return Status::InvalidArgument;
  capacity_ = candidate_capacity;
  max_selected_ = max_selected;
  index_.bind(arena, candidate_capacity);
  pairs_ = arena.allocate<CandidatePair>(candidate_capacity);
  order_ = arena.allocate<uint32_t>(candidate_capacity);
  a_ = arena.allocate<float>(size_t(max_selected) * 3);
  b_ = arena.allocate<float>(size_t(max_selected) * 3);
  w_ = arena.allocate<float>(max_selected);
  count_ = selected_ = 0;
  return arena.overflowed() ? Status::BufferTooSmall : Status::Ok;
}

void CorrespondenceSet::clear() {
  index_.clear();
  count_ = selected_ = 0;
}

bool CorrespondenceSet::add(uint32_t query, uint32_t map, float omega, uint32_t tier) {
  const uint64_t key = (uint64_t(query) << 32) | map;
  bool inserted = false;
  // The index and the pair array share one capacity, so the index refuses a new key (nullptr) exactly
  // when the array is full; the second test is a guard that can only fire if that invariant breaks.
  uint32_t* id = index_.find_or_insert(key, &inserted);
  if (!id || (inserted && count_ >= capacity_)) return false;
  if (inserted) {
    *id = count_;
    pairs_[count_++] = CandidatePair{query, map, 0.0f, 0, tier};
  }
  CandidatePair& c = pairs_[*id];
  if (tier < c.tier) return true;
  if (tier > c.tier) c = CandidatePair{query, map, 0.0f, 0, tier};
  c.weight = std::max(c.weight, omega);
  c.votes += 1;
  return true;
}

uint32_t CorrespondenceSet::select(uint32_t max_selected, const float* query_centroids,
                                   const MapInstance* map_instances, uint32_t fill_to) {
  const uint32_t total = count_;
  for (uint32_t i = 0; i < total; ++i) order_[i] = i;
  const CandidatePair* acc = pairs_;
  std::sort(order_, order_ + total, [acc](uint32_t x, uint32_t y) {
    if (acc[x].tier != acc[y].tier) return acc[x].tier > acc[y].tier;
    const float sx = acc[x].weight * float(acc[x].votes), sy = acc[y].weight * float(acc[y].votes);
    if (sx != sy) return sx > sy;
    const uint64_t hx = mix64((uint64_t(acc[x].query) << 32) | acc[x].map);
    const uint64_t hy = mix64((uint64_t(acc[y].query) << 32) | acc[y].map);
    if (hx != hy) return hx < hy;
    return x < y;
  });
  uint32_t C = std::min({total, max_selected, max_selected_});
  // Tier-0 pairs (sorted last) only while fewer than fill_to pairs are kept.
  for (uint32_t i = 0; i < C; ++i)
    if (acc[order_[i]].tier == 0) {
      C = std::max(i, std::min(C, fill_to));
      break;
    }
  for (uint32_t i = 0; i < C; ++i) {
    const CandidatePair& c = pairs_[order_[i]];
    for (int d = 0; d < 3; ++d) {
      a_[3 * i + d] = query_centroids[3 * c.query + d];
      b_[3 * i + d] = map_instances[c.map].centroid[d];
    }
    w_[i] = c.weight;
  }
  selected_ = C;
  return C;
}

}  // namespace gsf
