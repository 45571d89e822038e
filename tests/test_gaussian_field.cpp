// Gaussian semantic fields (gaussian_field.h), Algorithm 1 sparsification (sparsify.h) and the
// 2-Wasserstein similarity (wasserstein.h): closed forms, invariances, class proportions.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <vector>

#include "arena_buffer.h"
#include "gsf/detail/gaussian_field.h"
#include "gsf/detail/sparsify.h"
#include "gsf/detail/wasserstein.h"

namespace test_gaussian_field {

using namespace gsf;

namespace {
using Buffer = gsf_test::ArenaBuffer;
}  // namespace

TEST_CASE("Matern-3/2 closed form") {
  CHECK(matern32(0.0f, 2.0f, 1.5f) == Approx(1.5f));
  CHECK(matern32(2.0f, 2.0f, 1.0f) == Approx((1 + std::sqrt(3.0f)) * std::exp(-std::sqrt(3.0f))));
  CHECK(matern32(1.0f, 2.0f, 1.0f) > matern32(3.0f, 2.0f, 1.0f));
}

TEST_CASE("GP posterior matches hand-computed one- and two-point cases") {
  FieldConfig fc;
  fc.input_dims = 3;
  fc.noise_variance = 0.1f;
  Buffer buf(FieldSolver::required_bytes(fc, 16) + 64);
  FieldSolver solver;
  REQUIRE(solver.bind(buf.arena, fc, 16) == Status::Ok);
  // One point at the origin with target y: mean(x) = k(x,0) y / (k(0)+s2), var(x) = k(0) - k(x,0)^2/(k(0)+s2).
  float xyz[3] = {0, 0, 0}, y[kNumClasses] = {};
  y[3] = 0.8f;
  uint8_t lab[1] = {3};
  float in[kMaxInducing * 3], alpha[kMaxInducing * kNumClasses], chol[kMaxInducing * kMaxInducing];
  uint32_t m = 0;
  REQUIRE(solver.fit(xyz, y, lab, 1, in, alpha, chol, &m) == Status::Ok);
  REQUIRE(m == 1);
  const float grid[6] = {0, 0, 0, 1.5f, 0, 0};
  float mean[2 * kNumClasses], var[2], cov[4];
  REQUIRE(solver.probe(FieldView{in, alpha, m}, chol, grid, 2, mean, var, cov) == Status::Ok);
  const float k0 = 1.0f, k1 = matern32(1.5f, fc.length_scale, 1.0f);
  CHECK(mean[3] == Approx(k0 * 0.8f / (k0 + 0.1f)).epsilon(1e-4));
  CHECK(mean[kNumClasses + 3] == Approx(k1 * 0.8f / (k0 + 0.1f)).epsilon(1e-4));
  CHECK(var[0] == Approx(k0 - k0 * k0 / (k0 + 0.1f)).epsilon(1e-3));
  CHECK(var[1] == Approx(k0 - k1 * k1 / (k0 + 0.1f)).epsilon(1e-3));
  CHECK(cov[1] == Approx(k1 - k0 * k1 / (k0 + 0.1f)).epsilon(1e-3));
  CHECK(var[0] < var[1]);  // variance shrinks near data
  // Two points: solve the 2x2 system by hand.
  float xyz2[6] = {0, 0, 0, 1, 0, 0}, y2[2 * kNumClasses] = {};
  y2[0] = 1.0f;
  y2[kNumClasses + 0] = 0.2f;
  uint8_t lab2[2] = {0, 0};
  REQUIRE(solver.fit(xyz2, y2, lab2, 2, in, alpha, chol, &m) == Status::Ok);
  const double a = 1.1, b = matern32(1.0f, fc.length_scale, 1.0f), det = a * a - b * b;
  const double al0 = (a * 1.0 - b * 0.2) / det, al1 = (-b * 1.0 + a * 0.2) / det;
  const float g[3] = {0.5f, 0, 0};
  REQUIRE(solver.probe(FieldView{in, alpha, m}, chol, g, 1, mean, var, nullptr) == Status::Ok);
  const double kg = matern32(0.5f, fc.length_scale, 1.0f);
  CHECK(mean[0] == Approx(kg * al0 + kg * al1).epsilon(1e-4));
}

TEST_CASE("The posterior mean interpolates the targets as noise goes to zero") {
  FieldConfig fc;
  fc.noise_variance = 1e-4f;
  Buffer buf(FieldSolver::required_bytes(fc, 64) + 64);
  FieldSolver solver;
  REQUIRE(solver.bind(buf.arena, fc, 64) == Status::Ok);
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(-5, 5), p(0, 1);
  std::vector<float> xyz(20 * 3), y(20 * kNumClasses);
  std::vector<uint8_t> lab(20, 0);
  for (int i = 0; i < 20; ++i) {
    xyz[3 * i] = u(rng);
    xyz[3 * i + 1] = u(rng);
    xyz[3 * i + 2] = 0;
    for (int d = 0; d < kNumClasses; ++d) y[i * kNumClasses + d] = p(rng);
  }
  std::vector<float> in(kMaxInducing * 3), alpha(kMaxInducing * kNumClasses), chol(kMaxInducing * kMaxInducing);
  uint32_t m = 0;
  REQUIRE(solver.fit(xyz.data(), y.data(), lab.data(), 20, in.data(), alpha.data(), chol.data(), &m) == Status::Ok);
  REQUIRE(m == 20);
  std::vector<float> mean(20 * kNumClasses), var(20);
  REQUIRE(solver.probe(FieldView{in.data(), alpha.data(), m}, chol.data(), xyz.data(), 20, mean.data(), var.data(),
                       nullptr) == Status::Ok);
  for (int i = 0; i < 20 * kNumClasses; ++i) CHECK(mean[i] == Approx(y[i]).margin(0.02));
  for (int i = 0; i < 20; ++i) CHECK(var[i] < 0.01f);
}

TEST_CASE("The factor is lower and reproduces K; a grid probes as its points alone; the mean only where observed") {
  for (const uint32_t dims : {2u, 3u}) {
    FieldConfig fc;
    fc.input_dims = dims;
    fc.inducing_points = 32;
    Buffer buf(FieldSolver::required_bytes(fc, 64) + 64);
    FieldSolver solver;
    REQUIRE(solver.bind(buf.arena, fc, 64) == Status::Ok);
    std::mt19937 rng(7 + dims);
    std::uniform_real_distribution<float> u(-6, 6), p(0, 1);
    const uint32_t n = 29;  // not a multiple of the vector width
    std::vector<float> xyz(n * 3), y(n * kNumClasses);
    std::vector<uint8_t> lab(n, 0);
    for (uint32_t i = 0; i < n; ++i) {
      for (int d = 0; d < 3; ++d) xyz[3 * i + d] = d < 2 ? u(rng) : 0.3f * u(rng);
      for (int d = 0; d < kNumClasses; ++d) y[i * kNumClasses + d] = p(rng);
    }
    std::vector<float> in(kMaxInducing * 3), alpha(kMaxInducing * kNumClasses), chol(kMaxInducing * kMaxInducing);
    uint32_t m = 0;
    REQUIRE(solver.fit(xyz.data(), y.data(), lab.data(), n, in.data(), alpha.data(), chol.data(), &m) == Status::Ok);
    REQUIRE(m == n);
    // L is lower triangular and L L^T = K + noise I.
    for (uint32_t i = 0; i < m; ++i)
      for (uint32_t j = 0; j < m; ++j) {
        if (j > i) {
          CHECK(chol[i * m + j] == 0.0f);
          continue;
        }
        double llt = 0.0;
        for (uint32_t k = 0; k <= j; ++k) llt += double(chol[i * m + k]) * chol[j * m + k];
        double d2 = 0.0;
        for (uint32_t c = 0; c < dims; ++c) d2 += std::pow(double(in[3 * i + c]) - in[3 * j + c], 2);
        const double k =
            matern32(float(std::sqrt(d2)), fc.length_scale, fc.signal_variance) + (i == j ? fc.noise_variance : 0.0f);
        CHECK(llt == Approx(k).margin(1e-5));
      }
    // A 6 x 6 grid probed at once equals each point probed alone, bit for bit (the grid is padded to
    // whole vectors; every point is its own column of the solve).
    const uint32_t G = 36;
    std::vector<float> grid(G * 3);
    fc.grid_nx = fc.grid_ny = 6;
    make_probe_grid(fc, 0.4f, grid.data());
    const FieldView field{in.data(), alpha.data(), m};
    std::vector<float> mean(G * kNumClasses), var(G), mean1(kNumClasses), var1(1);
    REQUIRE(solver.probe(field, chol.data(), grid.data(), G, mean.data(), var.data(), nullptr) == Status::Ok);
    for (uint32_t s = 0; s < G; ++s) {
      REQUIRE(solver.probe(field, chol.data(), &grid[3 * s], 1, mean1.data(), var1.data(), nullptr) == Status::Ok);
      CHECK(var1[0] == var[s]);
      for (int d = 0; d < kNumClasses; ++d) CHECK(mean1[d] == mean[s * kNumClasses + d]);
    }
    // With mean_max_var the mean is the same where the variance is at most it, and 0 elsewhere.
    const float limit = 0.6f;
    std::vector<float> mean_obs(G * kNumClasses, -1.0f), var_obs(G);
    REQUIRE(solver.probe(field, chol.data(), grid.data(), G, mean_obs.data(), var_obs.data(), nullptr, limit) ==
            Status::Ok);
    uint32_t observed = 0;
    for (uint32_t s = 0; s < G; ++s) {
      CHECK(var_obs[s] == var[s]);
      observed += var[s] <= limit;
      for (int d = 0; d < kNumClasses; ++d)
        CHECK(mean_obs[s * kNumClasses + d] == (var[s] <= limit ? mean[s * kNumClasses + d] : 0.0f));
    }
    CHECK(observed > 0);
    CHECK(observed < G);  // the test sees both kinds of point
  }
}

TEST_CASE("Algorithm 1 keeps class proportions, exact total, deterministic per seed") {
  std::vector<uint8_t> labels;
  const int counts[4] = {700, 200, 90, 10};
  for (int c = 0; c < 4; ++c) labels.insert(labels.end(), counts[c], static_cast<uint8_t>(c));
  std::vector<uint32_t> out(64), out2(64), scratch(labels.size());
  const uint32_t n = sparsify_semantic(labels.data(), 1000, 48, 5, out.data(), scratch.data());
  REQUIRE(n == 48);
  int got[4] = {};
  for (uint32_t i = 0; i < n; ++i) got[labels[out[i]]]++;
  for (int c = 0; c < 4; ++c) CHECK(std::fabs(got[c] - counts[c] * 48.0 / 1000.0) < 1.0);
  for (uint32_t i = 1; i < n; ++i) CHECK(out[i - 1] < out[i]);
  sparsify_semantic(labels.data(), 1000, 48, 5, out2.data(), scratch.data());
  CHECK(std::equal(out.begin(), out.begin() + 48, out2.begin()));
  sparsify_semantic(labels.data(), 1000, 48, 6, out2.data(), scratch.data());
  CHECK_FALSE(std::equal(out.begin(), out.begin() + 48, out2.begin()));
  CHECK(sparsify_semantic(labels.data(), 30, 48, 5, out.data(), scratch.data()) == 30);
}

TEST_CASE("W2: zero for identical, symmetric, 1-D and diagonal closed forms, triangle inequality") {
  Buffer buf(W2Exact::required_bytes(16) + 64);
  W2Exact exact;
  REQUIRE(exact.bind(buf.arena, 16) == Status::Ok);
  float w[kNumClasses];
  for (float& x : w) x = 1.0f;
  w[0] = 1.0f;
  std::mt19937 rng(9);
  std::normal_distribution<float> nd(0, 1);
  auto random_psd = [&](int g, std::vector<float>& s) {
    std::vector<float> a(g * g);
    for (auto& x : a) x = nd(rng);
    s.assign(g * g, 0);
    for (int i = 0; i < g; ++i)
      for (int j = 0; j < g; ++j)
        for (int k = 0; k < g; ++k) s[i * g + j] += a[i * g + k] * a[j * g + k] / g;
    for (int i = 0; i < g; ++i) s[i * g + i] += 0.05f;
  };
  const int g = 6;
  std::vector<float> m1(g * kNumClasses), m2(g * kNumClasses), m3(g * kNumClasses), s1, s2, s3;
  for (auto* m : {&m1, &m2, &m3})
    for (auto& x : *m) x = nd(rng);
  random_psd(g, s1);
  random_psd(g, s2);
  random_psd(g, s3);
  double d11, d12, d21, d13, d23;
  REQUIRE(exact.w2_squared(m1.data(), s1.data(), m1.data(), s1.data(), g, w, &d11) == Status::Ok);
  CHECK(d11 == Approx(0.0).margin(1e-3));
  exact.w2_squared(m1.data(), s1.data(), m2.data(), s2.data(), g, w, &d12);
  exact.w2_squared(m2.data(), s2.data(), m1.data(), s1.data(), g, w, &d21);
  CHECK(d12 == Approx(d21).epsilon(1e-4));
  exact.w2_squared(m1.data(), s1.data(), m3.data(), s3.data(), g, w, &d13);
  exact.w2_squared(m2.data(), s2.data(), m3.data(), s3.data(), g, w, &d23);
  CHECK(std::sqrt(d13) <= std::sqrt(d12) + std::sqrt(d23) + 1e-6);
  // 1-D Gaussians (g = 1, one class weighted): |m1-m2|^2 + tr(W)(s1-s2)^2.
  float one_w[kNumClasses] = {};
  one_w[0] = 1.0f;
  float a_mean[kNumClasses] = {2.0f}, b_mean[kNumClasses] = {-1.0f};
  const float va = 4.0f, vb = 0.25f;
  double d;
  REQUIRE(exact.w2_squared(a_mean, &va, b_mean, &vb, 1, one_w, &d) == Status::Ok);
  CHECK(d == Approx(9.0 + (2.0 - 0.5) * (2.0 - 0.5)).epsilon(1e-5));
  // Diagonal covariances: the diagonal path is exact.
  std::vector<float> dg1(g * g, 0), dg2(g * g, 0), v1(g), v2(g);
  for (int i = 0; i < g; ++i) {
    dg1[i * g + i] = v1[i] = 0.1f + i;
    dg2[i * g + i] = v2[i] = 2.0f / (1 + i);
  }
  exact.w2_squared(m1.data(), dg1.data(), m2.data(), dg2.data(), g, w, &d);
  CHECK(d == Approx(w2_squared_diag(m1.data(), v1.data(), m2.data(), v2.data(), g, w)).epsilon(1e-4));
  // The observed-only path with everything observed and covariance weight 1 equals the diagonal path.
  const ObservedW2 ob = w2_squared_diag_observed(m1.data(), v1.data(), m2.data(), v2.data(), g, w, 1e9f, 1.0f);
  CHECK(ob.used == static_cast<uint32_t>(g));
  CHECK(ob.w2 == Approx(w2_squared_diag(m1.data(), v1.data(), m2.data(), v2.data(), g, w)).epsilon(1e-6));
  // Stability weights scale the classes: a difference only in a volatile class (0.1) costs 10x less.
  std::vector<float> w_stab(kNumClasses);
  stability_weights(w_stab.data());
  std::vector<float> base(kNumClasses, 0), car(kNumClasses, 0), pole(kNumClasses, 0);
  car[kTruck] = 1.0f;
  pole[kPole] = 1.0f;
  CHECK(w2_mean_term(base.data(), car.data(), 1, w_stab.data()) * 10 ==
        Approx(w2_mean_term(base.data(), pole.data(), 1, w_stab.data())));
}

TEST_CASE("The observed W2 sums in its documented order: the scalar lanes' bits, near the double sum") {
  // wasserstein.cpp: lane k adds classes k and k + 8 of every compared point, the tail lanes classes
  // 16-18, and the lanes meet in a fixed tree. Written out here in plain scalars, the vectorised
  // function (AVX2, SSE2 or NEON, whichever this build runs) must give the same bits; and it stays
  // within float rounding of the double sum (w2_mean_term over the same points).
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const uint32_t g = 36;
  std::vector<float> mq(g * kNumClasses), mm(g * kNumClasses), vq(g), vm(g), w(kNumClasses);
  for (auto& x : mq) x = u(rng);
  for (auto& x : mm) x = u(rng);
  for (auto& x : vm) x = u(rng);
  for (auto& x : w) x = 0.1f + u(rng);
  for (uint32_t s = 0; s < g; ++s) vq[s] = s % 5 == 0 ? 0.9f : 0.3f * u(rng);  // every 5th point unobserved
  const float max_var = 0.6f;
  float lane[8] = {}, tail[kNumClasses - 16] = {};
  uint32_t used = 0;
  std::vector<float> oq, om;  // the compared points, for the double reference
  for (uint32_t s = 0; s < g; ++s) {
    if (!(vq[s] <= max_var)) continue;
    const float* a = &mq[s * kNumClasses];
    const float* b = &mm[s * kNumClasses];
    for (int k = 0; k < 8; ++k) {
      const float x0 = a[k] - b[k], x1 = a[k + 8] - b[k + 8];
      lane[k] = lane[k] + w[k] * (x0 * x0);
      lane[k] = lane[k] + w[k + 8] * (x1 * x1);
    }
    for (int k = 0; k < kNumClasses - 16; ++k) {
      const float x = a[k + 16] - b[k + 16];
      tail[k] = tail[k] + w[k + 16] * (x * x);
    }
    oq.insert(oq.end(), a, a + kNumClasses);
    om.insert(om.end(), b, b + kNumClasses);
    ++used;
  }
  float t = 0.0f;
  for (float x : tail) t = t + x;
  const float expected =
      (((lane[0] + lane[4]) + (lane[2] + lane[6])) + ((lane[1] + lane[5]) + (lane[3] + lane[7]))) + t;
  const ObservedW2 r = w2_squared_diag_observed(mq.data(), vq.data(), mm.data(), vm.data(), g, w.data(), max_var, 0.0f);
  REQUIRE(r.used == used);
  REQUIRE(used == 28);
  CHECK(r.w2 == double(expected));  // bit for bit
  CHECK(r.w2 == Approx(w2_mean_term(oq.data(), om.data(), used, w.data())).epsilon(1e-6));
  // The covariance term adds on top in double, where asked for.
  const ObservedW2 c = w2_squared_diag_observed(mq.data(), vq.data(), mm.data(), vm.data(), g, w.data(), max_var, 1.0f);
  CHECK(c.w2 > r.w2);
}

TEST_CASE("W2 between fields is invariant when data and grid move rigidly together") {
  FieldConfig fc;  // bird's-eye
  Buffer buf(FieldSolver::required_bytes(fc, 200) + 2 * W2Exact::required_bytes(kMaxGridPoints) + 64);
  FieldSolver solver;
  REQUIRE(solver.bind(buf.arena, fc, 200) == Status::Ok);
  W2Exact exact;
  REQUIRE(exact.bind(buf.arena, kMaxGridPoints) == Status::Ok);
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> u(-7, 7);
  const int n = 150;
  std::vector<float> xa(n * 3), xb(n * 3), ya(n * kNumClasses, 0), yb(n * kNumClasses, 0);
  std::vector<uint8_t> la(n), lb(n);
  for (int i = 0; i < n; ++i) {
    xa[3 * i] = u(rng);
    xa[3 * i + 1] = u(rng);
    xa[3 * i + 2] = 0;
    xb[3 * i] = u(rng);
    xb[3 * i + 1] = u(rng);
    xb[3 * i + 2] = 0;
    la[i] = xa[3 * i] > 0 ? kVegetation : kRoad;
    lb[i] = xb[3 * i + 1] > 1 ? kTerrain : kRoad;
    ya[i * kNumClasses + la[i]] = 1;
    yb[i * kNumClasses + lb[i]] = 1;
  }
  auto w2_between = [&](float yaw) {
    const float c = std::cos(yaw), s = std::sin(yaw);
    std::vector<float> ra(xa), rb(xb);
    for (int i = 0; i < n; ++i) {
      ra[3 * i] = c * xa[3 * i] - s * xa[3 * i + 1];
      ra[3 * i + 1] = s * xa[3 * i] + c * xa[3 * i + 1];
      rb[3 * i] = c * xb[3 * i] - s * xb[3 * i + 1];
      rb[3 * i + 1] = s * xb[3 * i] + c * xb[3 * i + 1];
    }
    const uint32_t G = grid_points(fc);
    std::vector<float> grid(G * 3), in(kMaxInducing * 3), al(kMaxInducing * kNumClasses),
        ch(kMaxInducing * kMaxInducing);
    std::vector<float> in2(in), al2(al), ch2(ch), m1(G * kNumClasses), m2(G * kNumClasses), v1(G), v2(G), c1(G * G),
        c2(G * G);
    make_probe_grid(fc, yaw, grid.data());
    uint32_t ma = 0, mb = 0;
    REQUIRE(solver.fit(ra.data(), ya.data(), la.data(), n, in.data(), al.data(), ch.data(), &ma) == Status::Ok);
    REQUIRE(solver.probe(FieldView{in.data(), al.data(), ma}, ch.data(), grid.data(), G, m1.data(), v1.data(),
                         c1.data()) == Status::Ok);
    REQUIRE(solver.fit(rb.data(), yb.data(), lb.data(), n, in2.data(), al2.data(), ch2.data(), &mb) == Status::Ok);
    REQUIRE(solver.probe(FieldView{in2.data(), al2.data(), mb}, ch2.data(), grid.data(), G, m2.data(), v2.data(),
                         c2.data()) == Status::Ok);
    float w[kNumClasses];
    stability_weights(w);
    double d = 0;
    REQUIRE(exact.w2_squared(m1.data(), c1.data(), m2.data(), c2.data(), G, w, &d) == Status::Ok);
    return d;
  };
  const double d0 = w2_between(0.0f);
  CHECK(d0 > 1.0);
  CHECK(w2_between(0.7f) == Approx(d0).epsilon(1e-3));
  CHECK(w2_between(-2.1f) == Approx(d0).epsilon(1e-3));
}

}  // namespace test_gaussian_field
