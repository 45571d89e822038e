#include "sim/simulation.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "gsf/detail/bounded_hash_map.h"
#include "gsf/detail/rng.h"
#include "gsf/port/nuscenes.h"
#include "gsf/port/semantic_kitti.h"

namespace gsf::sim {
namespace {

Eigen::Isometry3d make_pose(float x, float y, float z, double yaw, double roll = 0, double pitch = 0) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  t.translation() = Eigen::Vector3d(x, y, z);
  return t;
}

}  // namespace

SimConfig SimConfig::demo() {
  SimConfig c;
  c.world.seed = 2024;
  c.world.blocks_x = 4;
  c.world.blocks_y = 3;
  c.world.block_size = 100.0f;
  c.world.zone_length = 300.0f;
  c.time_gap.seed = 7;
  return c;
}

SimConfig SimConfig::tiny() {
  SimConfig c;
  c.world.seed = 11;
  c.world.blocks_x = 2;
  c.world.blocks_y = 1;
  c.world.block_size = 80.0f;
  c.world.zone_length = 100.0f;
  c.world.zone_margin = 40.0f;
  c.lidar.beams = 24;
  c.lidar.azimuth_step_deg = 0.6f;
  c.lidar.max_range = 60.0f;
  c.map_spacing = 10.0f;
  c.query_spacing = 30.0f;
  c.time_gap.seed = 5;
  return c;
}

SimConfig SimConfig::suite(ZoneType zone, uint64_t seed) {
  SimConfig c;
  c.world.seed = seed;
  c.world.blocks_x = 2;
  c.world.blocks_y = 2;
  c.world.block_size = 100.0f;
  c.world.zone = zone;
  c.world.cue_density = 0.5f;
  c.world.zone_length = 240.0f;
  c.world.zone_margin = 60.0f;
  c.time_gap.seed = seed * 2654435761u + 7u;
  c.query_spacing = 20.0f;
  c.near_query_spacing = 10.0f;
  // Zone size by seed; the zone query spacing keeps about kZoneQueries queries in the zone.
  constexpr float kZoneQueries = 40.0f;
  gsf::Rng r(gsf::mix64(seed ^ 0x5017E5EEDULL));
  WorldParams& w = c.world;
  switch (zone) {
    case ZoneType::Row:
      w.zone_period = 8.0f + static_cast<float>(r.uniform(5));  // 8..12 m
      c.zone_query_spacing = w.zone_length / kZoneQueries;
      break;
    case ZoneType::Lattice: {
      w.lattice_nx = 6 + static_cast<int>(r.uniform(9));                   // 6..14
      w.lattice_ny = 4 + static_cast<int>(r.uniform(7));                   // 4..10
      w.lattice_spacing = 7.0f + 0.5f * static_cast<float>(r.uniform(5));  // 7..9 m
      const float s = w.lattice_spacing;  // query aisles: odd x-aisles (zone width), odd y-aisles (height)
      const float len = static_cast<float>((w.lattice_ny + 1) / 2) * (w.lattice_nx + 1) * s +
                        static_cast<float>((w.lattice_nx + 1) / 2) * (w.lattice_ny + 1) * s;
      c.zone_query_spacing = std::max(6.0f, len / kZoneQueries);
      break;
    }
    case ZoneType::Hall: {
      w.hall_nx = 8 + static_cast<int>(r.uniform(7));              // 8..14
      w.hall_ny = 3 + static_cast<int>(r.uniform(4));              // 3..6
      w.hall_dx = 9.0f + 0.5f * static_cast<float>(r.uniform(5));  // 9..11 m
      w.hall_dy = 7.0f + 0.5f * static_cast<float>(r.uniform(3));  // 7..8 m
      const float len = static_cast<float>((w.hall_ny + 1) / 2) * (w.hall_nx * w.hall_dx + 5.0f) +
                        static_cast<float>((w.hall_nx + 1) / 2) * (w.hall_ny * w.hall_dy + 4.0f);
      c.zone_query_spacing = std::max(6.0f, len / kZoneQueries);
      break;
    }
    case ZoneType::Avenue:
      w.avenue_period = 10.0f + static_cast<float>(r.uniform(5));  // 10..14 m
      c.zone_query_spacing = w.avenue_length / kZoneQueries;
      break;
  }
  return c;
}

