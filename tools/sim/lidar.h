// Spinning multi-beam LiDAR, ray-cast against a World. Rays march through a 2-D uniform grid of
// primitive lists (DDA), so a scan costs O(rays x cells crossed), not O(rays x primitives).
#pragma once
#include <cstdint>
#include <vector>

#include <Eigen/Geometry>

#include "sim/world.h"

namespace gsf::sim {

struct LidarParams {
  int beams = 32;
  float elevation_min_deg = -25.0f;
  float elevation_max_deg = 10.0f;
  float azimuth_step_deg = 0.4f;
  float max_range = 80.0f;
  float min_range = 1.0f;
  float range_noise = 0.02f;  // m, Gaussian sigma
  float dropout = 0.02f;      // probability a return is lost
};

struct SimScan {
  std::vector<float> xyzi;       // sensor frame, 4 floats per point
  std::vector<uint32_t> labels;  // semantic | instance << 16
  uint32_t size() const { return static_cast<uint32_t>(labels.size()); }
};

class Raycaster {
 public:
  explicit Raycaster(const World& world, float cell = 4.0f);
  // Nearest hit along origin + t dir (|dir| = 1) within max_t; returns t (or < 0) and the label word.
  float cast(const Eigen::Vector3f& origin, const Eigen::Vector3f& dir, float max_t, uint32_t* label) const;
  void scan(const Eigen::Isometry3d& world_T_lidar, const LidarParams& lidar, uint64_t seed, SimScan* out) const;

 private:
  const World& world_;
  float cell_;
  int nx_, ny_;
  float ox_, oy_;
  std::vector<uint32_t> cell_start_;  // CSR over cells
  std::vector<uint32_t> cell_prims_;
};

}  // namespace gsf::sim
