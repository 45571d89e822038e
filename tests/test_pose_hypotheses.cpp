// Pose hypotheses alone (core/include/gsf/detail/pose_hypotheses.h) on hand-made correspondences:
// peeled cliques (one per lattice shift), heading-diverse cliques, the edges removed at a heading, and
// the shift votes (bins ranked by support, votes over the pairs ranked out of the graph).
#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <vector>

#include "arena_buffer.h"
#include "gsf/config.h"
#include "gsf/detail/max_clique.h"
#include "gsf/detail/pose_distance.h"
#include "gsf/detail/pose_hypotheses.h"

namespace test_pose_hypotheses {

using namespace gsf;
using gsf_test::ArenaBuffer;

namespace {

// A 1-D lattice of columns every 8 m along x; correspondences of 6 query columns to map columns shifted
// by `shift` periods.
void lattice_correspondences(int shift, float noise, std::vector<float>* a, std::vector<float>* b) {
  for (int k = 0; k < 6; ++k) {
    const float x = 8.0f * k, y = (k % 2) ? 4.0f : -4.0f;
    a->insert(a->end(), {x + noise * (k % 3), y, 0.0f});
    b->insert(b->end(), {x + 8.0f * shift + 100.0f, y + 50.0f, 0.0f});
  }
}

// A pose turned by yaw_deg about z and moved to (x, y, 0).
Eigen::Isometry3d yawed(double yaw_deg, double x, double y) {
  Eigen::Isometry3d P = Eigen::Isometry3d::Identity();
  P.linear() = Eigen::AngleAxisd(yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  P.translation() = Eigen::Vector3d(x, y, 0);
  return P;
}

// Correspondences of the scan points pts (n x 3) to their images under pose, appended to a and b.
template <size_t N>
void add_correspondences(const float (&pts)[N][3], const Eigen::Isometry3d& pose, std::vector<float>* a,
                         std::vector<float>* b) {
  for (const auto& p : pts) {
    const Eigen::Vector3d q(p[0], p[1], p[2]), m = pose * q;
    for (int d = 0; d < 3; ++d) {
      a->push_back(float(q[d]));
      b->push_back(float(m[d]));
    }
  }
}

// PoseHypotheses bound in an arena of its own, for 64 correspondences.
struct BoundHypotheses {
  ArenaBuffer buf;
  PoseHypotheses hyp;
  explicit BoundHypotheses(uint32_t max_hypotheses, uint32_t max_votes = 0)
      : buf(PoseHypotheses::required_bytes(64, max_hypotheses, max_votes)) {
    REQUIRE(hyp.bind(buf.arena, 64, max_hypotheses, max_votes) == Status::Ok);
  }
};

// Index of the first hypothesis within 0.1 m and 0.01 rad of pose, or -1.
int find_pose(const PoseHypotheses& hyp, const Eigen::Isometry3d& pose) {
  for (uint32_t h = 0; h < hyp.size(); ++h) {
    const Eigen::Isometry3d d = pose.inverse() * hyp[h].map_T_scan;
    if (d.translation().norm() < 0.1 && Eigen::AngleAxisd(d.linear()).angle() < 0.01) return int(h);
  }
  return -1;
}

// 8 scan points for a pose the most correspondences agree on, and 6 for another.
const float kEightPoints[8][3] = {{5, 17, 1},    {-19, 11, 0.5f}, {22, -13, 1.2f}, {-9, -21, 0.3f},
                                  {9, -2, 0.9f}, {-4, 8, 1.1f},   {14, 3, 0.4f},   {-24, -9, 0.8f}};
const float kSixPoints[6][3] = {{3, 1, 0.5f}, {-7, 4, 1}, {12, -5, 0.2f}, {-2, -14, 1.5f}, {18, 9, 0.7f}, {-15, -3, 1}};

}  // namespace

TEST_CASE("Peeling yields one hypothesis per lattice shift, the largest clique first") {
  std::vector<float> a, b;
  lattice_correspondences(0, 0.02f, &a, &b);  // the true shift: 6 correspondences
  std::vector<float> a2, b2;
  lattice_correspondences(2, 0.0f, &a2, &b2);  // a competing shift: its first 4 only
  a.insert(a.end(), a2.begin(), a2.begin() + 12);
  b.insert(b.end(), b2.begin(), b2.begin() + 12);
  const uint32_t n = static_cast<uint32_t>(a.size() / 3);
  std::vector<float> w(n, 1.0f);
  HypothesisConfig hc;
  BoundHypotheses bound(8);
  PoseHypotheses& hyp = bound.hyp;
  HypothesisStats st;
  REQUIRE(hyp.generate(a.data(), b.data(), w.data(), n, hc, &st) == Status::Ok);
  REQUIRE(hyp.size() >= 2);
  CHECK(hyp[0].clique_size == 6);
  CHECK(hyp[0].map_T_scan.translation().isApprox(Eigen::Vector3d(100, 50, 0), 0.05));
  CHECK(hyp[1].clique_size == 4);
  CHECK(hyp[1].map_T_scan.translation().isApprox(Eigen::Vector3d(116, 50, 0), 0.05));
  for (uint32_t i = 0; i < 6; ++i) CHECK(hyp.in_clique(0, i));
  CHECK(st.searches >= 2);
  CHECK_FALSE(st.budget_exhausted);
  // Too few correspondences: no hypothesis, a clear status.
  CHECK(hyp.generate(a.data(), b.data(), w.data(), 2, hc, &st) == Status::NoSolution);
  CHECK(hyp.size() == 0);
}

TEST_CASE("Heading-diverse cliques give the true heading a hypothesis when the largest cliques share a wrong one") {
  // 8 correspondences agree on a wrong pose W (a lattice's 180 deg turn), 6 on the truth T (yaw 12 deg).
  // With one peeled clique, every hypothesis (the clique and its shift votes) has W's heading; the
  // heading-diverse search removes the edges at that heading and finds T's clique.
  const Eigen::Isometry3d T = yawed(12, 100, 50), W = yawed(192, 140, 70);
  const double yaw_t = 12.0 * M_PI / 180.0;
  std::vector<float> a, b;
  add_correspondences(kEightPoints, W, &a, &b);
  add_correspondences(kSixPoints, T, &a, &b);
  const uint32_t n = static_cast<uint32_t>(a.size() / 3);
  std::vector<float> w(n, 1.0f);
  HypothesisConfig hc;
  hc.max_peeled = 1;
  hc.shift_headings = 2;
  BoundHypotheses bound(16);
  PoseHypotheses& hyp = bound.hyp;
  auto has_heading = [&](double yaw) {
    for (uint32_t h = 0; h < hyp.size(); ++h) {
      if (std::fabs(std::remainder(yaw_of(hyp[h].map_T_scan) - yaw, 2 * M_PI)) < 5.0 * M_PI / 180.0) return true;
    }
    return false;
  };
  HypothesisStats st;
  hc.heading_cliques = 0;
  REQUIRE(hyp.generate(a.data(), b.data(), w.data(), n, hc, &st) == Status::Ok);
  CHECK(hyp[0].clique_size == 8);
  CHECK(find_pose(hyp, W) >= 0);
  CHECK_FALSE(has_heading(yaw_t));  // the truth's heading is never tried
  hc.heading_cliques = 3;
  REQUIRE(hyp.generate(a.data(), b.data(), w.data(), n, hc, &st) == Status::Ok);
  CHECK(hyp[0].clique_size == 8);  // the paper's answer stays first
  CHECK(find_pose(hyp, W) >= 0);
  CHECK(find_pose(hyp, T) >= 0);
  CHECK(st.heading_cliques == 1);
}

TEST_CASE("Heading-diverse cliques run when peeling already filled the headings with a stray one") {
  // 8 correspondences agree on a wrong pose W (a lattice's turn), 4 on a stray pose S at a third heading,
  // 3 on the truth T. Two peeled cliques (W, then S) give shift_headings = 2 distinct headings; before,
  // that stopped the heading-diverse search and T's heading was never tried (seed 41's lattice: a clique
  // of 3 at a stray heading left out the true heading, and the answer was a confident 180-degree flip).
  const Eigen::Isometry3d W = yawed(190, 140, 70), S = yawed(57, -60, 20), T = yawed(10, 100, 50);
  const float stray_pts[4][3] = {{30, 30, 1}, {-31, 27, 0.6f}, {26, -33, 1.4f}, {-28, -29, 0.2f}};
  const float true_pts[3][3] = {{3, 1, 0.5f}, {-7, 4, 1}, {12, -5, 0.2f}};
  std::vector<float> a, b;
  add_correspondences(kEightPoints, W, &a, &b);
  add_correspondences(stray_pts, S, &a, &b);
  add_correspondences(true_pts, T, &a, &b);
  const uint32_t n = static_cast<uint32_t>(a.size() / 3);
  std::vector<float> w(n, 1.0f);
  HypothesisConfig hc;
  hc.max_peeled = 2;
  hc.shift_headings = 2;
  hc.heading_cliques = 3;
  BoundHypotheses bound(16);
  PoseHypotheses& hyp = bound.hyp;
  HypothesisStats st;
  REQUIRE(hyp.generate(a.data(), b.data(), w.data(), n, hc, &st) == Status::Ok);
  CHECK(find_pose(hyp, W) == 0);  // the maximum clique first
  CHECK(find_pose(hyp, S) == 1);  // peeled second
  CHECK(find_pose(hyp, T) >= 2);  // found by the heading-diverse search
  CHECK(st.heading_cliques >= 1);
  // Without it, T is not found.
  hc.heading_cliques = 0;
  REQUIRE(hyp.generate(a.data(), b.data(), w.data(), n, hc, &st) == Status::Ok);
  CHECK(find_pose(hyp, T) < 0);
}

TEST_CASE("Shift-vote keys sort as std::sort by key then index: radix within 2^16 bins a side, std::sort beyond") {
  // Keys x << 21 | y (21 bits each) with many ties; the reference is the comparison the votes used before.
  std::mt19937 rng(11);
  for (const int64_t span : {3, 200, 70000}) {  // the last is wider than 2^16 bins: the fallback
    std::uniform_int_distribution<int64_t> u(0, span);
    const uint32_t n = 5000;
    std::vector<uint64_t> key(n);
    for (uint64_t& k : key) k = (uint64_t((1 << 20) + u(rng)) << 21) | uint64_t((1 << 20) - u(rng) / 2);
    std::vector<uint32_t> order(n), scratch_key(n), scratch_order(n), want(n);
    for (uint32_t i = 0; i < n; ++i) want[i] = i;
    std::sort(want.begin(), want.end(),
              [&](uint32_t a, uint32_t b) { return key[a] < key[b] || (key[a] == key[b] && a < b); });
    sort_by_shift_key(key.data(), n, order.data(), scratch_key.data(), scratch_order.data());
    CHECK(order == want);
  }
  uint64_t one = 7;
  uint32_t o = 99, sk = 0, so = 0;
  sort_by_shift_key(&one, 1, &o, &sk, &so);
  CHECK(o == 0);
}

TEST_CASE("Removing the edges at a heading removes exactly the pairs that turn by it") {
  // Three correspondences turned by 90 deg (pairwise consistent), one pair of which is too short to
  // tell a heading, and one correspondence consistent with all but turned by 0 deg relative to the first.
  const float a[4 * 3] = {0, 0, 0, 10, 0, 0, 10, 0.5f, 0, 0, 10, 0};
  const float b[4 * 3] = {0, 0, 0, 0, 10, 0, -0.5f, 10, 0, 0, 10, 0};
  ArenaBuffer buf(ConsistencyGraph::required_bytes(8));
  ConsistencyGraph g;
  REQUIRE(g.bind(buf.arena, 8) == Status::Ok);
  REQUIRE(g.build(a, b, 4, 0.1f) == Status::Ok);
  REQUIRE(g.adjacent(0, 1));
  REQUIRE(g.adjacent(0, 2));
  REQUIRE(g.adjacent(1, 2));
  REQUIRE(g.adjacent(0, 3));
  const uint32_t removed = g.remove_edges_at_heading(a, b, M_PI / 2, 5.0 * M_PI / 180.0, 1.0f);
  CHECK(removed == 2);  // (0,1) and (0,2); (1,2) is 0.5 m long
  CHECK_FALSE(g.adjacent(0, 1));
  CHECK_FALSE(g.adjacent(1, 0));
  CHECK_FALSE(g.adjacent(0, 2));
  CHECK(g.adjacent(1, 2));
  CHECK(g.adjacent(0, 3));  // (0,3) turns by 0 deg
}

TEST_CASE("Removing the edges at a heading walks the set bits: the same edges as the plain pair loop") {
  // 150 random correspondences (3 words a row), about a third of the pairs consistent; the plain loop
  // over every pair (i < j) with the same arithmetic is the reference.
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-30.0f, 30.0f);
  const uint32_t n = 150;
  std::vector<float> a(3 * n), b(3 * n);
  for (uint32_t i = 0; i < n; ++i) {
    a[3 * i] = u(rng), a[3 * i + 1] = u(rng), a[3 * i + 2] = 0.1f * u(rng);
    // Half the correspondences turned by 90 deg, half by 30 deg, with noise.
    const float c = i % 2 ? 0.0f : 0.8660254f, s = i % 2 ? 1.0f : 0.5f;
    b[3 * i] = c * a[3 * i] - s * a[3 * i + 1] + 0.05f * u(rng);
    b[3 * i + 1] = s * a[3 * i] + c * a[3 * i + 1] + 0.05f * u(rng);
    b[3 * i + 2] = a[3 * i + 2];
  }
  ArenaBuffer buf(2 * ConsistencyGraph::required_bytes(n));
  ConsistencyGraph g, ref;
  REQUIRE(g.bind(buf.arena, n) == Status::Ok);
  REQUIRE(ref.bind(buf.arena, n) == Status::Ok);
  REQUIRE(g.build(a.data(), b.data(), n, 2.0f) == Status::Ok);
  REQUIRE(ref.build(a.data(), b.data(), n, 2.0f) == Status::Ok);
  const double yaw = M_PI / 2, tol = 5.0 * M_PI / 180.0, min2 = 1.0;
  uint32_t expected = 0, edges = 0;
  for (uint32_t i = 0; i < n; ++i)
    for (uint32_t j = i + 1; j < n; ++j) {
      if (!ref.adjacent(i, j)) continue;
      ++edges;
      const double ax = double(a[3 * j]) - a[3 * i], ay = double(a[3 * j + 1]) - a[3 * i + 1];
      const double bx = double(b[3 * j]) - b[3 * i], by = double(b[3 * j + 1]) - b[3 * i + 1];
      const double la2 = ax * ax + ay * ay, lb2 = bx * bx + by * by;
      if (la2 < min2 || lb2 < min2) continue;
      const double rx = std::cos(yaw) * ax - std::sin(yaw) * ay, ry = std::sin(yaw) * ax + std::cos(yaw) * ay;
      if ((rx * bx + ry * by) >= std::cos(tol) * std::sqrt(la2 * lb2)) {
        ref.remove_edge(i, j);
        ++expected;
      }
    }
  CHECK(g.remove_edges_at_heading(a.data(), b.data(), yaw, tol, 1.0f) == expected);
  uint32_t differ = 0;
  for (uint32_t i = 0; i < n; ++i)
    for (uint32_t j = 0; j < n; ++j) differ += g.adjacent(i, j) != ref.adjacent(i, j);
  CHECK(differ == 0);
  INFO(edges << " edges, " << expected << " removed");
  CHECK(expected > 100);          // the 90 deg pairs went
  CHECK(edges - expected > 100);  // the 30 deg ones stayed
}

namespace {

// Correspondences for the shift-vote tests: one heading (the first clique's: 8 correspondences at
// translation (100, 50)), then six lattice shifts 8 m apart with 3 votes each in one bin; `x` is where
// the next query point goes.
struct ShiftVoteScene {
  std::vector<float> a, b;
  float x = 30.0f;
  void add(float qx, float qy, float qz, float tx, float ty) {
    a.insert(a.end(), {qx, qy, qz});
    b.insert(b.end(), {qx + tx, qy + ty, qz});
  }
  ShiftVoteScene() {
    const float clique_pts[8][2] = {{3, 1}, {-7, 4}, {12, -5}, {-2, -14}, {18, 9}, {-15, -3}, {6, 11}, {-11, 7}};
    for (const auto& p : clique_pts) add(p[0], p[1], 0.5f, 100.0f, 50.0f);
    for (int k = 1; k <= 6; ++k)  // bins well inside
      for (int j = 0; j < 3; ++j, x += 1.7f) add(x, -20.0f + 3.0f * j, 1.0f, 100.0f + 8.0f * k + 1.0f, 50.5f);
  }
  uint32_t size() const { return static_cast<uint32_t>(a.size() / 3); }
  // One peeled clique, no heading-diverse search: the hypotheses are the clique and its shift votes.
  static HypothesisConfig one_heading(uint32_t max_hypotheses) {
    HypothesisConfig hc;
    hc.max_peeled = 1;
    hc.heading_cliques = 0;
    hc.max_hypotheses = max_hypotheses;
    return hc;
  }
};

}  // namespace

TEST_CASE("Shift votes rank bins by their support: a translation split across a bin edge still becomes a hypothesis") {
  // The clique and the lattice shifts (ShiftVoteScene), and the truth with 4 votes that straddle the
  // bin edge at x = 160 (2 + 2).
  ShiftVoteScene sc;
  for (int j = 0; j < 4; ++j, sc.x += 1.9f)
    sc.add(sc.x, 25.0f + 2.0f * j, 1.0f, 160.0f + (j % 2 ? 0.05f : -0.05f), 51.0f);
  const std::vector<float>&a = sc.a, &b = sc.b;
  const uint32_t n = sc.size();
  std::vector<float> w(n, 1.0f);
  HypothesisConfig hc = ShiftVoteScene::one_heading(4);  // the clique and 3 shift votes
  BoundHypotheses bound(8);
  PoseHypotheses& hyp = bound.hyp;
  auto has_translation = [&](double tx, double ty) {
    for (uint32_t h = 0; h < hyp.size(); ++h)
      if ((hyp[h].map_T_scan.translation().head<2>() - Eigen::Vector2d(tx, ty)).norm() < 0.2) return true;
    return false;
  };
  HypothesisStats st;
  // Each bin on its own would hold 2 of the truth's votes, below min_inliers; its support holds them all.
  REQUIRE(hyp.generate(a.data(), b.data(), w.data(), n, hc, &st) == Status::Ok);
  CHECK(hyp.size() == 4);
  CHECK(has_translation(100, 50));
  CHECK(has_translation(160, 51));
  // A bad radius is a configuration error, not a slow query.
  LocalizerConfig cfg;
  cfg.hypotheses.tls_threshold = 2.5f;  // a support radius beyond the 3 x 3 bins searched
  CHECK(validate(cfg) == Status::InvalidArgument);
}

TEST_CASE("Shift votes over the pairs ranked out of the graph find the true shift the graph holds one pair of") {
  // The graph's pairs: a clique of 8 at translation (100, 50), six lattice shifts with 3 pairs each, and
  // one pair of the truth (160, 51). Ranked after them, outside the graph: 5 more pairs of the truth and
  // 2 more of one lattice shift. In a lattice the graph's cap keeps a few true pairs of many.
  ShiftVoteScene sc;
  const float x = sc.x;
  sc.add(x, 25.0f, 1.0f, 160.0f, 51.0f);
  const uint32_t n = sc.size();
  const float truth_dx[5] = {0.1f, -0.1f, 0.05f, -0.05f, 0.0f};
  for (int j = 0; j < 5; ++j) sc.add(x + 2.0f + 1.9f * j, 27.0f + 2.0f * j, 1.0f, 160.0f + truth_dx[j], 51.0f);
  for (int j = 0; j < 2; ++j) sc.add(x - 12.0f + 2.3f * j, -30.0f, 1.0f, 100.0f + 8.0f + 1.0f, 50.5f);
  const std::vector<float>&a = sc.a, &b = sc.b;
  const uint32_t total = sc.size();
  std::vector<float> w(total, 1.0f);
  HypothesisConfig hc = ShiftVoteScene::one_heading(3);  // the clique and the two best shift bins
  BoundHypotheses bound(8, 128);
  PoseHypotheses& hyp = bound.hyp;
  auto find_translation = [&](double tx, double ty) {
    for (uint32_t h = 0; h < hyp.size(); ++h)
      if ((hyp[h].map_T_scan.translation().head<2>() - Eigen::Vector2d(tx, ty)).norm() < 0.2) return int(h);
    return -1;
  };
  HypothesisStats st;
  // The graph's pairs alone: the truth has one vote, below min_inliers.
  REQUIRE(hyp.generate(a.data(), b.data(), w.data(), n, hc, &st) == Status::Ok);
  CHECK(st.vote_pairs == n);
  CHECK(find_translation(100, 50) == 0);
  CHECK(find_translation(160, 51) < 0);
  // All of them: the truth's 6 pairs make the best shift bin, fitted on its own votes only (translation
  // the mean of the six, exactly), and the cliques are unchanged.
  REQUIRE(hyp.generate(a.data(), b.data(), w.data(), n, hc, &st, total) == Status::Ok);
  CHECK(st.vote_pairs == total);
  CHECK(find_translation(100, 50) == 0);
  const int h = find_translation(160, 51);
  REQUIRE(h == 1);
  CHECK(hyp[uint32_t(h)].inliers == 6);
  CHECK(std::fabs(hyp[uint32_t(h)].map_T_scan.translation().x() - 160.0) < 1e-4);
  CHECK(hyp[uint32_t(h)].clique_size == 0);
  // More votes than bound, or a graph larger than the votes' capacity: refused, nothing kept.
  CHECK(hyp.generate(a.data(), b.data(), w.data(), n, hc, &st, 129) == Status::CapacityExceeded);
  ArenaBuffer small(PoseHypotheses::required_bytes(64, 8, 128));
  PoseHypotheses bad;
  CHECK(bad.bind(small.arena, 64, 8, 32) == Status::InvalidArgument);
}

}  // namespace test_pose_hypotheses