SimConfig SimConfig::tiny_lattice() {
  SimConfig c = tiny();
  c.world.seed = 13;
  c.world.blocks_x = 1;
  c.world.blocks_y = 1;
  c.world.block_size = 70.0f;
  c.world.zone = ZoneType::Lattice;
  c.world.cue_density = 0.5f;
  c.world.lattice_nx = 4;
  c.world.lattice_ny = 3;
  c.world.zone_margin = 40.0f;
  c.map_spacing = 14.0f;
  c.query_spacing = 30.0f;
  c.zone_query_spacing = 14.0f;
  c.time_gap.seed = 3;
  return c;
}

float zone_query_spacing(const World& w, const SimConfig& c) {
  if (c.zone_query_spacing > 0) return c.zone_query_spacing;
  switch (w.params.zone) {
    case ZoneType::Row: return c.query_spacing / 2;
    case ZoneType::Lattice: return 6.0f;
    case ZoneType::Hall: return 7.0f;
    case ZoneType::Avenue: return 6.0f;
  }
  return c.query_spacing / 2;
}

LidarParams drive_lidar(const SimConfig& c, int sequence) {
  LidarParams l = c.lidar;
  if (sequence == 0 && c.map_beams > 0) l.beams = c.map_beams;
  return l;
}

void strip_instance_ids(uint32_t* labels, uint32_t count) {
  for (uint32_t i = 0; i < count; ++i) labels[i] &= 0xFFFFu;
}

uint64_t scan_seed(uint64_t seed, int sequence, uint32_t frame) {
  return gsf::mix64(seed * 1000003u + uint64_t(sequence) * 7919u + frame);
}

namespace {
// Keeps the poses in the western `share` of the drive's x extent (SimConfig::map_coverage).
void keep_western_share(Drive* d, float share) {
  if (d->poses.empty()) return;
  double lo = d->poses[0].translation().x(), hi = lo;
  for (const auto& p : d->poses) {
    lo = std::min(lo, p.translation().x());
    hi = std::max(hi, p.translation().x());
  }
  const double cut = lo + double(share) * (hi - lo);
  Drive kept;
  for (size_t i = 0; i < d->poses.size(); ++i) {
    if (d->poses[i].translation().x() > cut) continue;
    kept.poses.push_back(d->poses[i]);
    kept.in_zone.push_back(d->in_zone[i]);
    kept.near_zone.push_back(d->near_zone[i]);
  }
  *d = kept;
}
}  // namespace

Drive mapping_drive(const World& w, const SimConfig& c) {
  Drive d;
  const float lane = w.params.road_width / 4;
  for (const RoadSegment& r : w.roads) {
    if (!(r.drives & kMapDrive)) continue;
    const float rl = r.width > 0 ? r.width / 4 : lane;
    const float len = std::fabs(r.x1 - r.x0) + std::fabs(r.y1 - r.y0);
    const float dx = (r.x1 - r.x0) / len, dy = (r.y1 - r.y0) / len;
    const double yaw = std::atan2(dy, dx);
    for (float s = 0.0f; s <= len; s += c.map_spacing) {
      const float x = r.x0 + s * dx + rl * dy, y = r.y0 + s * dy - rl * dx;  // right-hand lane
      d.poses.push_back(make_pose(x, y, c.sensor_height, yaw));
      d.in_zone.push_back(w.in_zone(x, y));
      d.near_zone.push_back(w.near_zone(x, y));
    }
  }
  if (c.map_coverage < 1.0f) keep_western_share(&d, c.map_coverage);
  return d;
}

