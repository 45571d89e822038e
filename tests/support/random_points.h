// Test helper: random instance positions and a rigid pose with yaw, a little roll and a large
// translation (the triangle, index and back-end tests).
#pragma once
#include <cstdint>
#include <random>
#include <vector>

#include <Eigen/Geometry>

namespace gsf_test {

inline std::vector<float> random_points(int n, uint32_t seed, float extent = 40.0f) {
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

inline Eigen::Isometry3d some_pose() {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = (Eigen::AngleAxisd(1.1, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  t.translation() = Eigen::Vector3d(120.0, -35.0, 2.0);
  return t;
}

}  // namespace gsf_test
