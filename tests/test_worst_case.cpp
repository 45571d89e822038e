// Adversarial inputs for the expensive stages: work and memory stay within what the Config implies.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "gsf/detail/max_clique.h"
#include "gsf/localizer.h"
#include "mapping/map_builder.h"

namespace test_worst_case {

using namespace gsf;

TEST_CASE("A dense random consistency graph: the clique search stops at its node budget with a valid clique") {
  std::vector<uint64_t> mem((ConsistencyGraph::required_bytes(256) + MaxCliqueSolver::required_bytes(256) + 4096) / 8 +
                            2);
  Arena arena(mem.data(), mem.size() * 8);
  ConsistencyGraph g;
  MaxCliqueSolver solver;
  FixedVector<uint32_t> clique;
  REQUIRE(g.bind(arena, 256) == Status::Ok);
  REQUIRE(solver.bind(arena, 256) == Status::Ok);
  REQUIRE(clique.bind(arena, 256));
  REQUIRE(g.reset(256) == Status::Ok);
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(0, 1);
  for (uint32_t i = 0; i < 256; ++i)
    for (uint32_t j = i + 1; j < 256; ++j)
      if (u(rng) < 0.9f) g.add_edge(i, j);  // exponential for exact search
  CliqueStats st;
  const uint64_t budget = 20000;
  CHECK(solver.solve(g, budget, clique, &st) == Status::BudgetExhausted);
  CHECK(st.nodes <= budget);
  CHECK(clique.size() >= st.greedy_size);
  CHECK(clique.size() >= 20);
  for (uint32_t a = 0; a < clique.size(); ++a)
    for (uint32_t b = a + 1; b < clique.size(); ++b) CHECK(g.adjacent(clique[a], clique[b]));
}

namespace {
// A perfect lattice of identical poles (every triangle of the scan collides with many of the map's).
void lattice_scan(float ox, float oy, std::vector<float>* pts, std::vector<uint32_t>* labels) {
  pts->clear();
  labels->clear();
  for (int gx = -6; gx <= 6; ++gx)
    for (int gy = -6; gy <= 6; ++gy) {
      const float cx = gx * 6.0f + ox, cy = gy * 6.0f + oy;
      if (std::hypot(cx, cy) < 3.0f) continue;
      for (int k = 0; k < 60; ++k) {
        const float a = 0.1047f * k;
        pts->insert(pts->end(), {cx + 0.12f * std::cos(a), cy + 0.12f * std::sin(a), -1.5f + 0.08f * k, 0.0f});
        labels->push_back(80);
      }
    }
  for (float x = -40; x <= 40; x += 0.5f)
    for (float y = -40; y <= 40; y += 0.5f) {
      pts->insert(pts->end(), {x, y, -1.73f, 0.0f});
      labels->push_back(40);
    }
}
}  // namespace

TEST_CASE("A lattice where every triangle collides in the hash: matches, correspondences and clique stay capped") {
  LocalizerConfig cfg;
  cfg.match.max_candidates = 5000;
  cfg.match.max_matches_per_triangle = 32;
  cfg.hypotheses.first_budget = 50000;
  cfg.hypotheses.next_budget = 5000;
  mapping::MapBuildConfig build_config;
  build_config.stages = cfg;
  mapping::MapBuilder builder(build_config);
  std::vector<float> pts;
  std::vector<uint32_t> labels;
  for (int s = 0; s < 4; ++s) {
    lattice_scan(0, 0, &pts, &labels);
    ScanView v;
    v.points = pts.data();
    v.labels = labels.data();
    v.count = static_cast<uint32_t>(labels.size());
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = Eigen::Vector3d(24.0 * s, 0, 0);  // shifted by whole lattice periods
    REQUIRE(builder.add_scan(v, pose) == Status::Ok);
  }
  std::vector<uint64_t> blob;
  size_t bytes = 0;
  REQUIRE(builder.build(&blob, &bytes, nullptr) == Status::Ok);
  MapView map;
  REQUIRE(load_map(blob.data(), bytes, &map) == Status::Ok);
  REQUIRE(map.counts.instances > 150);
  const size_t need = Localizer::required_bytes(cfg);
  std::vector<uint64_t> ws(need / 8 + 2);
  Localizer loc;
  REQUIRE(loc.init(cfg, map, ws.data(), ws.size() * 8) == Status::Ok);
  CHECK(loc.workspace_bytes() <= need);  // memory: exactly the precomputed buffer
  lattice_scan(0.3f, -0.2f, &pts, &labels);
  ScanView q;
  q.points = pts.data();
  q.labels = labels.data();
  q.count = static_cast<uint32_t>(labels.size());
  for (bool gsf : {false, true}) {  // the loop ends with GSF on, as `full` below needs
    LocalizerConfig mode = cfg;
    mode.gsf.enabled = gsf;
    REQUIRE(loc.init(mode, map, ws.data(), ws.size() * 8) == Status::Ok);
    LocalizeResult r;
    loc.localize(q, &r);
    INFO("gsf " << gsf << ": " << r.query_triangles << " triangles, " << r.triangle_matches << " matches, "
                << r.correspondences << " correspondences, " << r.clique_nodes << " clique nodes");
    CHECK(r.triangle_matches <= r.query_triangles * cfg.match.max_matches_per_triangle);
    CHECK(r.match_dropped == r.match_candidates - r.triangle_matches);  // every drop is counted
    CHECK(r.match_dropped > 0);
    CHECK(r.candidate_pairs <= cfg.match.max_candidates);
    CHECK(r.correspondences <= cfg.match.max_correspondences);
    CHECK(r.hypotheses <= cfg.hypotheses.max_hypotheses);
    // Each of at most 2K searches stays within its budget (+1 node for the root of each search).
    CHECK(r.clique_nodes <=
          cfg.hypotheses.first_budget + 2 * cfg.hypotheses.max_hypotheses * (cfg.hypotheses.next_budget + 1));
    CHECK(r.capacity_truncated);  // the caps were hit and reported
    CHECK(loc.workspace_bytes() <= need);
  }
  // A scan budget (match.max_matches_per_scan) bounds the matches of all triangles together: each
  // triangle keeps its best budget / triangles (at least 1), and the drops are still counted.
  LocalizerConfig budgeted = cfg;
  budgeted.match.max_matches_per_scan = 2000;
  REQUIRE(Localizer::required_bytes(budgeted) == need);  // a work bound, not memory
  Localizer lb;
  std::vector<uint64_t> ws2(need / 8 + 2);
  REQUIRE(lb.init(budgeted, map, ws2.data(), ws2.size() * 8) == Status::Ok);
  LocalizeResult full, cut;
  loc.localize(q, &full);
  lb.localize(q, &cut);
  REQUIRE(cut.query_triangles == full.query_triangles);
  const uint32_t per_triangle = std::max<uint32_t>(1, 2000 / cut.query_triangles);
  INFO(cut.query_triangles << " triangles, " << full.triangle_matches << " matches without the budget, "
                           << cut.triangle_matches << " with it");
  CHECK(cut.triangle_matches <= cut.query_triangles * per_triangle);
  CHECK(cut.triangle_matches < full.triangle_matches);
  CHECK(cut.match_candidates == full.match_candidates);  // the same candidates, ranked, then capped
  CHECK(cut.match_dropped == cut.match_candidates - cut.triangle_matches);
}

}  // namespace test_worst_case
