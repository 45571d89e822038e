// The maximum clique alone (core/include/gsf/detail/max_clique.h): exact on known graphs and against a
// brute-force oracle, a planted clique, and a node budget that still returns a valid clique.
#include <catch2/catch.hpp>

#include <random>
#include <vector>

#include "arena_buffer.h"
#include "gsf/detail/max_clique.h"

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
