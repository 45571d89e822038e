// Drives over a simulated world and the whole dataset generation (`gsf simulate`).
//   sequence "00": the mapping drive over every road, in the original world;
//   sequence "01": the localization drive, other lanes and the opposite direction, in the world after
//                  the time gap (cars moved/removed, vegetation changed).
// Output is the SemanticKITTI layout (port/semantic_kitti.h) plus meta.json (seed, parameters, road
// length, and per query frame whether it lies in the repetitive zone). Same config -> identical bytes.
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "gsf/status.h"
#include "sim/lidar.h"
#include "sim/world.h"

namespace gsf::sim {

struct SimConfig {
  WorldParams world;
  LidarParams lidar;
  TimeGapParams time_gap;
  float map_spacing = 10.0f;     // m between mapping scans
  float query_spacing = 25.0f;   // m between query scans (half of it inside the repetitive zone)
  float sensor_height = 1.73f;
  float pose_noise_xy = 0.5f;    // m, lateral jitter of query poses
  float pose_noise_yaw_deg = 3.0f;
  float pose_noise_tilt_deg = 0.5f;
  static SimConfig demo();  // a few km of road, hundreds of map scans, 100+ queries
  static SimConfig tiny();  // seconds to generate, for tests
};

struct Drive {
  std::vector<Eigen::Isometry3d> poses;  // world_T_lidar
  std::vector<bool> in_zone;
};

Drive mapping_drive(const World& world, const SimConfig& config);
Drive query_drive(const World& world, const SimConfig& config);
uint64_t scan_seed(uint64_t seed, int sequence, uint32_t frame);

using SimProgress = std::function<void(const char* stage, uint32_t done, uint32_t total)>;

struct SimSummary {
  float road_length_m = 0;
  uint32_t map_scans = 0, queries = 0, zone_queries = 0;
  uint64_t points = 0;
};

// Generates the dataset under `root` (sequences/00, sequences/01, meta.json).
Status run_simulation(const SimConfig& config, const std::string& root, SimSummary* summary,
                      const SimProgress& progress = nullptr);

}  // namespace gsf::sim
