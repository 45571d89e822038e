#include "mapping/scan_triangles.h"

#include <algorithm>
#include <unordered_map>
#include <unordered_set>

#include "gsf/detail/arena.h"
#include "gsf/detail/fixed_vector.h"
#include "mapping/workspace.h"

namespace gsf::mapping {

std::vector<uint32_t> nearest_instances(const float* centroids, const uint8_t* labels, uint32_t n,
                                        const std::vector<ScanDetection>& detections, float radius) {
  std::vector<uint32_t> out(detections.size(), UINT32_MAX);
  if (n == 0 || !(radius > 0.0f)) return out;
  const CellIndex cells(n, radius, [&](size_t i) { return std::make_pair(centroids[3 * i], centroids[3 * i + 1]); });
  const float r2 = radius * radius;
  for (size_t k = 0; k < detections.size(); ++k) {
    const ScanDetection& d = detections[k];
    float best = r2;
    cells.for_each_near(d.xyz[0], d.xyz[1], [&](uint32_t i) {
      if (labels[i] != d.label) return;
      const float ex = centroids[3 * size_t(i)] - d.xyz[0], ey = centroids[3 * size_t(i) + 1] - d.xyz[1];
      const float e2 = ex * ex + ey * ey;
      if (e2 < best || (e2 == best && e2 <= r2 && i < out[k])) {
        best = e2;
        out[k] = i;
      }
    });
  }
  return out;
}

Status add_scan_triangles(const float* centroids, const uint8_t* labels, uint32_t n,
                          const std::vector<uint32_t>& instance_of_detection, const std::vector<uint32_t>& scan_begin,
                          const TriangleConfig& query, uint32_t max_key_share, std::vector<Triangle>* triangles,
                          ScanTriangleStats* stats) {
  ScanTriangleStats st;
  if (!triangles || validate(query) != Status::Ok) return Status::InvalidArgument;
  std::unordered_set<uint64_t> present;
  present.reserve(triangles->size() * 2 + 16);
  std::unordered_map<uint64_t, uint32_t> key_share;
  for (const Triangle& t : *triangles) {
    present.insert(triangle_vertex_set_key(t.v[0], t.v[1], t.v[2]));
    if (max_key_share > 0) ++key_share[triangle_key(t, query.side_bin)];
  }
  // The largest scan's instance count sizes one builder for all scans.
  std::vector<uint32_t> ids;
  uint32_t largest = 0;
  for (size_t s = 0; s + 1 < scan_begin.size(); ++s) largest = std::max(largest, scan_begin[s + 1] - scan_begin[s]);
  if (largest < 3) {
    if (stats) *stats = st;
    return Status::Ok;
  }
  TriangleConfig tc = query;
  tc.map_neighbours = 0;
  tc.max_triangles = largest * tc.neighbours * (tc.neighbours - 1) / 2 + 16;
  Workspace ws(TriangleBuilder::required_bytes(tc, largest) + size_t(tc.max_triangles) * sizeof(Triangle) + 512);
  TriangleBuilder builder;
  FixedVector<Triangle> local;
  if (builder.bind(ws.arena, tc, largest) != Status::Ok || !local.bind(ws.arena, tc.max_triangles))
    return Status::InvalidArgument;
  std::vector<float> xyz;
  std::vector<uint8_t> lab;
  for (size_t s = 0; s + 1 < scan_begin.size(); ++s) {
    ids.clear();
    for (uint32_t k = scan_begin[s]; k < scan_begin[s + 1]; ++k)
      if (instance_of_detection[k] < n) ids.push_back(instance_of_detection[k]);
    std::sort(ids.begin(), ids.end());
    ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
    if (ids.size() < 3) continue;
    ++st.scans;
    st.largest_scan = std::max<uint32_t>(st.largest_scan, static_cast<uint32_t>(ids.size()));
    xyz.resize(ids.size() * 3);
    lab.resize(ids.size());
    for (size_t i = 0; i < ids.size(); ++i) {
      for (int k = 0; k < 3; ++k) xyz[3 * i + k] = centroids[3 * size_t(ids[i]) + k];
      lab[i] = labels[ids[i]];
    }
    // Ids in increasing order, so the canonical vertex order's id tie-breaks are the whole map's.
    const Status b = builder.build(xyz.data(), 3, lab.data(), static_cast<uint32_t>(ids.size()), local);
    if (b != Status::Ok) return b;
    st.formed += local.size();
    for (uint32_t t = 0; t < local.size(); ++t) {
      Triangle tri = local[t];
      for (int k = 0; k < 3; ++k) tri.v[k] = ids[tri.v[k]];
      const uint64_t vertex_set = triangle_vertex_set_key(tri.v[0], tri.v[1], tri.v[2]);
      if (present.count(vertex_set)) continue;
      if (max_key_share > 0) {
        uint32_t& share = key_share[triangle_key(tri, query.side_bin)];
        if (share >= max_key_share) {
          ++st.crowded;
          continue;
        }
        ++share;
      }
      present.insert(vertex_set);
      triangles->push_back(tri);
      ++st.added;
    }
  }
  if (stats) *stats = st;
  return Status::Ok;
}

}  // namespace gsf::mapping