Drive query_drive(const World& w, const SimConfig& c) {
  Drive d;
  gsf::Rng rng(w.params.seed ^ 0xABCDEF12345ULL);
  const float lane = w.params.road_width / 4;
  const double deg = M_PI / 180.0;
  int segment = 0;
  const float zone_spacing = zone_query_spacing(w, c);
  for (const RoadSegment& r : w.roads) {
    if (!(r.drives & kQueryDrive)) continue;
    const float lane_r = r.width > 0 ? r.width / 4 : lane;
    const float len = std::fabs(r.x1 - r.x0) + std::fabs(r.y1 - r.y0);
    const float dx = (r.x1 - r.x0) / len, dy = (r.y1 - r.y0) / len;
    // Alternate: opposite direction in the other lane, or the same direction in the other lane. Zone
    // roads and aisles: always against the segment's (the mapping drive's) direction.
    const bool reverse = (segment++ % 2) == 0 || r.in_zone;
    const float spacing =
        r.in_zone ? zone_spacing : (r.approach && c.near_query_spacing > 0 ? c.near_query_spacing : c.query_spacing);
    for (float s = spacing * 0.37f; s <= len; s += spacing) {
      // Reverse: the left lane of the mapping direction. Same direction: the road centre line, half a
      // lane from the mapping lane.
      const float side = reverse ? lane_r : 0.0f;
      float x = r.x0 + s * dx - side * dy, y = r.y0 + s * dy + side * dx;
      x += c.pose_noise_xy * (2 * rng.uniform01() - 1) * std::fabs(dy);
      y += c.pose_noise_xy * (2 * rng.uniform01() - 1) * std::fabs(dx);
      const double yaw =
          std::atan2(reverse ? -dy : dy, reverse ? -dx : dx) + c.pose_noise_yaw_deg * deg * (2 * rng.uniform01() - 1);
      const double roll = c.pose_noise_tilt_deg * deg * (2 * rng.uniform01() - 1);
      const double pitch = c.pose_noise_tilt_deg * deg * (2 * rng.uniform01() - 1);
      d.poses.push_back(make_pose(x, y, c.sensor_height, yaw, roll, pitch));
      d.in_zone.push_back(w.in_zone(x, y));
      d.near_zone.push_back(w.near_zone(x, y));
    }
  }
  return d;
}

namespace {

// The query lane of segment r at arc length s: position and heading (query_drive's lane rule: reverse
// segments in the mapping drive's left lane against it, the others on the centre line with it).
Eigen::Vector3d lane_point(const World& w, const RoadSegment& r, bool reverse, float s) {
  const float lane_r = r.width > 0 ? r.width / 4 : w.params.road_width / 4;
  const float len = std::fabs(r.x1 - r.x0) + std::fabs(r.y1 - r.y0);
  const float dx = (r.x1 - r.x0) / len, dy = (r.y1 - r.y0) / len;
  const float side = reverse ? lane_r : 0.0f;
  return Eigen::Vector3d(r.x0 + s * dx - side * dy, r.y0 + s * dy + side * dx,
                         std::atan2(reverse ? -dy : dy, reverse ? -dx : dx));
}

// One stretch along segment r: `n` poses 0.5-1.5 m apart in the driving direction, a smooth path (a
// constant lateral offset within 0.3 m, heading noise 0.5 deg).
void add_stretch(const World& w, const SimConfig& c, const RoadSegment& r, bool reverse, gsf::Rng& rng, Drive* d) {
  const float len = std::fabs(r.x1 - r.x0) + std::fabs(r.y1 - r.y0);
  const float need = 1.5f * float(c.stretch_scans);
  float s = len > need ? rng.uniform01() * (len - need) : 0.0f;
  const float offset = 0.3f * (2.0f * rng.uniform01() - 1.0f);
  const double deg = M_PI / 180.0;
  for (uint32_t k = 0; k < c.stretch_scans; ++k, s += 0.5f + rng.uniform01()) {
    const float along = reverse ? len - s : s;  // reverse lanes drive from the segment's end
    const Eigen::Vector3d p = lane_point(w, r, reverse, std::min(along, len));
    const double yaw = p.z() + 0.5 * deg * (2 * rng.uniform01() - 1);
    const float nx = -std::sin(float(p.z())), ny = std::cos(float(p.z()));
    const float x = float(p.x()) + offset * nx, y = float(p.y()) + offset * ny;
    d->poses.push_back(make_pose(x, y, c.sensor_height, yaw));
    d->in_zone.push_back(w.in_zone(x, y));
    d->near_zone.push_back(w.near_zone(x, y));
  }
}

}  // namespace

