#include "gsf/detail/triangle.h"

#include <cmath>

#include "gsf/semantic_classes.h"

namespace gsf {
static_assert(kNumClasses <= int(kTriangleKeyLabelLimit), "a dense class must fit the key's 5-bit label field");

namespace {

float dist(const float* a, const float* b) {
  const float dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
  return std::sqrt(dx * dx + dy * dy + dz * dz);
}

}  // namespace

Status validate(const TriangleConfig& c) {
  if (c.neighbours < 2 || c.neighbours > 64 ||
      (c.map_neighbours != 0 && (c.map_neighbours < c.neighbours || c.map_neighbours > 64)) || !(c.min_side >= 0.0f) ||
      !(c.max_side > c.min_side) || !(c.side_bin > 0.0f) || !(c.relative_side_tolerance > 0.0f) ||
      c.max_triangles == 0 || !(c.sparse_side_tolerance == 0.0f || c.sparse_side_tolerance > c.relative_side_tolerance))
    return Status::InvalidArgument;
  // Every side quantises into the key's 16 bits, with room for the matcher's +1 neighbour.
  if (!(c.max_side / c.side_bin < float(kTriangleKeyMaxBin - 1))) return Status::InvalidArgument;
  return Status::Ok;
}

uint8_t triangle_orientation(const float* p0, const float* p1, const float* p2, float longest_side) {
  const float cross = (p1[0] - p0[0]) * (p2[1] - p0[1]) - (p1[1] - p0[1]) * (p2[0] - p0[0]);
  // |cross| is twice the bird's-eye area: the apex's height over the longest side times its length.
  if (!(std::fabs(cross) >= kOrientationMinHeight * longest_side)) return kOrientationFlat;
  return cross > 0.0f ? kOrientationCounterClockwise : kOrientationClockwise;
}

uint64_t triangle_key(const Triangle& t, float bin) {
  uint32_t q[3];
  for (int k = 0; k < 3; ++k) {
    if (t.label[k] >= kTriangleKeyLabelLimit) return kInvalidTriangleKey;
    const float f = std::floor(t.side[k] / bin);
    if (!(f >= 0.0f && f <= float(kTriangleKeyMaxBin))) return kInvalidTriangleKey;  // also NaN
    q[k] = static_cast<uint32_t>(f);
  }
  return triangle_key(t.label, q[0], q[1], q[2]);
}

Triangle make_triangle(uint32_t a, uint32_t b, uint32_t c, const float* pa, const float* pb, const float* pc,
                       const uint8_t* labels) {
  // Edges: e0 = (a,b), e1 = (b,c), e2 = (c,a); order them by (length, smaller id pair) for determinism.
  const uint32_t id[3] = {a, b, c};
  const float* p[3] = {pa, pb, pc};
  struct Edge {
    float len;
    uint32_t i, j;
    uint64_t tie;
  };
  Edge e[3];
  for (int k = 0; k < 3; ++k) {
    const int i = k, j = (k + 1) % 3;
    const uint32_t lo = id[i] < id[j] ? id[i] : id[j], hi = id[i] < id[j] ? id[j] : id[i];
    e[k] = Edge{dist(p[i], p[j]), uint32_t(i), uint32_t(j), (uint64_t(lo) << 32) | hi};
  }
  auto less = [](const Edge& x, const Edge& y) { return x.len < y.len || (x.len == y.len && x.tie < y.tie); };
  for (int x = 0; x < 2; ++x)
    for (int y = 0; y < 2 - x; ++y)
      if (less(e[y + 1], e[y])) {
        const Edge t = e[y];
        e[y] = e[y + 1];
        e[y + 1] = t;
      }
  // v0 = vertex shared by the shortest (e[0]) and longest (e[2]) edges; v1 = other end of the shortest.
  const uint32_t v0 = (e[0].i == e[2].i || e[0].i == e[2].j) ? e[0].i : e[0].j;
  const uint32_t v1 = e[0].i == v0 ? e[0].j : e[0].i;
  const uint32_t v2 = 3u - v0 - v1;
  Triangle t{};
  t.v[0] = id[v0];
  t.v[1] = id[v1];
  t.v[2] = id[v2];
  t.side[0] = e[0].len;
  t.side[1] = e[1].len;
  t.side[2] = e[2].len;
  t.label[0] = labels[id[v0]];
  t.label[1] = labels[id[v1]];
  t.label[2] = labels[id[v2]];
  t.orientation = triangle_orientation(p[v0], p[v1], p[v2], t.side[2]);
  return t;
}

size_t TriangleBuilder::required_bytes(const TriangleConfig& config, uint32_t max_instances) {
  return counted_bytes<TriangleBuilder>(config, max_instances);
}

Status TriangleBuilder::bind(Arena& arena, const TriangleConfig& config, uint32_t max_instances) {
  bound_ = false;
  const Status v = validate(config);
  if (v != Status::Ok) return v;
  if (max_instances == 0 || max_instances >= (1u << 21)) return Status::InvalidArgument;
  config_ = config;
  max_instances_ = max_instances;
  knn_ = arena.allocate<uint32_t>(size_t(max_instances) * config.neighbours);
  knn_d_ = arena.allocate<float>(size_t(max_instances) * config.neighbours);
  knn_count_ = arena.allocate<uint32_t>(max_instances);
  const bool ok = seen_.bind(arena, config.max_triangles);
  if (arena.counting()) return Status::Ok;
  if (!knn_ || !knn_d_ || !knn_count_ || !ok) return Status::BufferTooSmall;
  bound_ = true;
  return Status::Ok;
}

Status TriangleBuilder::build(const float* c, uint32_t stride, const uint8_t* labels, uint32_t n,
                              FixedVector<Triangle>& out) {
  out.clear();
  seen_.clear();
  if (!bound_) return Status::NotInitialized;
  if (n > max_instances_ || stride < 3) return Status::InvalidArgument;
  const uint32_t K = config_.neighbours;
  // K nearest within max_side, kept sorted by (distance, id) - brute force, O(n^2 K) worst case.
  for (uint32_t i = 0; i < n; ++i) {
    uint32_t* nb = knn_ + size_t(i) * K;
    float* nd = knn_d_ + size_t(i) * K;
    uint32_t cnt = 0;
    for (uint32_t j = 0; j < n; ++j) {
      if (j == i) continue;
      const float d = dist(c + size_t(i) * stride, c + size_t(j) * stride);
      if (!(d <= config_.max_side)) continue;
      if (cnt == K && !(d < nd[K - 1])) continue;
      uint32_t pos = cnt < K ? cnt++ : K - 1;
      while (pos > 0 && d < nd[pos - 1]) {
        nd[pos] = nd[pos - 1];
        nb[pos] = nb[pos - 1];
        --pos;
      }
      nd[pos] = d;
      nb[pos] = j;
    }
    knn_count_[i] = cnt;
  }
  const uint32_t cap = out.capacity() < config_.max_triangles ? out.capacity() : config_.max_triangles;
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t* nb = knn_ + size_t(i) * K;
    for (uint32_t x = 0; x < knn_count_[i]; ++x)
      for (uint32_t y = x + 1; y < knn_count_[i]; ++y) {
        const uint32_t a = i, b = nb[x], d = nb[y];
        Triangle t =
            make_triangle(a, b, d, c + size_t(a) * stride, c + size_t(b) * stride, c + size_t(d) * stride, labels);
        if (!(t.side[0] >= config_.min_side && t.side[2] <= config_.max_side)) continue;
        bool inserted = false;
        if (out.size() >= cap) return Status::CapacityExceeded;
        if (!seen_.find_or_insert(triangle_vertex_set_key(a, b, d), &inserted)) return Status::CapacityExceeded;
        if (!inserted) continue;
        out.push_back(t);
      }
  }
  return Status::Ok;
}

}  // namespace gsf
