// Zero heap allocations over fitting, probing (with full covariance) and both W2 paths for many
// fields after binding - including the exact reference path the localizer does not use per scan.
#include <catch2/catch.hpp>

#include <random>
#include <vector>

#include "alloc_counter.h"
#include "arena_buffer.h"
#include "gsf/detail/gaussian_field.h"
#include "gsf/detail/wasserstein.h"

using namespace gsf;

TEST_CASE("Fields and W2 never allocate after bind") {
  FieldConfig fc;
  const uint32_t n = 600, G = grid_points(fc), M = fc.inducing_points;
  gsf_test::ArenaBuffer buf(FieldSolver::required_bytes(fc, n) + W2Exact::required_bytes(G) + 64);
  FieldSolver solver;
  W2Exact exact;
  REQUIRE(solver.bind(buf.arena, fc, n) == Status::Ok);
  REQUIRE(exact.bind(buf.arena, G) == Status::Ok);
  // Inputs prepared before the measured region (they stand for the voxel layer's output).
  std::mt19937 rng(2);
  std::uniform_real_distribution<float> u(-8, 8), p(0, 1);
  std::vector<float> xyz(n * 3), tgt(n * kNumClasses), grid(G * 3), in(2 * M * 3), al(2 * M * kNumClasses),
      ch(2 * M * M), mean(2 * G * kNumClasses), var(2 * G), cov(2 * G * G);
  std::vector<uint8_t> lab(n);
  for (uint32_t i = 0; i < n; ++i) {
    xyz[3 * i] = u(rng);
    xyz[3 * i + 1] = u(rng);
    xyz[3 * i + 2] = 0;
    lab[i] = static_cast<uint8_t>(i % 5 == 0 ? kPole : (xyz[3 * i] > 0 ? kVegetation : kRoad));
    tgt[i * kNumClasses + lab[i]] = 1.0f;
  }
  float w[kNumClasses];
  stability_weights(w);
  make_probe_grid(fc, 0.3f, grid.data());
  double total = 0;
  gsf_test::AllocationScope scope;
  for (int round = 0; round < 100; ++round) {
    for (int f = 0; f < 2; ++f) {
      uint32_t m = 0;
      const uint32_t take = n - 100 * f - round;  // different data per field and round
      REQUIRE(solver.fit(xyz.data(), tgt.data(), lab.data(), take, &in[f * M * 3], &al[f * M * kNumClasses],
                         &ch[f * M * M], &m) == Status::Ok);
      REQUIRE(solver.probe(FieldView{&in[f * M * 3], &al[f * M * kNumClasses], m}, &ch[f * M * M], grid.data(), G,
                           &mean[f * G * kNumClasses], &var[f * G], &cov[f * G * G]) == Status::Ok);
    }
    double e = 0;
    REQUIRE(exact.w2_squared(mean.data(), cov.data(), &mean[G * kNumClasses], &cov[G * G], G, w, &e) == Status::Ok);
    total += e + w2_squared_diag(mean.data(), var.data(), &mean[G * kNumClasses], &var[G], G, w);
    total += w2_squared_diag_observed(mean.data(), var.data(), &mean[G * kNumClasses], &var[G], G, w, 0.6f, 1.0f).w2;
  }
  CHECK(scope.allocations() == 0);
  CHECK(total > 0.0);  // the work was done
}