Drive stretch_drive(const World& w, const SimConfig& c, std::vector<uint32_t>* starts) {
  Drive d;
  starts->clear();
  std::vector<uint32_t> segments;  // query segments with their query_drive direction rule
  std::vector<bool> reverse;
  int segment = 0;
  for (uint32_t i = 0; i < w.roads.size(); ++i) {
    if (!(w.roads[i].drives & kQueryDrive)) continue;
    segments.push_back(i);
    reverse.push_back((segment++ % 2) == 0 || w.roads[i].in_zone);
  }
  if (segments.empty() || c.stretch_scans == 0) return d;
  gsf::Rng rng(w.params.seed ^ 0x5742E7C4E5ULL);
  for (uint32_t k = 0; k < c.stretches; ++k) {
    const uint32_t pick = uint32_t((uint64_t(k) * segments.size()) / c.stretches);  // evenly over segments
    starts->push_back(static_cast<uint32_t>(d.poses.size()));
    add_stretch(w, c, w.roads[segments[pick]], reverse[pick], rng, &d);
  }
  return d;
}

namespace {

// The labels a segmentation network would write for one scan of drive `sequence`: its errors are drawn
// from the scan's seed (independent per scan and between the drives), then instance ids are stripped.
void apply_sensing(const SimConfig& c, int sequence, uint32_t frame, SimScan* scan) {
  const uint64_t seed = scan_seed(c.world.seed, sequence, frame);
  if (c.object_confusion > 0)
    apply_object_confusion(scan->labels.data(), scan->size(), c.object_confusion,
                           gsf::mix64(seed ^ label_errors::kObjectSalt));
  if (c.thin_miss > 0)
    apply_thin_miss(scan->xyzi.data(), scan->labels.data(), scan->size(), c.thin_miss,
                    gsf::mix64(seed ^ label_errors::kThinSalt));
  if (c.spurious_objects > 0)
    apply_spurious_objects(scan->xyzi.data(), scan->labels.data(), scan->size(), c.spurious_objects,
                           gsf::mix64(seed ^ label_errors::kSpuriousSalt));
  if (c.label_noise > 0)
    apply_label_noise(scan->labels.data(), scan->size(), c.label_noise, gsf::mix64(seed ^ label_errors::kNoiseSalt));
  if (!c.instance_ids) strip_instance_ids(scan->labels.data(), scan->size());
}

// Scans one drive and writes it as sequence "00" (sequence 0), "01" (1) or "02" (2) with its poses.
Status write_drive(const SimConfig& c, const std::string& root, int sequence, const Drive& d, const Raycaster& caster,
                   SimSummary* sum, const SimProgress& progress) {
  gsf::port::SemanticKittiWriter writer;
  gsf::port::NuScenesLidarsegWriter nus_writer;
  std::vector<uint8_t> lidarseg;
  SimScan scan;
  const LidarParams lidar = drive_lidar(c, sequence);
  const char* name = sequence == 0 ? "00" : (sequence == 1 ? "01" : "02");
  Status s = c.nuscenes_labels ? nus_writer.open(root, name) : writer.open(root, name);
  if (s != Status::Ok) return s;
  for (uint32_t f = 0; f < d.poses.size(); ++f) {
    caster.scan(d.poses[f], lidar, scan_seed(c.world.seed, sequence, f), &scan);
    apply_sensing(c, sequence, f, &scan);
    if (c.nuscenes_labels) {
      lidarseg.resize(scan.size());
      for (uint32_t i = 0; i < scan.size(); ++i) lidarseg[i] = gsf::port::kitti_to_nuscenes(scan.labels[i]);
      s = nus_writer.write_scan(f, scan.xyzi.data(), lidarseg.data(), scan.size());
    } else {
      s = writer.write_scan(f, scan.xyzi.data(), scan.labels.data(), nullptr, scan.size());
    }
    if (s != Status::Ok) return s;
    sum->points += scan.size();
    if (progress)
      progress(sequence == 0 ? "mapping drive" : (sequence == 1 ? "query drive" : "10 Hz stretches"), f + 1,
               static_cast<uint32_t>(d.poses.size()));
  }
  std::vector<Eigen::Isometry3d> posed = d.poses;  // the scans stay in the sensor frame; only poses move
  for (Eigen::Isometry3d& p : posed)
    p.translation() += Eigen::Vector3d(c.pose_offset[0], c.pose_offset[1], c.pose_offset[2]);
  return c.nuscenes_labels ? nus_writer.write_poses(posed) : writer.write_poses(posed);
}

// meta.json's "zone" object: type, cue mode and density, rectangle, the type's sizes and counts.
void write_zone_meta(std::ostream& meta, const SimConfig& c, const World& world, const SimSummary& sum) {
  const WorldParams& wp = c.world;
  meta << "  \"zone\": {\"type\": \"" << zone_name(wp.zone) << "\", \"cues\": \""
       << (wp.legacy_row_cues() ? "legacy" : "density")
       << "\", \"cue_density\": " << (wp.legacy_row_cues() ? -1.0f : wp.effective_cue_density()) << ", \"rect\": ["
       << world.zone_rect[0] << ", " << world.zone_rect[1] << ", " << world.zone_rect[2] << ", " << world.zone_rect[3]
       << "]";
  if (wp.zone == ZoneType::Lattice)
    meta << ", \"nx\": " << wp.lattice_nx << ", \"ny\": " << wp.lattice_ny << ", \"dx\": " << wp.lattice_spacing
         << ", \"dy\": " << wp.lattice_spacing;
  else if (wp.zone == ZoneType::Hall)
    meta << ", \"nx\": " << wp.hall_nx << ", \"ny\": " << wp.hall_ny << ", \"dx\": " << wp.hall_dx
         << ", \"dy\": " << wp.hall_dy;
  else if (wp.zone == ZoneType::Avenue)
    meta << ", \"length\": " << wp.avenue_length << ", \"period\": " << wp.avenue_period << ", \"kind\": \""
         << (!world.zone_repeated_prims.empty() && world.prims[world.zone_repeated_prims[0]].semantic == 71 ? "trees"
                                                                                                            : "lamps")
         << "\"";
  else meta << ", \"length\": " << wp.zone_length << ", \"period\": " << wp.zone_period;
  meta << ", \"margin\": " << wp.zone_margin << ", \"repeated_instances\": " << sum.zone_instances
       << ", \"cued_instances\": " << sum.cued_instances << ", \"zone_queries\": " << sum.zone_queries
       << ", \"near_zone_queries\": " << sum.near_zone_queries << ", \"near_zone_m\": " << kNearZone << "},\n";
}

// meta.json's "sensing" object: the label errors and label format of the written scans.
void write_sensing_meta(std::ostream& meta, const SimConfig& c) {
  meta << "  \"sensing\": {\"label_noise\": " << c.label_noise << ", \"object_confusion\": " << c.object_confusion
       << ", \"thin_miss\": " << c.thin_miss << ", \"spurious_objects\": " << c.spurious_objects
       << ", \"map_coverage\": " << c.map_coverage << ", \"map_beams\": " << drive_lidar(c, 0).beams
       << ", \"beams\": " << drive_lidar(c, 1).beams << ", \"instance_ids\": " << (c.instance_ids ? "true" : "false")
       << ", \"label_set\": \"" << (c.nuscenes_labels ? "nuscenes" : "semantic-kitti") << "\""
       << "},\n";
}

void write_flags(std::ostream& meta, const std::vector<bool>& flags) {
  for (size_t i = 0; i < flags.size(); ++i) meta << (i ? "," : "") << (flags[i] ? 1 : 0);
}

// meta.json: the original keys first, then the zone, sensing and per-query near-zone keys added later.
// meta.json's stretch keys (sequence 02): each stretch's first scan and length, and per scan whether it
// is in / near the zone.
void write_stretch_meta(std::ostream& meta, const SimConfig& c, const Drive& stretches,
                        const std::vector<uint32_t>& starts) {
  meta << "  \"stretch_sequence\": \"02\",\n  \"stretches\": [";
  for (size_t i = 0; i < starts.size(); ++i)
    meta << (i ? ", " : "") << "[" << starts[i] << ", " << c.stretch_scans << "]";
  meta << "],\n  \"stretch_in_repetitive_zone\": [";
  write_flags(meta, stretches.in_zone);
  meta << "],\n  \"stretch_near_zone\": [";
  write_flags(meta, stretches.near_zone);
  meta << "],\n";
}

Status write_meta(const SimConfig& c, const World& world, const Drive& queries, const SimSummary& sum,
                  const std::string& root, const Drive& stretches, const std::vector<uint32_t>& starts) {
  std::ofstream meta(std::filesystem::path(root) / "meta.json", std::ios::trunc);
  meta << "{\n  \"generator\": \"gsf simulate\",\n  \"seed\": " << c.world.seed << ",\n";
  meta << "  \"world\": {\"blocks_x\": " << c.world.blocks_x << ", \"blocks_y\": " << c.world.blocks_y
       << ", \"block_size\": " << c.world.block_size << ", \"road_width\": " << c.world.road_width
       << ", \"repetitive_zone\": " << (c.world.repetitive_zone ? "true" : "false")
       << ", \"zone_length\": " << c.world.zone_length << ", \"zone_period\": " << c.world.zone_period << "},\n";
  meta << "  \"lidar\": {\"beams\": " << c.lidar.beams << ", \"elevation_min_deg\": " << c.lidar.elevation_min_deg
       << ", \"elevation_max_deg\": " << c.lidar.elevation_max_deg
       << ", \"azimuth_step_deg\": " << c.lidar.azimuth_step_deg << ", \"max_range\": " << c.lidar.max_range
       << ", \"range_noise\": " << c.lidar.range_noise << ", \"dropout\": " << c.lidar.dropout << "},\n";
  meta << "  \"time_gap\": {\"seed\": " << c.time_gap.seed << ", \"cars_removed\": " << c.time_gap.cars_removed
       << ", \"cars_moved\": " << c.time_gap.cars_moved << ", \"vegetation_change\": " << c.time_gap.vegetation_change
       << ", \"bushes_cut\": " << c.time_gap.bushes_cut << "},\n";
  char offset[96];  // every digit (the stream's default 6 would print 5.41234e+06)
  std::snprintf(offset, sizeof(offset), "[%.17g, %.17g, %.17g]", c.pose_offset[0], c.pose_offset[1], c.pose_offset[2]);
  meta << "  \"pose_offset\": " << offset << ",\n";
  meta << "  \"road_length_m\": " << sum.road_length_m
       << ",\n  \"map_sequence\": \"00\",\n  \"query_sequence\": \"01\",\n";
  meta << "  \"map_scans\": " << sum.map_scans << ",\n  \"queries\": " << sum.queries << ",\n";
  meta << "  \"query_in_repetitive_zone\": [";
  write_flags(meta, queries.in_zone);
  meta << "],\n";
  write_zone_meta(meta, c, world, sum);
  write_sensing_meta(meta, c);
  if (!starts.empty()) write_stretch_meta(meta, c, stretches, starts);
  meta << "  \"query_near_zone\": [";
  write_flags(meta, queries.near_zone);
  meta << "]\n}\n";
  return meta ? Status::Ok : Status::IoError;
}

}  // namespace

