// The Scan Context peer baseline: rotation recovery by column shift, and retrieval of the right place.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <vector>

#include "baselines/scan_context.h"

namespace test_scan_context {

using gsf::bench::ScanContextConfig;

namespace {

// A "place": random boxes of random heights around the sensor, sampled as points.
std::vector<float> make_place(uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> pos(-60.0f, 60.0f), size(1.0f, 6.0f), height(0.5f, 12.0f), u(0.0f, 1.0f);
  std::vector<float> pts;
  for (int b = 0; b < 40; ++b) {
    const float cx = pos(rng), cy = pos(rng), sx = size(rng), sy = size(rng), h = height(rng);
    for (int k = 0; k < 200; ++k) {
      pts.insert(pts.end(), {cx + (u(rng) - 0.5f) * sx, cy + (u(rng) - 0.5f) * sy, u(rng) * h - 1.8f, 0.0f});
    }
  }
  return pts;
}

std::vector<float> rotate_z(const std::vector<float>& pts, double yaw) {
  std::vector<float> out(pts);
  const float c = static_cast<float>(std::cos(yaw)), s = static_cast<float>(std::sin(yaw));
  for (size_t i = 0; i < pts.size(); i += 4) {
    out[i] = c * pts[i] - s * pts[i + 1];
    out[i + 1] = s * pts[i] + c * pts[i + 1];
  }
  return out;
}

}  // namespace

TEST_CASE("Scan Context: a rotated scan is the same place, and the pose carries the yaw") {
  ScanContextConfig cfg;
  gsf::bench::ScanContextDatabase db(cfg);
  for (uint32_t p = 0; p < 8; ++p) {
    auto pts = make_place(100 + p);
    Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
    pose.translation() = Eigen::Vector3d(100.0 * p, 0, 0);
    db.add(gsf::bench::make_scan_context(cfg, pts.data(), 4, static_cast<uint32_t>(pts.size() / 4)), pose);
  }
  // The sensor turned by +42 deg (7 sectors): the same world appears rotated by -42 deg in its frame.
  const double yaw = 42.0 * M_PI / 180.0;
  auto base = make_place(103);
  auto seen = rotate_z(base, -yaw);
  auto q = gsf::bench::make_scan_context(cfg, seen.data(), 4, static_cast<uint32_t>(seen.size() / 4));
  auto m = db.query(q);
  REQUIRE(m.found);
  CHECK(m.index == 3);
  CHECK(m.distance < 0.05f);
  CHECK(m.second_distance > m.distance);
  const Eigen::Matrix3d R = m.pose.rotation();
  const double est_yaw = std::atan2(R(1, 0), R(0, 0));
  CHECK(std::abs(est_yaw - yaw) < 6.1 * M_PI / 180.0);  // within one sector
  CHECK((m.pose.translation() - Eigen::Vector3d(300, 0, 0)).norm() < 1e-9);
}

TEST_CASE("Scan Context: distance is zero to itself and NaN points are ignored") {
  ScanContextConfig cfg;
  auto pts = make_place(7);
  auto a = gsf::bench::make_scan_context(cfg, pts.data(), 4, static_cast<uint32_t>(pts.size() / 4));
  pts[0] = std::nanf("");
  auto b = gsf::bench::make_scan_context(cfg, pts.data(), 4, static_cast<uint32_t>(pts.size() / 4));
  int shift = -1;
  CHECK(gsf::bench::scan_context_distance(cfg, a, a, &shift) == Approx(0.0f).margin(1e-6));
  CHECK(shift == 0);
  CHECK(gsf::bench::scan_context_distance(cfg, a, b, &shift) < 0.01f);
  auto other = make_place(8);
  auto c = gsf::bench::make_scan_context(cfg, other.data(), 4, static_cast<uint32_t>(other.size() / 4));
  CHECK(gsf::bench::scan_context_distance(cfg, a, c, nullptr) > 0.1f);
}

}  // namespace test_scan_context
