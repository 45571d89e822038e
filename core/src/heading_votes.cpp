#include "gsf/detail/heading_votes.h"

#include <cmath>

#include "gsf/detail/angles.h"

namespace gsf {

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

uint32_t match_yaw_bin(const Triangle& qt, const RankedTriangleMatch& rm, const float* query_centroids,
                       const MapView& map, uint32_t yaw_bins, uint32_t* qv) {
  const Triangle& mt = map.triangles[rm.map];
  for (int v = 0; v < 3; ++v) qv[v] = TriangleMatcher::query_vertex(qt, rm.order, v);
  const float* qp[3] = {query_centroids + 3 * qv[0], query_centroids + 3 * qv[1], query_centroids + 3 * qv[2]};
  const float* mp[3] = {map.instances[mt.v[0]].centroid, map.instances[mt.v[1]].centroid,
                        map.instances[mt.v[2]].centroid};
  return triangle_yaw_bin(qp, mp, yaw_bins);
}

size_t HeadingVotes::required_bytes(uint32_t yaw_bins) { return counted_bytes<HeadingVotes>(yaw_bins); }

Status HeadingVotes::bind(Arena& arena, uint32_t yaw_bins) {
  if (yaw_bins == 0) return Status::InvalidArgument;
  bins_ = yaw_bins;
  votes_ = arena.allocate<uint32_t>(yaw_bins);
  allowed_ = arena.allocate<uint8_t>(yaw_bins);
  return arena.overflowed() ? Status::BufferTooSmall : Status::Ok;
}

uint32_t HeadingVotes::vote(const FixedVector<Triangle>& triangles, const float* query_centroids,
                            TriangleMatcher& matcher, const TriangleIndexView& index, const MapView& map,
                            const TriangleConfig& triangle_config, const HeadingVoteParams& params) {
  const uint32_t B = bins_, T = triangles.size();
  for (uint32_t b = 0; b < B; ++b) allowed_[b] = params.kept_bins == 0 ? 1 : 0;
  scan_candidates_ = 0;
  if (params.kept_bins > 0 && T > 0) {
    for (uint32_t b = 0; b < B; ++b) votes_[b] = 0;
    const uint32_t stride = (T + params.sample_triangles - 1) / params.sample_triangles;
    uint32_t qv[3];
    uint64_t found = 0;
    for (uint32_t qt_id = 0; qt_id < T; qt_id += stride) {
      const Triangle& qt = triangles[qt_id];
      const TriangleMatchStats ms =
          matcher.match(qt, index, map.triangles, triangle_config, params.vertex_tie_tolerance);
      found += uint64_t(ms.accepted) + ms.outside;
      for (uint32_t k = 0; k < matcher.size(); ++k)
        ++votes_[match_yaw_bin(qt, matcher.match_at(k), query_centroids, map, B, qv)];
    }
    found *= stride;
    scan_candidates_ = found < UINT32_MAX ? static_cast<uint32_t>(found) : UINT32_MAX;
    // The best bins by votes, ties to the lower bin (a strict > over ascending bins).
    for (uint32_t pick = 0; pick < params.kept_bins && pick < B; ++pick) {
      uint32_t best = UINT32_MAX;
      for (uint32_t b = 0; b < B; ++b)
        if (votes_[b] > 0 && (best == UINT32_MAX || votes_[b] > votes_[best])) best = b;
      if (best == UINT32_MAX) break;
      votes_[best] = 0;
      allowed_[best] = allowed_[(best + 1) % B] = allowed_[(best + B - 1) % B] = 1;
    }
  }
  uint32_t kept = 0;
  for (uint32_t b = 0; b < B; ++b) kept += allowed_[b];
  return kept;
}

}  // namespace gsf
