// The maximum clique alone (core/include/gsf/detail/max_clique.h): exact on known graphs and against a
// brute-force oracle, a planted clique, a node budget that still returns a valid clique, and a search
// restricted to allowed vertices; the consistency graph's edges against their definition.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <vector>

#include "arena_buffer.h"
#include "gsf/detail/max_clique.h"

namespace test_max_clique {

using namespace gsf;
using Buffer = gsf_test::ArenaBuffer;

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

TEST_CASE("The consistency graph's edges are exactly the pairs whose distances agree within eps") {
  // Random correspondences (half of a rigid motion, half noise): edge (i, j) iff
  // | |a_i - a_j| - |b_i - b_j| | <= eps, with heights scaled by z_weight (0: bird's-eye distances).
  std::mt19937 rng(31);
  std::uniform_real_distribution<float> u(-30, 30), z(0, 5), jitter(-0.6f, 0.6f);
  const uint32_t n = 70;
  std::vector<float> a(3 * n), b(3 * n);
  for (uint32_t i = 0; i < n; ++i) {
    a[3 * i] = u(rng);
    a[3 * i + 1] = u(rng);
    a[3 * i + 2] = z(rng);
    const bool in = i % 2 == 0;
    b[3 * i] = in ? -a[3 * i + 1] + 50.0f + jitter(rng) : u(rng);  // a quarter turn and a shift
    b[3 * i + 1] = in ? a[3 * i] + jitter(rng) : u(rng);
    b[3 * i + 2] = in ? a[3 * i + 2] + 3.0f * jitter(rng) : z(rng);
  }
  Buffer buf(ConsistencyGraph::required_bytes(128) + 64);
  ConsistencyGraph g;
  REQUIRE(g.bind(buf.arena, 128) == Status::Ok);
  for (float zw : {1.0f, 0.0f, 0.5f}) {
    REQUIRE(g.build(a.data(), b.data(), n, 1.0f, zw) == Status::Ok);
    REQUIRE(g.size() == n);
    uint32_t edges = 0, wrong = 0;
    for (uint32_t i = 0; i < n; ++i) {
      CHECK_FALSE(g.adjacent(i, i));
      for (uint32_t j = i + 1; j < n; ++j) {
        auto dist = [&](const std::vector<float>& p) {
          const double dx = p[3 * i] - p[3 * j], dy = p[3 * i + 1] - p[3 * j + 1];
          const double dz = zw * (p[3 * i + 2] - p[3 * j + 2]);
          return std::sqrt(dx * dx + dy * dy + dz * dz);
        };
        const double gap = std::fabs(dist(a) - dist(b));
        if (std::fabs(gap - 1.0) < 1e-4) continue;  // within float rounding of eps: either is right
        const bool expect = gap <= 1.0;
        wrong += g.adjacent(i, j) != expect || g.adjacent(j, i) != expect;
        edges += expect;
      }
    }
    INFO("z_weight " << zw << ": " << edges << " edges");
    CHECK(wrong == 0);
    CHECK(edges > 300);  // the inliers' pairs at least (35 x 34 / 2 = 595 minus jitter)
  }
  // More vertices than bound: refused before any is read.
  CHECK(g.build(a.data(), b.data(), 129, 1.0f) != Status::Ok);
}

TEST_CASE("A clique search restricted to allowed vertices is the maximum clique of that induced subgraph") {
  Buffer buf(ConsistencyGraph::required_bytes(64) + MaxCliqueSolver::required_bytes(64) + 64 * 4 + 64);
  ConsistencyGraph g;
  MaxCliqueSolver solver;
  FixedVector<uint32_t> clique;
  REQUIRE(g.bind(buf.arena, 64) == Status::Ok);
  REQUIRE(solver.bind(buf.arena, 64) == Status::Ok);
  REQUIRE(clique.bind(buf.arena, 64));
  std::mt19937 rng(33);
  std::uniform_real_distribution<float> u(0, 1);
  for (int trial = 0; trial < 40; ++trial) {
    const uint32_t n = 8 + trial % 10;
    g.reset(n);
    for (uint32_t i = 0; i < n; ++i)
      for (uint32_t j = i + 1; j < n; ++j)
        if (u(rng) < 0.55f) g.add_edge(i, j);
    uint64_t allowed = 0;
    for (uint32_t i = 0; i < n; ++i)
      if (u(rng) < 0.6f) allowed |= uint64_t(1) << i;
    if (allowed == 0) allowed = 1;
    // The oracle: the largest clique among the allowed vertices, by brute force over their subsets.
    uint32_t best = 0;
    for (uint64_t mask = allowed;; mask = (mask - 1) & allowed) {
      if (mask == 0) break;
      const uint32_t size = static_cast<uint32_t>(__builtin_popcountll(mask));
      bool ok = size > best;
      for (uint32_t i = 0; i < n && ok; ++i)
        for (uint32_t j = i + 1; j < n && ok; ++j)
          if ((mask >> i & 1) && (mask >> j & 1)) ok = g.adjacent(i, j);
      if (ok) best = size;
    }
    INFO("trial " << trial);
    REQUIRE(solver.solve(g, 10000000, clique, nullptr, &allowed) == Status::Ok);
    CHECK(clique.size() == best);
    CHECK(is_clique(g, clique));
    for (uint32_t k = 0; k < clique.size(); ++k) {
      CHECK((allowed >> clique[k] & 1) == 1);
      if (k > 0) CHECK(clique[k - 1] < clique[k]);  // ascending ids
    }
  }
}

}  // namespace test_max_clique
