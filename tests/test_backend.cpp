// The back end chained on one synthetic rigid motion: consistency graph + maximum clique find the inliers,
// then Kabsch and TLS recover the motion (each stage alone: test_max_clique.cpp, test_pose_solver.cpp).
#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <vector>

#include "arena_buffer.h"
#include "gsf/detail/max_clique.h"
#include "gsf/detail/pose_solver.h"
#include "random_points.h"

namespace test_backend {

using namespace gsf;
using gsf_test::random_points;
using gsf_test::some_pose;
using Buffer = gsf_test::ArenaBuffer;

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

}  // namespace test_backend
