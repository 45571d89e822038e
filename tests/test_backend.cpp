// Triangles, the CSR index and matching, max clique (vs a brute-force oracle), and robust pose.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <vector>

#include "arena_buffer.h"
#include "gsf/detail/max_clique.h"
#include "gsf/detail/pose_solver.h"
#include "gsf/detail/triangle.h"
#include "gsf/detail/triangle_index.h"
#include "gsf/detail/triangle_matcher.h"

using namespace gsf;

namespace {
using Buffer = gsf_test::ArenaBuffer;

std::vector<float> random_points(int n, uint32_t seed, float extent = 40.0f) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-extent, extent), z(0, 4);
  std::vector<float> p(n * 3);
  for (int i = 0; i < n; ++i) {
    p[3 * i] = u(rng);
    p[3 * i + 1] = u(rng);
    p[3 * i + 2] = z(rng);
  }
  return p;
}

Eigen::Isometry3d some_pose() {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = (Eigen::AngleAxisd(1.1, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  t.translation() = Eigen::Vector3d(120.0, -35.0, 2.0);
  return t;
}
}  // namespace

TEST_CASE("Triangles: canonical order, permutation-invariant key") {
  const float p[9] = {0, 0, 0, 3, 0, 0, 0, 4, 0};  // sides 3, 4, 5
  const uint8_t labels[3] = {1, 2, 3};
  for (auto perm : {std::array<uint32_t, 3>{0, 1, 2}, {2, 0, 1}, {1, 2, 0}, {2, 1, 0}}) {
    const Triangle t =
        make_triangle(perm[0], perm[1], perm[2], p + 3 * perm[0], p + 3 * perm[1], p + 3 * perm[2], labels);
    CHECK(t.side[0] == Approx(3));
    CHECK(t.side[1] == Approx(4));
    CHECK(t.side[2] == Approx(5));
    CHECK(t.v[0] == 1);  // joins the shortest (3: 0-1) and longest (5: 1-2) sides
    CHECK(t.v[1] == 0);
    CHECK(t.v[2] == 2);
    CHECK(t.label[0] == 2);                   // labels follow the vertex order
    const uint8_t key_labels[3] = {2, 1, 3};  // in vertex order (ids 1, 0, 2)
    CHECK(triangle_key(t, 1.0f) == triangle_key(key_labels, 3, 4, 5));
  }
  // Key fields: labels above the sides, q2 lowest; what does not fit is never a valid key.
  const uint8_t l[3] = {1, 2, 3};
  CHECK(triangle_key(l, 3, 4, 5) + 1 == triangle_key(l, 3, 4, 6));
  CHECK(triangle_key(l, 65535, 65535, 65535) < triangle_key(l, 0, 0, 0) + (uint64_t(1) << 48));
  Triangle big{};
  big.side[0] = big.side[1] = 1.0f;
  big.side[2] = 65536.0f;
  CHECK(triangle_key(big, 1.0f) == kInvalidTriangleKey);
  big.side[2] = 2.0f;
  big.label[1] = 32;
  CHECK(triangle_key(big, 1.0f) == kInvalidTriangleKey);
  TriangleConfig fine;
  fine.side_bin = fine.max_side / 65534.0f;
  CHECK(validate(fine) == Status::InvalidArgument);
}

TEST_CASE("TriangleBuilder: dedup, side range, rigid invariance, capacity") {
  TriangleConfig tc;
  Buffer buf(2 * TriangleBuilder::required_bytes(tc, 64) + 2 * tc.max_triangles * sizeof(Triangle) + 64);
  TriangleBuilder b;
  FixedVector<Triangle> a, c;
  REQUIRE(b.bind(buf.arena, tc, 64) == Status::Ok);
  REQUIRE(a.bind(buf.arena, tc.max_triangles));
  REQUIRE(c.bind(buf.arena, tc.max_triangles));
  const auto pts = random_points(30, 1);
  std::vector<uint8_t> labels(30);
  for (int i = 0; i < 30; ++i) labels[i] = static_cast<uint8_t>(i % 3);
  REQUIRE(b.build(pts.data(), 3, labels.data(), 30, a) == Status::Ok);
  REQUIRE(a.size() > 30);
  std::set<std::array<uint32_t, 3>> sets;
  for (const Triangle& t : a) {
    std::array<uint32_t, 3> s = {t.v[0], t.v[1], t.v[2]};
    std::sort(s.begin(), s.end());
    CHECK(sets.insert(s).second);  // each vertex set once
    CHECK(t.side[0] <= t.side[1]);
    CHECK(t.side[1] <= t.side[2]);
    CHECK(t.side[0] >= tc.min_side);
    CHECK(t.side[2] <= tc.max_side);
  }
  // A rigidly moved copy gives the same triangles (sides within float rounding, same labels).
  const Eigen::Isometry3d T = some_pose();
  std::vector<float> moved(pts.size());
  for (int i = 0; i < 30; ++i) {
    const Eigen::Vector3d q = T * Eigen::Vector3d(pts[3 * i], pts[3 * i + 1], pts[3 * i + 2]);
    for (int k = 0; k < 3; ++k) moved[3 * i + k] = static_cast<float>(q[k]);
  }
  REQUIRE(b.build(moved.data(), 3, labels.data(), 30, c) == Status::Ok);
  CHECK(c.size() == a.size());
  for (uint32_t i = 0; i < std::min(a.size(), c.size()); ++i) {
    CHECK(c[i].side[2] == Approx(a[i].side[2]).epsilon(1e-4));
    CHECK(c[i].label[0] == a[i].label[0]);
  }
  FixedVector<Triangle> small;
  REQUIRE(small.bind(buf.arena, 5));
  CHECK(b.build(pts.data(), 3, labels.data(), 30, small) == Status::CapacityExceeded);
  CHECK(small.size() == 5);
  CHECK(std::equal(small.begin(), small.end(), a.begin(), [](const Triangle& x, const Triangle& y) {
    return x.v[0] == y.v[0] && x.v[1] == y.v[1] && x.v[2] == y.v[2];
  }));  // deterministic prefix
}

TEST_CASE("Triangle index: lookup equals brute force, validate rejects bad arrays, matching recovers noisy copies") {
  TriangleConfig tc;
  Buffer buf(TriangleBuilder::required_bytes(tc, 128) + 8192 * sizeof(Triangle) + 64);
  TriangleBuilder b;
  FixedVector<Triangle> tris;
  REQUIRE(b.bind(buf.arena, tc, 128) == Status::Ok);
  REQUIRE(tris.bind(buf.arena, 8192));
  const auto pts = random_points(100, 2, 60.0f);
  std::vector<uint8_t> labels(100);
  for (int i = 0; i < 100; ++i) labels[i] = static_cast<uint8_t>(i % 4);
  REQUIRE(b.build(pts.data(), 3, labels.data(), 100, tris) == Status::Ok);
  const uint32_t n = tris.size();
  std::vector<Triangle> sorted(n);
  std::vector<uint64_t> keys(n), scratch(n);
  std::vector<uint32_t> offsets(n + 1), ids(n);
  uint32_t kc = 0;
  REQUIRE(build_triangle_index(tris.data(), n, tc.side_bin, sorted.data(), keys.data(), offsets.data(), &kc,
                               scratch.data(), ids.data()) == Status::Ok);
  TriangleIndexView idx{keys.data(), offsets.data(), kc, n};
  REQUIRE(idx.validate(sorted.data(), tc.side_bin) == Status::Ok);
  // Stored in key order, ties in build order: a permutation of the input.
  for (uint32_t t = 1; t < n; ++t)
    CHECK(triangle_key(sorted[t - 1], tc.side_bin) <= triangle_key(sorted[t], tc.side_bin));
  for (uint32_t k = 0; k < kc; k += 7) {
    uint32_t bgn, end;
    REQUIRE(idx.lookup(keys[k], &bgn, &end));
    std::vector<uint32_t> got, brute;
    for (uint32_t t = bgn; t < end; ++t)
      got.push_back(sorted[t].v[0] * 4096u * 4096u + sorted[t].v[1] * 4096u + sorted[t].v[2]);
    for (uint32_t t = 0; t < n; ++t)
      if (triangle_key(tris[t], tc.side_bin) == keys[k])
        brute.push_back(tris[t].v[0] * 4096u * 4096u + tris[t].v[1] * 4096u + tris[t].v[2]);
    CHECK(got == brute);
  }
  // A range of three q2 neighbours is the union of their lookups.
  for (uint32_t k = 0; k < kc; k += 5) {
    uint32_t rb, re, b0, e0;
    REQUIRE(idx.range(keys[k], keys[k] + 2, &rb, &re));
    uint32_t count = 0;
    for (uint64_t key = keys[k]; key <= keys[k] + 2; ++key)
      if (idx.lookup(key, &b0, &e0)) count += e0 - b0;
    CHECK(rb == idx.offsets[k]);
    CHECK(re - rb == count);
  }
  // range_from over increasing ranges (galloping from where the last ended) equals range() each time,
  // for ranges near each other and far apart, present or not.
  for (uint64_t stride : {uint64_t(1), uint64_t(3), uint64_t(1) << 16, uint64_t(1) << 32, uint64_t(1) << 48}) {
    uint32_t from = 0, checked = 0;
    for (uint64_t lo = keys[0] > 5 ? keys[0] - 5 : 0; lo <= keys[kc - 1] + 1 && checked < 20000;
         lo += stride, ++checked) {
      uint32_t b1, e1, b2, e2;
      const bool r1 = idx.range(lo, lo + 2 < lo + stride ? lo + 2 : lo + stride - 1, &b1, &e1);
      const bool r2 = idx.range_from(lo, lo + 2 < lo + stride ? lo + 2 : lo + stride - 1, &from, &b2, &e2);
      REQUIRE(r1 == r2);
      CHECK(b1 == b2);
      CHECK(e1 == e2);
    }
  }
  uint32_t bgn, end;
  const uint8_t no_labels[3] = {9, 9, 9};
  CHECK_FALSE(idx.lookup(triangle_key(no_labels, 999, 999, 999), &bgn, &end));
  std::swap(keys[0], keys[1]);
  CHECK(idx.validate(sorted.data(), tc.side_bin) == Status::CorruptData);
  std::swap(keys[0], keys[1]);
  std::swap(sorted[0], sorted[n - 1]);  // triangles under another bucket's key
  CHECK(idx.validate(sorted.data(), tc.side_bin) == Status::CorruptData);
  std::swap(sorted[0], sorted[n - 1]);
  offsets[1] = offsets[2] + 1;
  CHECK(idx.validate(sorted.data(), tc.side_bin) == Status::CorruptData);
  build_triangle_index(tris.data(), n, tc.side_bin, sorted.data(), keys.data(), offsets.data(), &kc, scratch.data(),
                       ids.data());
  // Noisy copies (1% per side, under the 3% tolerance) match their originals; wrong labels do not.
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> e(-0.01f, 0.01f);
  Buffer mb(TriangleMatcher::required_bytes(4096) + 64);
  TriangleMatcher matcher;
  REQUIRE(matcher.bind(mb.arena, 4096) == Status::Ok);
  for (uint32_t t = 0; t < n; t += 11) {
    Triangle q = sorted[t];
    for (float& s : q.side) s *= 1.0f + e(rng);
    const TriangleMatchStats st = matcher.match(q, idx, sorted.data(), tc, 0.0f);
    CHECK(st.dropped() == 0);
    bool found = false;
    for (uint32_t k = 0; k < matcher.size(); ++k) found = found || matcher.match_at(k).map == t;
    CHECK(found);
    q.label[0] = static_cast<uint8_t>((q.label[0] + 1) % 4);
    matcher.match(q, idx, sorted.data(), tc, 0.0f);
    for (uint32_t k = 0; k < matcher.size(); ++k) CHECK(matcher.match_at(k).map != t);
  }
}

namespace {
uint32_t brute_force_clique(const ConsistencyGraph& g) {
  const uint32_t n = g.size();
  uint32_t best = 0;
  for (uint32_t mask = 1; mask < (1u << n); ++mask) {
    const uint32_t size = static_cast<uint32_t>(__builtin_popcount(mask));
    if (size <= best) continue;
    bool ok = true;
    for (uint32_t i = 0; i < n && ok; ++i)
      for (uint32_t j = i + 1; j < n && ok; ++j)
        if ((mask >> i & 1) && (mask >> j & 1)) ok = g.adjacent(i, j);
    if (ok) best = size;
  }
  return best;
}
bool is_clique(const ConsistencyGraph& g, const FixedVector<uint32_t>& c) {
  for (uint32_t i = 0; i < c.size(); ++i)
    for (uint32_t j = i + 1; j < c.size(); ++j)
      if (!g.adjacent(c[i], c[j])) return false;
  return true;
}
}  // namespace

TEST_CASE("Max clique is exact: known graphs and a brute-force oracle") {
  Buffer buf(ConsistencyGraph::required_bytes(256) + MaxCliqueSolver::required_bytes(256) + 256 * 4 + 64);
  ConsistencyGraph g;
  MaxCliqueSolver solver;
  FixedVector<uint32_t> clique;
  REQUIRE(g.bind(buf.arena, 256) == Status::Ok);
  REQUIRE(solver.bind(buf.arena, 256) == Status::Ok);
  REQUIRE(clique.bind(buf.arena, 256));
  // Complete graph, empty graph, odd cycle.
  g.reset(10);
  for (uint32_t i = 0; i < 10; ++i)
    for (uint32_t j = i + 1; j < 10; ++j) g.add_edge(i, j);
  REQUIRE(solver.solve(g, 1000000, clique, nullptr) == Status::Ok);
  CHECK(clique.size() == 10);
  g.reset(10);
  solver.solve(g, 1000000, clique, nullptr);
  CHECK(clique.size() == 1);
  g.reset(7);
  for (uint32_t i = 0; i < 7; ++i) g.add_edge(i, (i + 1) % 7);
  solver.solve(g, 1000000, clique, nullptr);
  CHECK(clique.size() == 2);
  // Random graphs vs the oracle, and a planted clique in a larger random graph.
  std::mt19937 rng(7);
  for (int trial = 0; trial < 60; ++trial) {
    const uint32_t n = 4 + trial % 14;
    const float p = 0.2f + 0.6f * (trial % 5) / 4.0f;
    g.reset(n);
    std::uniform_real_distribution<float> u(0, 1);
    for (uint32_t i = 0; i < n; ++i)
      for (uint32_t j = i + 1; j < n; ++j)
        if (u(rng) < p) g.add_edge(i, j);
    REQUIRE(solver.solve(g, 10000000, clique, nullptr) == Status::Ok);
    CHECK(is_clique(g, clique));
    CHECK(clique.size() == brute_force_clique(g));
  }
  g.reset(200);
  std::uniform_real_distribution<float> u(0, 1);
  for (uint32_t i = 0; i < 200; ++i)
    for (uint32_t j = i + 1; j < 200; ++j)
      if (u(rng) < 0.3f) g.add_edge(i, j);
  for (uint32_t i = 0; i < 200; i += 10)
    for (uint32_t j = i + 10; j < 200; j += 10) g.add_edge(i, j);  // 20 planted vertices
  REQUIRE(solver.solve(g, 10000000, clique, nullptr) == Status::Ok);
  CHECK(clique.size() >= 20);
  CHECK(is_clique(g, clique));
  // A tiny budget still returns a valid clique and says so.
  CliqueStats st;
  CHECK(solver.solve(g, 3, clique, &st) == Status::BudgetExhausted);
  CHECK(is_clique(g, clique));
  CHECK(clique.size() >= st.greedy_size);
  CHECK(clique.size() >= 1);
}

TEST_CASE("Consistency graph + clique find the inliers of a rigid motion; Kabsch and TLS recover it") {
  const int n = 40, inliers = 16;
  const auto a = random_points(n, 11);
  std::vector<float> b(n * 3);
  const Eigen::Isometry3d T = some_pose();
  std::mt19937 rng(12);
  std::uniform_real_distribution<float> u(-100, 100), noise(-0.05f, 0.05f);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d q = T * Eigen::Vector3d(a[3 * i], a[3 * i + 1], a[3 * i + 2]);
    for (int k = 0; k < 3; ++k) b[3 * i + k] = i < inliers ? static_cast<float>(q[k]) + noise(rng) : u(rng);
  }
  Buffer buf(ConsistencyGraph::required_bytes(64) + MaxCliqueSolver::required_bytes(64) + 64 * 4 + 64);
  ConsistencyGraph g;
  MaxCliqueSolver solver;
  FixedVector<uint32_t> clique;
  REQUIRE(g.bind(buf.arena, 64) == Status::Ok);
  REQUIRE(solver.bind(buf.arena, 64) == Status::Ok);
  REQUIRE(clique.bind(buf.arena, 64));
  REQUIRE(g.build(a.data(), b.data(), n, 1.0f) == Status::Ok);
  REQUIRE(solver.solve(g, 1000000, clique, nullptr) == Status::Ok);
  CHECK(clique.size() >= inliers);
  uint32_t true_in = 0;
  for (uint32_t v : clique) true_in += v < static_cast<uint32_t>(inliers);
  CHECK(true_in == static_cast<uint32_t>(inliers));
  // Kabsch on clean inliers is exact; TLS over everything (60% outliers) recovers T.
  Eigen::Isometry3d est;
  std::vector<float> clean(b);
  for (int i = 0; i < inliers; ++i) {
    const Eigen::Vector3d q = T * Eigen::Vector3d(a[3 * i], a[3 * i + 1], a[3 * i + 2]);
    for (int k = 0; k < 3; ++k) clean[3 * i + k] = static_cast<float>(q[k]);
  }
  REQUIRE(kabsch(a.data(), clean.data(), nullptr, inliers, &est) == Status::Ok);
  CHECK((est.translation() - T.translation()).norm() < 1e-3);
  CHECK(Eigen::AngleAxisd(est.rotation().transpose() * T.rotation()).angle() < 1e-4);
  std::vector<float> gw(n);
  std::vector<uint8_t> mask(n);
  TlsResult r;
  REQUIRE(solve_tls(a.data(), b.data(), nullptr, n, 1.0, 100, &r, mask.data(), gw.data()) == Status::Ok);
  CHECK((r.b_T_a.translation() - T.translation()).norm() < 0.1);
  CHECK(r.inliers == static_cast<uint32_t>(inliers));
  // Degenerate input is a status, not NaN.
  const float line_a[9] = {0, 0, 0, 1, 0, 0, 2, 0, 0};
  CHECK(kabsch(line_a, line_a, nullptr, 3, &est) == Status::InvalidInput);
  CHECK(kabsch(a.data(), b.data(), nullptr, 2, &est) == Status::InvalidInput);
  const float zero_w[3] = {0, 0, 0};
  CHECK(kabsch(a.data(), b.data(), zero_w, 3, &est) == Status::InvalidInput);
}