Status run_simulation(const SimConfig& c, const std::string& root, SimSummary* summary, const SimProgress& progress) {
  SimSummary sum;
  const World world = generate_world(c.world);
  const World later = apply_time_gap(world, c.time_gap);
  const Drive map = mapping_drive(world, c);
  const Drive queries = query_drive(world, c);
  sum.road_length_m = world.road_length();
  Status s = write_drive(c, root, 0, map, Raycaster(world), &sum, progress);
  if (s == Status::Ok) s = write_drive(c, root, 1, queries, Raycaster(later), &sum, progress);
  std::vector<uint32_t> starts;
  const Drive stretches = stretch_drive(world, c, &starts);
  if (s == Status::Ok && !stretches.poses.empty())
    s = write_drive(c, root, 2, stretches, Raycaster(later), &sum, progress);
  if (s != Status::Ok) return s;
  sum.stretch_scans = static_cast<uint32_t>(stretches.poses.size());
  sum.map_scans = static_cast<uint32_t>(map.poses.size());
  sum.queries = static_cast<uint32_t>(queries.poses.size());
  for (bool z : queries.in_zone) sum.zone_queries += z ? 1u : 0u;
  for (bool z : queries.near_zone) sum.near_zone_queries += z ? 1u : 0u;
  sum.zone_instances = static_cast<uint32_t>(world.zone_instances.size());
  for (const ZoneInstance& zi : world.zone_instances) sum.cued_instances += zi.cued ? 1u : 0u;
  s = write_meta(c, world, queries, sum, root, stretches, starts);
  if (s == Status::Ok && summary) *summary = sum;
  return s;
}

}  // namespace gsf::sim
