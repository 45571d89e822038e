// The pose solver alone (core/include/gsf/detail/pose_solver.h): weighted Kabsch, the upright fit and
// the truncated least squares, against known motions (exact where the inputs are exact in float), their
// closed forms (a zero weight is a missing row, z from the weighted means, the truncated cost), their
// invariances (row order, weight scale, a change of the query frame) and their refusals.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <vector>

#include "gsf/detail/pose_solver.h"
#include "random_points.h"

namespace test_pose_solver {

using namespace gsf;
using gsf_test::random_points;
using gsf_test::some_pose;

namespace {

// b = T a for every row (as floats).
std::vector<float> moved(const std::vector<float>& a, const Eigen::Isometry3d& T) {
  std::vector<float> b(a.size());
  for (size_t i = 0; i < a.size() / 3; ++i) {
    const Eigen::Vector3d q = T * Eigen::Vector3d(a[3 * i], a[3 * i + 1], a[3 * i + 2]);
    for (int k = 0; k < 3; ++k) b[3 * i + k] = static_cast<float>(q[k]);
  }
  return b;
}

double angle_between(const Eigen::Isometry3d& x, const Eigen::Isometry3d& y) {
  return Eigen::AngleAxisd(x.rotation().transpose() * y.rotation()).angle();
}

// A quarter turn about z and a whole-metre translation: b = T a is exact in float for integer a.
Eigen::Isometry3d quarter_turn() {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() << 0, -1, 0, 1, 0, 0, 0, 0, 1;
  T.translation() = Eigen::Vector3d(10, -3, 2);
  return T;
}

}  // namespace

TEST_CASE("Kabsch recovers a known motion: exactly from exact input, within float rounding otherwise") {
  const std::vector<float> a = {0, 0, 0, 4, 0, 1, 0, 3, 2, -2, 5, 0, 7, -1, 3};
  const Eigen::Isometry3d Q = quarter_turn();
  Eigen::Isometry3d est;
  REQUIRE(kabsch(a.data(), moved(a, Q).data(), nullptr, 5, &est) == Status::Ok);
  CHECK((est.matrix() - Q.matrix()).cwiseAbs().maxCoeff() < 1e-12);
  CHECK(est.linear().determinant() == Approx(1.0).margin(1e-12));
  const std::vector<float> p = random_points(50, 21);
  const Eigen::Isometry3d T = some_pose();
  REQUIRE(kabsch(p.data(), moved(p, T).data(), nullptr, 50, &est) == Status::Ok);
  CHECK((est.translation() - T.translation()).norm() < 1e-4);
  CHECK(angle_between(est, T) < 1e-6);
}

TEST_CASE("Weighted Kabsch: a zero weight is a missing row, weights' scale and the rows' order do not matter") {
  const std::vector<float> a = random_points(30, 22);
  const Eigen::Isometry3d T = some_pose();
  std::vector<float> b = moved(a, T);
  std::mt19937 rng(23);
  std::uniform_real_distribution<float> junk(-80, 80), w01(0.2f, 2.0f);
  for (int i = 20; i < 30; ++i)
    for (int k = 0; k < 3; ++k) b[3 * i + k] = junk(rng);  // rows 20-29: outliers
  std::vector<float> w(30);
  for (float& x : w) x = w01(rng);
  // Weight 0 on the outliers = Kabsch on rows 0-19 alone with their weights.
  std::vector<float> w0 = w;
  std::fill(w0.begin() + 20, w0.end(), 0.0f);
  Eigen::Isometry3d with_zero, subset;
  REQUIRE(kabsch(a.data(), b.data(), w0.data(), 30, &with_zero) == Status::Ok);
  REQUIRE(kabsch(a.data(), b.data(), w.data(), 20, &subset) == Status::Ok);
  CHECK((with_zero.matrix() - subset.matrix()).cwiseAbs().maxCoeff() < 1e-9);
  CHECK((with_zero.translation() - T.translation()).norm() < 1e-4);
  // Every weight times 8 (a power of two: exact): the same pose, bit for bit.
  std::vector<float> w8 = w;
  for (float& x : w8) x *= 8.0f;
  Eigen::Isometry3d all, all8;
  REQUIRE(kabsch(a.data(), b.data(), w.data(), 30, &all) == Status::Ok);
  REQUIRE(kabsch(a.data(), b.data(), w8.data(), 30, &all8) == Status::Ok);
  CHECK((all.matrix() - all8.matrix()).cwiseAbs().maxCoeff() < 1e-12);
  // The rows reversed: the same pose up to the sums' rounding.
  std::vector<float> ra(a.size()), rb(b.size()), rw(w.size());
  for (int i = 0; i < 30; ++i) {
    for (int k = 0; k < 3; ++k) {
      ra[3 * (29 - i) + k] = a[3 * i + k];
      rb[3 * (29 - i) + k] = b[3 * i + k];
    }
    rw[29 - i] = w[i];
  }
  Eigen::Isometry3d reversed;
  REQUIRE(kabsch(ra.data(), rb.data(), rw.data(), 30, &reversed) == Status::Ok);
  CHECK((all.matrix() - reversed.matrix()).cwiseAbs().maxCoeff() < 1e-9);
}

TEST_CASE("Kabsch returns a rotation, never a reflection, and refuses degenerate input") {
  // b is a's mirror image (x -> -x): the best proper rotation, determinant +1.
  const std::vector<float> a = random_points(20, 24);
  std::vector<float> b = a;
  for (int i = 0; i < 20; ++i) b[3 * i] = -b[3 * i];
  Eigen::Isometry3d est;
  REQUIRE(kabsch(a.data(), b.data(), nullptr, 20, &est) == Status::Ok);
  CHECK(est.linear().determinant() == Approx(1.0).margin(1e-9));
  CHECK((est.linear() * est.linear().transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-9);
  // Refusals: fewer than 3 rows, collinear rows, a negative or NaN weight, a NaN point, no weight at all.
  const float line[9] = {0, 0, 0, 1, 1, 1, 2, 2, 2};
  CHECK(kabsch(a.data(), b.data(), nullptr, 2, &est) == Status::InvalidInput);
  CHECK(kabsch(line, line, nullptr, 3, &est) == Status::InvalidInput);
  const float neg[3] = {1, -1, 1}, nan_w[3] = {1, NAN, 1}, zero[3] = {0, 0, 0};
  CHECK(kabsch(a.data(), b.data(), neg, 3, &est) == Status::InvalidInput);
  CHECK(kabsch(a.data(), b.data(), nan_w, 3, &est) == Status::InvalidInput);
  CHECK(kabsch(a.data(), b.data(), zero, 3, &est) == Status::InvalidInput);
  std::vector<float> nan_b = b;
  nan_b[4] = NAN;
  CHECK(kabsch(a.data(), nan_b.data(), nullptr, 20, &est) == Status::InvalidInput);
}

TEST_CASE("fit_upright: the yaw in closed form, z from the weighted means, masked rows left out") {
  const std::vector<float> a = {0, 0, 0, 4, 0, 1, 0, 3, 2, -2, 5, 0, 7, -1, 3, 1, 1, 1};
  const Eigen::Isometry3d Q = quarter_turn();
  std::vector<float> b = moved(a, Q);
  Eigen::Isometry3d est;
  REQUIRE(fit_upright(a.data(), b.data(), nullptr, nullptr, 6, &est) == Status::Ok);
  CHECK((est.matrix() - Q.matrix()).cwiseAbs().maxCoeff() < 1e-12);
  // A tilted motion: the fit stays upright (rotation about z only).
  const std::vector<float> p = random_points(40, 25);
  const Eigen::Isometry3d T = some_pose();  // yaw 1.1 rad and a 0.05 rad roll
  REQUIRE(fit_upright(p.data(), moved(p, T).data(), nullptr, nullptr, 40, &est) == Status::Ok);
  CHECK(est.linear()(2, 2) == 1.0);
  CHECK(est.linear()(0, 2) == 0.0);
  CHECK(std::atan2(est.linear()(1, 0), est.linear()(0, 0)) == Approx(1.1).margin(0.01));
  // Heights off by a different amount per row: t_z is the weighted mean of b_z - a_z (x, y exact).
  std::vector<float> bz = b;
  const float dz[6] = {0.5f, -1.0f, 2.0f, 0.0f, 1.5f, -0.5f}, w[6] = {1, 2, 1, 4, 1, 1};
  double num = 0.0, den = 0.0;
  for (int i = 0; i < 6; ++i) {
    bz[3 * i + 2] += dz[i];
    num += w[i] * dz[i];
    den += w[i];
  }
  REQUIRE(fit_upright(a.data(), bz.data(), w, nullptr, 6, &est) == Status::Ok);
  CHECK(est.translation().z() == Approx(Q.translation().z() + num / den).margin(1e-9));
  CHECK(est.translation().x() == Approx(10.0).margin(1e-9));
  CHECK(std::atan2(est.linear()(1, 0), est.linear()(0, 0)) == Approx(M_PI / 2).margin(1e-12));
  // Masked rows are left out: garbage in them changes nothing.
  std::vector<float> junk = b;
  for (int k = 0; k < 3; ++k) junk[3 * 5 + k] = 1000.0f;
  const uint8_t mask[6] = {1, 1, 1, 1, 1, 0};
  Eigen::Isometry3d masked, five;
  REQUIRE(fit_upright(a.data(), junk.data(), nullptr, mask, 6, &masked) == Status::Ok);
  REQUIRE(fit_upright(a.data(), b.data(), nullptr, nullptr, 5, &five) == Status::Ok);
  CHECK((masked.matrix() - five.matrix()).cwiseAbs().maxCoeff() < 1e-12);
  CHECK((masked.matrix() - Q.matrix()).cwiseAbs().maxCoeff() < 1e-12);
  // Refusals: fewer than 2 rows left, no positive weight, no horizontal spread.
  const uint8_t one[6] = {1, 0, 0, 0, 0, 0};
  CHECK(fit_upright(a.data(), b.data(), nullptr, one, 6, &est) == Status::InvalidInput);
  const float zero[6] = {0, 0, 0, 0, 0, 0};
  CHECK(fit_upright(a.data(), b.data(), zero, nullptr, 6, &est) == Status::InvalidInput);
  const float stack[9] = {1, 2, 0, 1, 2, 1, 1, 2, 2};  // one vertical column: yaw undetermined
  CHECK(fit_upright(stack, stack, nullptr, nullptr, 3, &est) == Status::InvalidInput);
}

TEST_CASE("TLS: the inliers' motion, the truncated cost in closed form, the inlier mask, a query frame change") {
  // 12 exact inliers of a quarter turn and 8 outliers far from it (each residual > 10 m).
  std::vector<float> a, b;
  const Eigen::Isometry3d Q = quarter_turn();
  for (int i = 0; i < 20; ++i) {
    const float x = float((i * 7) % 11) - 5.0f, y = float((i * 5) % 13) - 6.0f, z = float(i % 3);
    a.insert(a.end(), {x, y, z});
    const Eigen::Vector3d q = Q * Eigen::Vector3d(x, y, z);
    const float off = i < 12 ? 0.0f : 15.0f + float(i);
    b.insert(b.end(), {float(q.x()) + off, float(q.y()) - off, float(q.z())});
  }
  std::vector<float> w(20, 1.0f), scratch(20);
  for (int i = 12; i < 20; ++i) w[i] = 0.5f + 0.25f * float(i - 12);
  std::vector<uint8_t> mask(20);
  const double c = 1.5;
  TlsResult r;
  REQUIRE(solve_tls(a.data(), b.data(), w.data(), 20, c, 50, &r, mask.data(), scratch.data()) == Status::Ok);
  CHECK((r.b_T_a.matrix() - Q.matrix()).cwiseAbs().maxCoeff() < 1e-9);
  CHECK(r.inliers == 12);
  for (int i = 0; i < 20; ++i) CHECK(mask[i] == (i < 12 ? 1 : 0));
  // cost = sum w_i min(r_i^2, c^2): the inliers' residuals are 0, each outlier pays c^2 times its weight.
  const double outlier_weight = std::accumulate(w.begin() + 12, w.end(), 0.0);
  CHECK(r.cost == Approx(c * c * outlier_weight).epsilon(1e-9));
  CHECK(r.iterations <= 50);
  // The query frame moved by S (a' = S a): the motion becomes T S^-1.
  const Eigen::Isometry3d S = some_pose();
  const std::vector<float> a2 = moved(a, S);
  TlsResult r2;
  REQUIRE(solve_tls(a2.data(), b.data(), w.data(), 20, c, 50, &r2, nullptr, scratch.data()) == Status::Ok);
  const Eigen::Isometry3d expect = Q * S.inverse();
  CHECK((r2.b_T_a.translation() - expect.translation()).norm() < 1e-3);
  CHECK(angle_between(r2.b_T_a, expect) < 1e-5);
  CHECK(r2.inliers == 12);
  // A threshold must be positive; degenerate input is Kabsch's status.
  CHECK(solve_tls(a.data(), b.data(), w.data(), 20, 0.0, 50, &r, nullptr, scratch.data()) == Status::InvalidArgument);
  CHECK(solve_tls(a.data(), b.data(), w.data(), 2, c, 50, &r, nullptr, scratch.data()) == Status::InvalidInput);
}

TEST_CASE("TLS follows the weights: a heavier consistent group wins over a larger light one") {
  // Group A: 6 rows of motion QA, weight 1. Group B: 30 rows of motion QB, weight 0.1. Unweighted TLS takes
  // B (more rows), weighted takes A (weight 6 > 3).
  const Eigen::Isometry3d QA = quarter_turn();
  Eigen::Isometry3d QB = Eigen::Isometry3d::Identity();
  QB.translation() = Eigen::Vector3d(-40, 25, 0);
  std::vector<float> a, b, w;
  auto add = [&](float x, float y, float z, const Eigen::Isometry3d& T, float weight) {
    const Eigen::Vector3d q = T * Eigen::Vector3d(x, y, z);
    a.insert(a.end(), {x, y, z});
    b.insert(b.end(), {float(q.x()), float(q.y()), float(q.z())});
    w.push_back(weight);
  };
  for (int i = 0; i < 6; ++i) add(float(3 * i - 7), float((i * i) % 7) - 3.0f, float(i % 2), QA, 1.0f);
  for (int i = 0; i < 30; ++i) add(float((i * 7) % 31) - 15.0f, float(i) - 15.0f, float(i % 3), QB, 0.1f);
  std::vector<float> scratch(36);
  TlsResult weighted, plain;
  REQUIRE(solve_tls(a.data(), b.data(), w.data(), 36, 1.0, 50, &weighted, nullptr, scratch.data()) == Status::Ok);
  REQUIRE(solve_tls(a.data(), b.data(), nullptr, 36, 1.0, 50, &plain, nullptr, scratch.data()) == Status::Ok);
  CHECK((weighted.b_T_a.translation() - QA.translation()).norm() < 1e-6);
  CHECK(weighted.inliers == 6);
  CHECK((plain.b_T_a.translation() - QB.translation()).norm() < 1e-6);
  CHECK(plain.inliers == 30);
}

}  // namespace test_pose_solver
