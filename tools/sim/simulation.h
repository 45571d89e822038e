// Drives over a simulated world and the whole dataset generation (`gsf simulate`).
//   sequence "00": the mapping drive over every road, in the original world;
//   sequence "01": the localization drive, other lanes and the opposite direction, in the world after
//                  the time gap (cars moved/removed, vegetation changed).
// Output is the SemanticKITTI layout (port/semantic_kitti.h) plus meta.json (seed, parameters, road
// length, zone type and cue density, and per query frame whether it lies in the repetitive zone or near
// it). Same config -> identical bytes.
#pragma once
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "gsf/status.h"
#include "label_errors/label_errors.h"
#include "sim/lidar.h"
#include "sim/world.h"

namespace gsf::sim {

struct SimConfig {
  WorldParams world;
  LidarParams lidar;
  TimeGapParams time_gap;
  float map_spacing = 10.0f;    // m between mapping scans
  float query_spacing = 25.0f;  // m between query scans (half of it inside the repetitive zone)
  float sensor_height = 1.73f;
  float pose_noise_xy = 0.5f;  // m, lateral jitter of query poses
  float pose_noise_yaw_deg = 3.0f;
  float pose_noise_tilt_deg = 0.5f;
  // Query spacing inside the zone; 0 = the zone's default (row: query_spacing / 2, lattice 6 m, hall 7 m,
  // avenue 6 m). The approach road of a lattice / hall gets near_query_spacing (0 = query_spacing).
  float zone_query_spacing = 0.0f;
  float near_query_spacing = 0.0f;
  // Beams of the mapping drive's LiDAR (sequence 00); 0 = lidar.beams, which is always the query drive's.
  // Cross-sensor: a map from a dense 64/128-beam car queried by a 16/32-beam one. Only the beam count
  // differs: the same elevation range, azimuth step, range and noise (drive_lidar).
  int map_beams = 0;
  // Share of the world the map covers: the mapping drive keeps only its poses in the western
  // map_coverage of its x extent (the query drive is unchanged), so queries beyond are off the map and
  // queries at its edge see it partly, as a vehicle does at the edge of its mapped area. 1 = all.
  float map_coverage = 1.0f;
  // 10 Hz stretches (sequence "02", for tracking and several-scan localization): `stretches` runs of
  // `stretch_scans` consecutive scans 0.5-1.5 m apart (5-15 m/s at 10 Hz), each along the query lane of
  // one road segment, segments chosen evenly over the query drive's, in the world after the time gap.
  // meta.json lists each stretch's first scan and length. 0 = no sequence 02.
  uint32_t stretches = 0;
  uint32_t stretch_scans = 20;
  // Sensing: share of points whose written label is confused with a plausible other class (a network's
  // mistakes), and whether labels keep the instance id in their high 16 bits.
  float label_noise = 0.0f;
  bool instance_ids = true;
  // Correlated segmentation errors (issue 24), drawn per scan for both drives, before label_noise:
  // share of instances relabelled whole, per scan, to one partner class (a pole called a trunk).
  float object_confusion = 0.0f;
  // Thin things missed with range: P of the points of poles, signs and trunks beyond kThinMissFar
  // (linearly from kThinMissNear) take the class behind them (apply_thin_miss).
  float thin_miss = 0.0f;
  // Spurious thin objects (apply_spurious_objects): p x the scan's instances, patches of wall or hedge
  // labelled pole or trunk, drawn per scan.
  float spurious_objects = 0.0f;
  // Label set of the written scans: false = SemanticKITTI (labels/, uint32); true = nuScenes-lidarseg
  // (lidarseg/, uint8, kitti_to_nuscenes): poles, signs, fences and trunks lose their classes inside
  // static.manmade / static.vegetation, as in real nuScenes data.
  bool nuscenes_labels = false;
  // Added to every written pose's translation (in double): the same world and the same scans posed in
  // another frame, e.g. UTM metres as a GNSS/INS-posed drive would be. meta.json records it.
  double pose_offset[3] = {0.0, 0.0, 0.0};
  static SimConfig demo();  // a few km of road, hundreds of map scans, 100+ queries
  static SimConfig tiny();  // seconds to generate, for tests
  // bench/suite.sh: a 2 x 2-block city plus the zone, cue density 0.5, ~100-150 queries, ~40 in the zone.
  // The zone's size varies with the seed (lattice 6..14 x 4..10 columns 7..9 m apart, hall 8..14 x 3..6
  // pillars, row / avenue period) so that some zones are larger than the LiDAR's view; the time gap's
  // seed follows the world seed.
  static SimConfig suite(ZoneType zone, uint64_t seed = 1);
  // ctest end-to-end: a 4 x 3 lattice and a one-block city, <= 40 map scans, ~15 queries, half in the zone.
  static SimConfig tiny_lattice();
};

float zone_query_spacing(const World& world, const SimConfig& config);
// The LiDAR of drive `sequence` (0 mapping, 1 queries): config.lidar with map_beams for the mapping drive.
LidarParams drive_lidar(const SimConfig& config, int sequence);

struct Drive {
  std::vector<Eigen::Isometry3d> poses;  // world_T_lidar
  std::vector<bool> in_zone;
  std::vector<bool> near_zone;  // within kNearZone m of the zone, not inside
};

Drive mapping_drive(const World& world, const SimConfig& config);
Drive query_drive(const World& world, const SimConfig& config);
// The stretches of SimConfig::stretches (empty when 0); starts[i] is stretch i's first pose.
Drive stretch_drive(const World& world, const SimConfig& config, std::vector<uint32_t>* starts);
uint64_t scan_seed(uint64_t seed, int sequence, uint32_t frame);

// The label-error families (object confusion, thin misses, label noise on SemanticKITTI ids) live in
// tools/label_errors, shared with the CLI's real-data runs; the simulator applies them as it writes.
using label_errors::apply_label_noise;
using label_errors::apply_object_confusion;
using label_errors::apply_spurious_objects;
using label_errors::apply_thin_miss;
using label_errors::kThinMissFar;
using label_errors::kThinMissNear;
using label_errors::label_partner;
using label_errors::label_partner_count;
using label_errors::thin_miss_probability;
void strip_instance_ids(uint32_t* labels, uint32_t count);

using SimProgress = std::function<void(const char* stage, uint32_t done, uint32_t total)>;

struct SimSummary {
  float road_length_m = 0;
  uint32_t map_scans = 0, queries = 0, zone_queries = 0, near_zone_queries = 0;
  uint32_t stretch_scans = 0;  // sequence 02 (SimConfig::stretches)
  uint32_t zone_instances = 0, cued_instances = 0;
  uint64_t points = 0;
};

// Generates the dataset under `root` (sequences/00, sequences/01, meta.json).
Status run_simulation(const SimConfig& config, const std::string& root, SimSummary* summary,
                      const SimProgress& progress = nullptr);

}  // namespace gsf::sim
