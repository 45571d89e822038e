// MapBuilder: streaming in tiles (a tiled build with a tiny budget, its spills and a loop back into
// spilled tiles give the same map bytes as a single-tile build) and georeferencing: the origin it picks
// (first pose rounded half up, or the one given), the frame name and class table id it records, and that
// subtracting the origin in double makes a drive posed in UTM-size coordinates give the same map as the
// same drive posed locally.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <string>
#include <vector>

#include <unistd.h>

#include "arena_buffer.h"
#include "gsf/class_table.h"
#include "gsf/detail/fixed_vector.h"
#include "gsf/detail/refine_layer.h"
#include "gsf/detail/triangle.h"
#include "gsf/map_format.h"
#include "mapping/map_builder.h"
#include "mapping/map_writer.h"
#include "mapping/scan_triangles.h"
#include "mapping/workspace.h"
#include "short_run.h"
#include "test_cloud.h"
#include "tiny_world.h"

namespace test_map_builder {

using namespace gsf;

namespace {

constexpr double kEast = 512345.0, kNorth = 5412345.0;  // a UTM-size shift (zone 32N, near Munich)

// The first scans of the tiny world's mapping drive (enough for a map with instances and triangles).
struct Drive {
  std::vector<gsf_test::QueryScan> scans;
  Drive() {
    const sim::SimConfig sc = sim::SimConfig::tiny();
    const sim::World world = sim::generate_world(sc.world);
    const sim::Raycaster rc(world);
    const sim::Drive md = sim::mapping_drive(world, sc);
    for (uint32_t f = 0; f < 12 && f < md.poses.size(); ++f) {
      gsf_test::QueryScan s;
      gsf_test::make_scan(rc, sc, md.poses[f], sim::scan_seed(sc.world.seed, 0, f), 1000000u + f, &s);
      scans.push_back(std::move(s));
    }
  }
};

const Drive& drive() {
  static const Drive d;
  return d;
}

struct Built {
  Status add = Status::Ok, build = Status::Ok;
  std::vector<uint64_t> blob;
  size_t bytes = 0;
  MapView map;
  mapping::MapBuildStats stats;
  const uint8_t* sections() const { return reinterpret_cast<const uint8_t*>(blob.data()) + 624; }
};

// The bytes of a file as 16-byte aligned words (empty when it cannot be read).
std::vector<uint64_t> read_words(const std::string& path, size_t* bytes) {
  std::ifstream f(path, std::ios::binary);
  const std::vector<char> data((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  *bytes = data.size();
  std::vector<uint64_t> words(data.size() / 8 + 2, 0);
  if (!data.empty()) std::memcpy(words.data(), data.data(), data.size());
  return words;
}

// Builds the drive's scans in `order` (default: each once, in drive order); with `file`, through a
// FileMapSink to that file, read back into the blob.
Built build(const mapping::MapBuildConfig& options, const Eigen::Vector3d& shift,
            const std::vector<uint32_t>& order = {}, mapping::TileStoreStats* after_scans = nullptr,
            const std::string& file = "") {
  mapping::MapBuildConfig config = options;
  config.stages.max_scan_points = 262144;
  config.road_length_m = 120.0f;
  mapping::MapBuilder builder(config);
  Built b;
  std::vector<uint32_t> frames = order;
  for (uint32_t f = 0; frames.size() < drive().scans.size() && order.empty(); ++f) frames.push_back(f);
  for (uint32_t f : frames) {
    const auto& s = drive().scans[f];
    Eigen::Isometry3d pose = s.truth;
    pose.translation() += shift;
    b.add = builder.add_scan(s.view(), pose);
    if (b.add != Status::Ok) return b;
  }
  if (after_scans) *after_scans = builder.tile_stats();
  if (file.empty()) {
    b.build = builder.build(&b.blob, &b.bytes, &b.stats);
  } else {
    mapping::FileMapSink sink(file);
    size_t bytes = 0;
    b.build = builder.build(sink, &bytes, &b.stats);
    if (b.build == Status::Ok) b.blob = read_words(file, &b.bytes);
    if (b.build == Status::Ok && b.bytes != bytes) b.build = Status::IoError;
  }
  if (b.build == Status::Ok) b.build = load_map(b.blob.data(), b.bytes, &b.map);
  return b;
}

// The default options' build, which several test cases compare against: built once per run (each
// build costs seconds under ASan and qemu).
const Built& default_build() {
  static const Built b = build(mapping::MapBuildConfig(), Eigen::Vector3d::Zero());
  return b;
}

}  // namespace

TEST_CASE("The default origin is the first pose rounded half up to a whole metre; the class table is recorded") {
  const Built& local = default_build();
  REQUIRE(local.build == Status::Ok);
  const Eigen::Vector3d first = drive().scans[0].truth.translation();  // (0, -2.5, 1.73) in the tiny world
  for (int k = 0; k < 3; ++k) CHECK(local.map.georef.origin[k] == std::floor(first[k] + 0.5));
  CHECK(local.map.georef.origin[1] == -2.0);  // half up: -2.5 -> -2 (std::round would give -3)
  CHECK(std::string(local.map.georef.frame) == "local");
  ClassTable kitti;
  semantic_kitti_class_table(&kitti);
  CHECK(local.map.params.class_table_id == kitti.id());
  CHECK(local.map.counts.instances > 10);
  CHECK(local.map.counts.triangles > 10);
}

TEST_CASE("The map is the same bytes whatever its workspaces held before (no stage reads what it did not write)") {
  const Built& zero = default_build();
  REQUIRE(zero.build == Status::Ok);
  for (int fill : {0x00, 0xA5}) {  // and the default build: as the allocator gave them
    mapping::workspace_fill_for_tests = fill;
    const Built b = build(mapping::MapBuildConfig(), Eigen::Vector3d::Zero());
    mapping::workspace_fill_for_tests = -1;
    REQUIRE(b.build == Status::Ok);
    REQUIRE(b.bytes == zero.bytes);
    CHECK(std::memcmp(b.blob.data(), zero.blob.data(), b.bytes) == 0);
  }
}

TEST_CASE("A drive shifted by a UTM-size offset gives the same map sections, with the origin shifted exactly") {
  const Built& local = default_build();
  const Built utm = build(mapping::MapBuildConfig(), Eigen::Vector3d(kEast, kNorth, 0.0));
  REQUIRE(local.build == Status::Ok);
  REQUIRE(utm.build == Status::Ok);
  CHECK(utm.map.georef.origin[0] == local.map.georef.origin[0] + kEast);
  CHECK(utm.map.georef.origin[1] == local.map.georef.origin[1] + kNorth);
  CHECK(utm.map.georef.origin[2] == local.map.georef.origin[2]);
  // Everything after the header: instances, fields, triangles, index, refinement and semantic layers.
  REQUIRE(utm.bytes == local.bytes);
  CHECK(std::memcmp(utm.sections(), local.sections(), local.bytes - 624) == 0);
  CHECK(std::memcmp(&utm.map.counts, &local.map.counts, sizeof(MapCounts)) == 0);
}

TEST_CASE("A given origin and frame are recorded and the sections are relative to that origin") {
  mapping::MapBuildConfig zero;
  zero.origin_given = true;  // (0, 0, 0), the simulator's own frame
  mapping::MapBuildConfig utm;
  utm.origin_given = true;
  utm.origin = {kEast, kNorth, 0.0};
  utm.frame = "utm-32N";
  const Built a = build(zero, Eigen::Vector3d::Zero());
  const Built b = build(utm, Eigen::Vector3d(kEast, kNorth, 0.0));
  REQUIRE(a.build == Status::Ok);
  REQUIRE(b.build == Status::Ok);
  CHECK(b.map.georef.origin[0] == kEast);
  CHECK(b.map.georef.origin[1] == kNorth);
  CHECK(std::string(b.map.georef.frame) == "utm-32N");
  REQUIRE(a.bytes == b.bytes);
  CHECK(std::memcmp(a.sections(), b.sections(), a.bytes - 624) == 0);
  // The sections are the unshifted drive's own coordinates: an instance lies where the simulator put it.
  const Eigen::Vector3d first = drive().scans[0].truth.translation();
  double nearest = 1e9;
  for (uint32_t i = 0; i < a.map.counts.instances; ++i)
    nearest = std::min(
        nearest, std::hypot(a.map.instances[i].centroid[0] - first.x(), a.map.instances[i].centroid[1] - first.y()));
  CHECK(nearest < 40.0);  // the map is around the drive, not 5,000 km away
}

TEST_CASE("Poses far from the origin, non-finite poses and bad frame names are refused at add_scan") {
  // The old failure: UTM poses kept in a map whose origin is 0 would lose precision in float; the
  // builder now says so at the first scan instead of after accumulating every one.
  mapping::MapBuildConfig zero;
  zero.origin_given = true;
  CHECK(build(zero, Eigen::Vector3d(kEast, kNorth, 0.0)).add == Status::InvalidInput);
  mapping::MapBuildConfig near = zero;
  near.origin = {kEast - 1000.0, kNorth + 1000.0, 0.0};  // 1 km away: fine
  CHECK(build(near, Eigen::Vector3d(kEast, kNorth, 0.0)).build == Status::Ok);
  const Built nan = build(mapping::MapBuildConfig(), Eigen::Vector3d(std::nan(""), 0.0, 0.0));
  CHECK(nan.add == Status::InvalidInput);
  for (const char* name : {"", "bad\tname", "a-frame-name-that-is-much-too-long"}) {
    mapping::MapBuildConfig bad;
    bad.frame = name;
    INFO("frame '" << name << "'");
    CHECK(build(bad, Eigen::Vector3d::Zero()).add == Status::InvalidArgument);
  }
}

TEST_CASE("The builder's capacities are options: what they cut is counted, the rest kept by rank") {
  const Built& full = default_build();
  REQUIRE(full.build == Status::Ok);
  CHECK(full.stats.instances_dropped == 0);
  CHECK(full.stats.field_points_dropped == 0);
  REQUIRE(full.stats.instances > 6);
  mapping::MapBuildConfig small;
  small.max_instances = 5;
  small.max_field_points = 50;
  const Built cut = build(small, Eigen::Vector3d::Zero());
  REQUIRE(cut.build == Status::Ok);
  CHECK(cut.stats.instances == 5);
  CHECK(cut.stats.instances_dropped == full.stats.instances - 5);
  CHECK(cut.stats.field_points_dropped > 0);
  // The kept instances are the largest by points (InstanceClustering's ranking), not the first found.
  uint32_t smallest_kept = UINT32_MAX;
  for (uint32_t i = 0; i < cut.map.counts.instances; ++i)
    smallest_kept = std::min(smallest_kept, cut.map.instances[i].point_count);
  uint32_t larger_in_full = 0;
  for (uint32_t i = 0; i < full.map.counts.instances; ++i)
    larger_in_full += full.map.instances[i].point_count > smallest_kept;
  CHECK(larger_in_full <= 5);
}

namespace {

// One tile for the whole map, everything in memory: the reference the streaming builds must equal.
mapping::MapBuildConfig single_tile() {
  mapping::MapBuildConfig c;
  c.tile_size = 0.0f;
  c.max_resident_tiles = 0;
  return c;
}

mapping::MapBuildConfig tiled(float tile_size, uint32_t resident) {
  mapping::MapBuildConfig c;
  c.tile_size = tile_size;
  c.max_resident_tiles = resident;
  return c;
}

bool same_bytes(const Built& a, const Built& b) {
  return a.bytes == b.bytes && std::memcmp(a.blob.data(), b.blob.data(), a.bytes) == 0;
}

// Out along the drive and back over its first four scans.
std::vector<uint32_t> drive_and_back() {
  std::vector<uint32_t> loop;
  for (uint32_t f = 0; f < drive().scans.size(); ++f) loop.push_back(f);
  for (uint32_t f = 0; f < 4; ++f) loop.push_back(f);
  return loop;
}

// The single-tile build of the drive once (loop false) or out and back, built once per run as
// default_build (each only when first asked for).
const Built& whole_build(bool loop) {
  if (loop) {
    static const Built back = build(single_tile(), Eigen::Vector3d::Zero(), drive_and_back());
    return back;
  }
  static const Built once = build(single_tile(), Eigen::Vector3d::Zero());
  return once;
}

}  // namespace

TEST_CASE("A streaming build with tiny tiles and a two-tile budget spills and reloads, and gives the same map bytes") {
  const Built& whole = whole_build(false);
  REQUIRE(whole.build == Status::Ok);
  REQUIRE(whole.stats.instances > 10);
  CHECK(whole.stats.tiles.tiles == 1);
  CHECK(whole.stats.tiles.spills == 0);
  // 10 m tiles: many cars and most field neighbourhoods cross tile borders; an instance is built by the
  // tile of its lowest voxel with its neighbours loaded. A second size moves the borders (not in a
  // slow build: short_run.h).
  for (float tile : {10.0f, 26.0f}) {
    if (tile != 10.0f && gsf_test::short_run()) break;
    INFO("tile " << tile << " m");
    const Built streamed = build(tiled(tile, 2), Eigen::Vector3d::Zero());
    REQUIRE(streamed.build == Status::Ok);
    CHECK(streamed.stats.tiles.tiles > 8);
    CHECK(streamed.stats.tiles.peak_resident <= 2);
    CHECK(streamed.stats.tiles.spills > 0);
    CHECK(streamed.stats.tiles.reloads > 0);
    // The spill file reuses freed slots: never more than twice the live slots it holds.
    CHECK(streamed.stats.tiles.spill_live_peak_bytes > 0);
    CHECK(streamed.stats.tiles.spill_peak_bytes <= 2 * streamed.stats.tiles.spill_live_peak_bytes);
    CHECK(streamed.stats.map_voxels == whole.stats.map_voxels);
    CHECK(streamed.stats.instances == whole.stats.instances);
    CHECK(same_bytes(streamed, whole));
  }
}

namespace {

// The tiny drive's scans in `order` as a drive the builder can read again; counts the reads.
class TestDrive : public mapping::ScanSequence {
 public:
  explicit TestDrive(const std::vector<uint32_t>& order) : order_(order) {}
  uint32_t size() const override { return static_cast<uint32_t>(order_.size()); }
  Status read(uint32_t i, ScanView* scan, Eigen::Isometry3d* pose) override {
    ++reads;
    *scan = drive().scans[order_[i]].view();
    *pose = drive().scans[order_[i]].truth;
    return Status::Ok;
  }
  uint64_t reads = 0;

 private:
  std::vector<uint32_t> order_;
};

// build_blocked over the scans in `order` (default: each once, in drive order).
Built build_in_blocks(const mapping::MapBuildConfig& options, std::vector<uint32_t> order = {},
                      uint64_t* reads = nullptr) {
  mapping::MapBuildConfig config = options;
  config.stages.max_scan_points = 262144;
  config.road_length_m = 120.0f;
  for (uint32_t f = 0; order.empty() && f < drive().scans.size(); ++f) order.push_back(f);
  if (order.empty()) order.push_back(0);
  mapping::MapBuilder builder(config);
  TestDrive d(order);
  Built b;
  mapping::MemoryMapSink sink(&b.blob);
  b.build = builder.build_blocked(d, sink, &b.bytes, &b.stats);
  if (b.build == Status::Ok) b.build = load_map(b.blob.data(), b.bytes, &b.map);
  if (reads) *reads = d.reads;
  return b;
}

mapping::MapBuildConfig blocked(float tile_size, uint32_t block_tiles) {
  mapping::MapBuildConfig c;
  c.tile_size = tile_size;
  c.block_tiles = block_tiles;
  return c;
}

}  // namespace

TEST_CASE("A blocked build holds one block, never spills, reads scans again, and gives the same map bytes") {
  // Out along the drive and back over its start (a drive that returns to tiles it left: add_scan's
  // build spills them), built block by block with blocks and tiles smaller than a scan.
  const std::vector<uint32_t> loop = drive_and_back();
  const Built& whole = whole_build(true);
  REQUIRE(whole.build == Status::Ok);
  REQUIRE(whole.stats.instances > 10);
  const Built streamed = build(tiled(10.0f, 2), Eigen::Vector3d::Zero(), loop);
  REQUIRE(streamed.build == Status::Ok);
  CHECK(streamed.stats.tiles.spill_peak_bytes > 0);
  uint32_t blocks_of_3x3_10m_tiles = 0;
  // Blocks of one tile, of 3 x 3 small tiles (many blocks), of 2 x 2 others, one block for the whole
  // drive; a slow build (short_run.h) the two middle ones.
  for (const auto& [tile, block] : {std::pair<float, uint32_t>{10.0f, 1}, {10.0f, 3}, {26.0f, 2}, {64.0f, 4}}) {
    if (gsf_test::short_run() && (block == 1 || block == 4)) continue;
    INFO("tile " << tile << " m, blocks of " << block << " x " << block);
    uint64_t reads = 0;
    const Built b = build_in_blocks(blocked(tile, block), loop, &reads);
    REQUIRE(b.build == Status::Ok);
    CHECK(b.stats.scans == loop.size());
    CHECK(b.stats.tiles.spills == 0);  // no spill file
    CHECK(b.stats.tiles.spill_peak_bytes == 0);
    CHECK(b.stats.map_voxels == whole.stats.map_voxels);
    CHECK(reads == loop.size() + b.stats.block_scan_reads);  // the first pass, then once per block reached
    if (b.stats.blocks > 1) {
      // One block and its halo in memory, not the map (the map's voxels in spill records: 192 B each).
      CHECK(b.stats.tiles.peak_resident_voxels < whole.stats.map_voxels);
      CHECK(b.stats.tiles.peak_resident_bytes == b.stats.tiles.peak_resident_voxels * 192);
      CHECK(b.stats.block_scan_reads > loop.size());
    }
    CHECK(same_bytes(b, whole));
    if (tile == 10.0f && block == 3) blocks_of_3x3_10m_tiles = b.stats.blocks;
  }
  CHECK(blocks_of_3x3_10m_tiles > 4);
}

TEST_CASE("A blocked build refuses a builder that added scans, no tiles or no blocks, and reports a bad scan") {
  mapping::MapBuilder used(blocked(16.0f, 2));
  REQUIRE(used.add_scan(drive().scans[0].view(), drive().scans[0].truth) == Status::Ok);
  TestDrive d({0, 1});
  std::vector<uint64_t> blob;
  mapping::MemoryMapSink sink(&blob);
  size_t bytes = 0;
  CHECK(used.build_blocked(d, sink, &bytes, nullptr) == Status::InvalidArgument);
  CHECK(build_in_blocks(blocked(0.0f, 2)).build == Status::InvalidArgument);
  CHECK(build_in_blocks(blocked(16.0f, 0)).build == Status::InvalidArgument);
  // A pose beyond the map-local range: InvalidInput, with the scan's index.
  class FarDrive : public TestDrive {
   public:
    FarDrive() : TestDrive({0, 1, 2}) {}
    Status read(uint32_t i, ScanView* scan, Eigen::Isometry3d* pose) override {
      const Status s = TestDrive::read(i, scan, pose);
      if (i == 2) pose->translation().x() += 1e6;
      return s;
    }
  } far;
  mapping::MapBuilder builder(blocked(16.0f, 2));
  uint32_t failed = 0;
  CHECK(builder.build_blocked(far, sink, &bytes, nullptr, nullptr, &failed) == Status::InvalidInput);
  CHECK(failed == 2);
}

TEST_CASE("A loop back into spilled tiles continues their sums: the same bytes as in memory") {
  // Out along the drive and back over its start: by then the start's tiles were spilled.
  const std::vector<uint32_t> loop = drive_and_back();
  const Built& whole = whole_build(true);
  mapping::TileStoreStats during;
  const Built streamed = build(tiled(16.0f, 2), Eigen::Vector3d::Zero(), loop, &during);
  REQUIRE(whole.build == Status::Ok);
  REQUIRE(streamed.build == Status::Ok);
  CHECK(during.spills > 0);
  CHECK(during.reloads > 0);  // the revisit read spilled tiles back before build()
  CHECK(streamed.stats.tiles.spill_peak_bytes <= 2 * streamed.stats.tiles.spill_live_peak_bytes);
  CHECK(same_bytes(streamed, whole));
  // The revisit counts: its points are in the map (instances have more points than without the loop).
  const Built& once = whole_build(false);
  REQUIRE(once.build == Status::Ok);
  CHECK_FALSE(same_bytes(once, whole));
}

namespace {

// Adds `n` voxels (keys seeded by `seed`) to tile column `tx` of a 4-voxel-tile store, and the same
// sums to `truth`.
void grow_tile(mapping::TileStore* store, std::map<uint64_t, mapping::VoxelAccum>* truth, int tx, int n, int seed) {
  for (int i = 0; i < n; ++i) {
    // x within the tile column, y within tile row 0, z distinct per (seed, i).
    const double x = (4 * tx + i % 4) * 0.5 + 0.25, y = (i / 4 % 4) * 0.5 + 0.25, z = (seed * 16 + i / 16) * 0.5 + 0.25;
    const uint64_t key = mapping::voxel_key(x, y, z, 0.5);
    Status s = Status::Ok;
    mapping::VoxelAccum* a = store->accumulator(key, &s);
    REQUIRE(a != nullptr);
    mapping::VoxelAccum& t = (*truth)[key];
    for (mapping::VoxelAccum* x : {a, &t}) {
      x->sum[0] += 0.1 * (seed + 1);
      x->prob[seed % kNumClasses] += 1.0 / 3.0;
      x->count += 1;
    }
  }
}

// The size of the one spill file in `dir`.
uint64_t spill_file_size(const std::string& dir) {
  uint64_t bytes = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) bytes += entry.file_size();
  return bytes;
}

}  // namespace

TEST_CASE("The spill file reuses freed slots and is compacted: never more than its ratio x its live slots") {
  // 24 tiles spilled side by side, then every other one grown (reloaded, spilled again to a bigger slot)
  // twice. At ratio 1 every hole left behind forces a compaction before the next append.
  for (double ratio : {1.0, 2.0}) {
    INFO("max_spill_ratio " << ratio);
    char dir_name[] = "/tmp/gsf-test-spill-XXXXXX";
    REQUIRE(mkdtemp(dir_name) != nullptr);
    const std::string dir = dir_name;
    std::map<uint64_t, mapping::VoxelAccum> truth;
    {
      mapping::TileStoreConfig c;
      c.tile_voxels = 4;
      c.max_resident_tiles = 1;
      c.spill_dir = dir;
      c.max_spill_ratio = ratio;
      mapping::TileStore store(c);
      uint64_t file_peak = 0;
      for (int round = 0; round < 3; ++round)
        for (int tx = 0; tx < 24; ++tx) {
          if (round > 0 && tx % 2 == 0) continue;
          grow_tile(&store, &truth, tx, round == 0 ? 8 : 16 * round, round);
          file_peak = std::max(file_peak, spill_file_size(dir));  // one spill per tile touched
        }
      REQUIRE(store.spill_resident() == Status::Ok);
      file_peak = std::max(file_peak, spill_file_size(dir));
      const mapping::TileStoreStats& st = store.stats();
      CHECK(st.spills == 24 + 2 * 12);
      if (ratio == 1.0) CHECK(st.compactions > 0);
      if (ratio == 1.0) CHECK(st.compaction_bytes > 0);
      CHECK(st.spill_peak_bytes == file_peak);  // the stats report the file's size on disk
      CHECK(double(st.spill_peak_bytes) <= ratio * double(st.spill_live_peak_bytes));
      CHECK(st.spill_bytes == spill_file_size(dir));
      // Every voxel's sums read back from the file exactly, wherever its slot moved.
      std::vector<std::pair<uint64_t, mapping::VoxelAccum>> all;
      for (uint64_t id : store.tile_ids())
        REQUIRE(store.append_voxels(id, -1000, 1000, -1000, 1000, &all) == Status::Ok);
      REQUIRE(all.size() == truth.size());
      for (const auto& kv : all) {
        REQUIRE(truth.count(kv.first) == 1);
        CHECK(std::memcmp(&kv.second, &truth[kv.first], sizeof(mapping::VoxelAccum)) == 0);
      }
    }
    CHECK(std::filesystem::is_empty(dir));  // the store removed its file
    std::filesystem::remove(dir);
  }
}

TEST_CASE("Whole-map capacities apply after the tiles, with the stages' ranking") {
  mapping::MapBuildConfig whole = single_tile();
  whole.max_instances = 7;
  mapping::MapBuildConfig streamed = tiled(16.0f, 2);
  streamed.max_instances = 7;
  const Built a = build(whole, Eigen::Vector3d::Zero());
  const Built b = build(streamed, Eigen::Vector3d::Zero());
  REQUIRE(a.build == Status::Ok);
  REQUIRE(b.build == Status::Ok);
  CHECK(a.stats.instances == 7);
  CHECK(b.stats.instances_dropped == a.stats.instances_dropped);
  CHECK(b.stats.instances_dropped > 0);
  CHECK(same_bytes(a, b));
}

TEST_CASE("The map's instance ceiling is the triangle builder's 21-bit ids, far beyond 65,535") {
  const mapping::MapBuildConfig defaults;
  CHECK(uint64_t(defaults.max_instances) + defaults.max_pole_instances <= mapping::kMaxMapInstances);
  CHECK(defaults.max_instances > 1000000u);
  CHECK(defaults.max_pole_instances > 1000000u);
}

TEST_CASE("A spill directory that cannot be written fails the scan with IoError") {
  mapping::MapBuildConfig c = tiled(32.0f, 1);
  c.spill_dir = "/nonexistent-gsf-spill-dir";
  CHECK(build(c, Eigen::Vector3d::Zero()).add == Status::IoError);
  c.spill_dir = "/tmp";
  CHECK(build(c, Eigen::Vector3d::Zero()).build == Status::Ok);
}

TEST_CASE("Map scans are voxelised with at least scan_max_voxels; what a smaller capacity drops is counted") {
  mapping::MapBuildConfig full;
  full.stages.voxel.max_voxels = 500;  // an on-board setting far below a scan's voxels
  const Built b = build(full, Eigen::Vector3d::Zero());
  REQUIRE(b.build == Status::Ok);
  CHECK(b.stats.scan_points_dropped == 0);  // raised to scan_max_voxels (100k) for map scans
  mapping::MapBuildConfig small = full;
  small.scan_max_voxels = 500;
  const Built s = build(small, Eigen::Vector3d::Zero());
  REQUIRE(s.build == Status::Ok);
  CHECK(s.stats.scan_points_dropped > 0);
  CHECK(s.stats.map_voxels < b.stats.map_voxels);
}

TEST_CASE("A map built straight to a file is the in-memory build's bytes, and write_map's of its sections") {
  const std::string path = "/tmp/gsf-test-map-builder-" + std::to_string(::getpid()) + ".gsfmap";
  for (const mapping::MapBuildConfig& config : {mapping::MapBuildConfig(), tiled(16.0f, 2)}) {
    const Built memory = build(config, Eigen::Vector3d::Zero());
    const Built file = build(config, Eigen::Vector3d::Zero(), {}, nullptr, path);
    REQUIRE(memory.build == Status::Ok);
    REQUIRE(file.build == Status::Ok);
    CHECK(memory.map.counts.refine_points > 0);  // every section is exercised
    CHECK(memory.map.counts.semantic_tiles > 0);
    CHECK(memory.stats.bytes == memory.bytes);
    REQUIRE(file.bytes == memory.bytes);
    CHECK(std::memcmp(file.blob.data(), memory.blob.data(), memory.bytes) == 0);
    CHECK(std::memcmp(&file.stats.tiles, &memory.stats.tiles, sizeof(mapping::TileStoreStats)) == 0);
    // The library's in-memory serialiser over the loaded view writes the same bytes.
    std::vector<uint64_t> again(memory.bytes / 8 + 2, 0);
    size_t written = 0;
    REQUIRE(write_map(memory.map, again.data(), again.size() * 8, &written) == Status::Ok);
    REQUIRE(written == memory.bytes);
    CHECK(std::memcmp(again.data(), memory.blob.data(), memory.bytes) == 0);
    CHECK(std::ifstream(path + ".partial").fail());  // renamed into place
  }
  std::remove(path.c_str());
}

TEST_CASE("A map sink takes the sections in id order, checks them against the header and reports write errors") {
  const Built& b = default_build();
  REQUIRE(b.build == Status::Ok);
  const MapView& m = b.map;
  const auto* base = reinterpret_cast<const uint8_t*>(b.blob.data());
  MapSectionLayout layout[kMapSectionCount];
  size_t total = 0;
  REQUIRE(map_layout(m, layout, &total) == Status::Ok);
  CHECK(total == b.bytes);
  // Each section in pieces of 1000 bytes: the same blob.
  std::vector<uint64_t> blob;
  mapping::MemoryMapSink sink(&blob);
  for (uint32_t i = 0; i < kMapSectionCount; ++i) {
    REQUIRE(sink.begin_section(MapSection(layout[i].id)) == Status::Ok);
    for (uint64_t at = 0; at < layout[i].bytes; at += 1000)
      REQUIRE(sink.append(base + layout[i].offset + at, std::min<uint64_t>(1000, layout[i].bytes - at)) == Status::Ok);
    REQUIRE(sink.end_section() == Status::Ok);
  }
  size_t bytes = 0;
  REQUIRE(sink.finish(m, &bytes) == Status::Ok);
  REQUIRE(bytes == b.bytes);
  CHECK(std::memcmp(blob.data(), b.blob.data(), bytes) == 0);
  // Out of order, twice, or counts that disagree with what was written.
  std::vector<uint64_t> other;
  mapping::MemoryMapSink bad(&other);
  CHECK(bad.section(MapSection::GridMean, base, 1) == Status::InvalidArgument);
  CHECK(bad.section(MapSection::Instances, base + layout[0].offset, layout[0].bytes) == Status::Ok);
  CHECK(bad.section(MapSection::Instances, base, 1) == Status::InvalidArgument);
  for (uint32_t i = 1; i < kMapSectionCount; ++i)
    REQUIRE(bad.section(MapSection(layout[i].id), base + layout[i].offset, layout[i].bytes) == Status::Ok);
  MapView wrong = m;
  wrong.counts.triangles += 1;
  CHECK(bad.finish(wrong, &bytes) == Status::InvalidArgument);
  CHECK(bytes == 0);
  // A file that cannot be created: IoError from the first section on, and nothing is left behind.
  mapping::FileMapSink nowhere("/nonexistent-gsf-dir/map.gsfmap");
  CHECK_FALSE(nowhere.is_open());
  CHECK(nowhere.section(MapSection::Instances, base + layout[0].offset, layout[0].bytes) == Status::IoError);
  CHECK(nowhere.finish(m, &bytes) == Status::IoError);
}

TEST_CASE("count_detections counts same-label detections within the radius, across cell borders") {
  // Instances at (0.9, 0.9) label 3, (10, 10) label 3, (0.9, 0.9) label 4; radius 2 m cells.
  const float c[9] = {0.9f, 0.9f, 0.0f, 10.0f, 10.0f, 0.0f, 0.9f, 0.9f, 0.0f};
  const uint8_t lab[3] = {3, 3, 4};
  std::vector<mapping::ScanDetection> d;
  auto add = [&](float x, float y, uint8_t l) {
    mapping::ScanDetection s{};
    s.xyz[0] = x;
    s.xyz[1] = y;
    s.xyz[2] = 5.0f;  // height does not matter (bird's-eye)
    s.label = l;
    d.push_back(s);
  };
  add(2.5f, 0.9f, 3);    // 1.6 m away, next cell: counts for instance 0
  add(-0.9f, -0.5f, 3);  // 2.28 m away: too far
  add(1.0f, 1.0f, 4);    // label 4: instance 2 only
  add(10.0f, 11.9f, 3);  // 1.9 m from instance 1
  add(10.0f, 11.9f, 3);  // a second scan's detection of it
  const std::vector<uint32_t> n = mapping::count_detections(c, lab, 3, d, 2.0f);
  REQUIRE(n.size() == 3);
  CHECK(n[0] == 1);
  CHECK(n[1] == 2);
  CHECK(n[2] == 1);
  CHECK(mapping::count_detections(c, lab, 3, {}, 2.0f) == std::vector<uint32_t>{0, 0, 0});
}

TEST_CASE("Map triangles join only instances the query stages find in enough mapping scans") {
  mapping::MapBuildConfig all = single_tile();
  all.triangle_min_detections = 0;
  all.scan_triangles = 0;  // the apex-K triangles alone (the scans' views add their own, tested below)
  const Built full = build(all, Eigen::Vector3d::Zero());
  REQUIRE(full.build == Status::Ok);
  CHECK(full.stats.triangle_instances == full.stats.instances);
  mapping::MapBuildConfig some = single_tile();
  some.triangle_min_detections = 2;
  some.scan_triangles = 0;
  const Built det = build(some, Eigen::Vector3d::Zero());
  REQUIRE(det.build == Status::Ok);
  // Same instances and fields; only the triangles' vertex set shrinks.
  CHECK(det.stats.instances == full.stats.instances);
  CHECK(det.stats.scan_detections > 0);
  CHECK(det.stats.triangle_instances <= det.stats.instances);
  CHECK(det.stats.triangles <= full.stats.triangles);
  CHECK(det.stats.triangles > 0);
  // Every triangle vertex is a map instance id among the qualifying instances.
  std::vector<bool> vertex(det.map.counts.instances, false);
  for (uint32_t t = 0; t < det.map.counts.triangles; ++t)
    for (int k = 0; k < 3; ++k) {
      REQUIRE(det.map.triangles[t].v[k] < det.map.counts.instances);
      vertex[det.map.triangles[t].v[k]] = true;
    }
  uint32_t vertices = 0;
  for (bool v : vertex) vertices += v;
  CHECK(vertices <= det.stats.triangle_instances);
}

TEST_CASE("nearest_instances picks the nearest same-label instance within the radius, across cell borders") {
  const float c[12] = {0.9f, 0.9f, 0.0f, 2.2f, 0.9f, 0.0f, 10.0f, 10.0f, 0.0f, 0.9f, 0.9f, 0.0f};
  const uint8_t lab[4] = {3, 3, 3, 4};
  std::vector<mapping::ScanDetection> d(4);
  const float at[4][2] = {{1.8f, 0.9f}, {1.4f, 0.9f}, {10.0f, 12.5f}, {1.0f, 1.0f}};
  const uint8_t dl[4] = {3, 3, 3, 4};
  for (int k = 0; k < 4; ++k) {
    d[k].xyz[0] = at[k][0];
    d[k].xyz[1] = at[k][1];
    d[k].label = dl[k];
  }
  const std::vector<uint32_t> n = mapping::nearest_instances(c, lab, 4, d, 2.0f);
  CHECK(n == std::vector<uint32_t>{1, 0, UINT32_MAX, 3});  // 0.4 vs 0.9 m; 0.5 vs 0.8 m; 2.5 m: none; label 4
}

TEST_CASE("Scan triangles: what the query's builder forms over each scan's instances, once, crowded keys left out") {
  // Eight instances on a line 7 m apart (label 2) and one bush (label 5). Scan 0 sees 0-3 and the bush,
  // scan 1 sees 4-7 (its detections list instance 5 twice and one unassociated detection).
  std::vector<float> c;
  std::vector<uint8_t> lab;
  for (int i = 0; i < 8; ++i) {
    c.insert(c.end(), {7.0f * i, 0.37f * i * i, 0.0f});
    lab.push_back(2);
  }
  c.insert(c.end(), {9.0f, 6.0f, 0.0f});
  lab.push_back(5);
  const std::vector<uint32_t> det = {0, 1, 2, 3, 8, 4, 5, 5, UINT32_MAX, 6, 7};
  const std::vector<uint32_t> begin = {0, 5, 11};
  TriangleConfig query;
  query.neighbours = 3;
  std::vector<Triangle> tris;
  mapping::ScanTriangleStats st;
  REQUIRE(mapping::add_scan_triangles(c.data(), lab.data(), 9, det, begin, query, 0, &tris, &st) == Status::Ok);
  // The reference: the query's own builder over each scan's instances.
  auto reference = [&](const std::vector<uint32_t>& ids) {
    std::vector<float> x;
    std::vector<uint8_t> l;
    for (uint32_t i : ids) {
      x.insert(x.end(), {c[3 * i], c[3 * i + 1], c[3 * i + 2]});
      l.push_back(lab[i]);
    }
    gsf_test::ArenaBuffer buf(TriangleBuilder::required_bytes(query, 16) + 64 * sizeof(Triangle) + 256);
    TriangleBuilder b;
    FixedVector<Triangle> out;
    REQUIRE(b.bind(buf.arena, query, 16) == Status::Ok);
    REQUIRE(out.bind(buf.arena, 64));
    REQUIRE(b.build(x.data(), 3, l.data(), static_cast<uint32_t>(ids.size()), out) == Status::Ok);
    std::vector<std::array<uint32_t, 3>> sets;
    for (uint32_t t = 0; t < out.size(); ++t) {
      std::array<uint32_t, 3> v = {ids[out[t].v[0]], ids[out[t].v[1]], ids[out[t].v[2]]};
      std::sort(v.begin(), v.end());
      sets.push_back(v);
    }
    return sets;
  };
  auto sets_of = [](const std::vector<Triangle>& ts) {
    std::vector<std::array<uint32_t, 3>> sets;
    for (const Triangle& t : ts) {
      std::array<uint32_t, 3> v = {t.v[0], t.v[1], t.v[2]};
      std::sort(v.begin(), v.end());
      sets.push_back(v);
    }
    return sets;
  };
  std::vector<std::array<uint32_t, 3>> want = reference({0, 1, 2, 3, 8});
  const auto second = reference({4, 5, 6, 7});
  want.insert(want.end(), second.begin(), second.end());
  REQUIRE(want.size() >= 6);
  CHECK(sets_of(tris) == want);  // scan order, each scan's builder order
  CHECK(st.scans == 2);
  CHECK(st.added == want.size());
  CHECK(st.largest_scan == 5);
  // No vertex set twice: adding the same scans again adds nothing.
  std::vector<Triangle> again = tris;
  REQUIRE(mapping::add_scan_triangles(c.data(), lab.data(), 9, det, begin, query, 0, &again, &st) == Status::Ok);
  CHECK(again.size() == tris.size());
  CHECK(st.added == 0);
  // A key shared by max_key_share triangles takes no more: with a share of 1 each key appears once.
  std::vector<Triangle> sparse;
  REQUIRE(mapping::add_scan_triangles(c.data(), lab.data(), 9, det, begin, query, 1, &sparse, &st) == Status::Ok);
  std::vector<uint64_t> keys;
  for (const Triangle& t : sparse) keys.push_back(triangle_key(t, query.side_bin));
  std::sort(keys.begin(), keys.end());
  CHECK(std::adjacent_find(keys.begin(), keys.end()) == keys.end());
  CHECK(st.added + st.crowded == want.size());
  CHECK(st.crowded > 0);
}

TEST_CASE("A triangle vertex needs min(min_detections, nearby scans) detections") {
  // Not near any scan: no evidence against it. One nearby scan (a one-scan map): one detection is all it
  // can have. Otherwise min_detections.
  const std::vector<uint32_t> det = {0, 1, 2, 5, 0, 1};
  const std::vector<uint32_t> near = {0, 1, 3, 10, 4, 5};
  CHECK(mapping::triangle_vertices(det, near, 2) == std::vector<uint32_t>{0, 1, 2, 3});
  CHECK(mapping::triangle_vertices(det, near, 1) == std::vector<uint32_t>{0, 1, 2, 3, 5});
  CHECK(mapping::triangle_vertices(det, near, 0) == std::vector<uint32_t>{0, 1, 2, 3, 4, 5});
}

TEST_CASE("A refinement cell's point is the mean of its voxels' centroids, not one of them") {
  // One scan, posed at the origin: a building's points in two voxels of the 1 m cell (10, 10, 1), three
  // at (10.1, 10.1, 1.1) and one at (10.9, 10.1, 1.1). The cell's point is their voxels' mean, 10.5 in x:
  // the first voxel in key order (10.1) put a column's point on its low-x side (docs/map-format.md).
  gsf_test::Cloud scan;
  for (int i = 0; i < 3; ++i) scan.add(10.1f, 10.1f, 1.1f, kitti_from_class(kBuilding));
  scan.add(10.9f, 10.1f, 1.1f, kitti_from_class(kBuilding));
  mapping::MapBuildConfig config;
  mapping::MapBuilder builder(config);
  REQUIRE(builder.add_scan(scan.view(), Eigen::Isometry3d::Identity()) == Status::Ok);
  std::vector<uint64_t> blob;
  size_t bytes = 0;
  REQUIRE(builder.build(&blob, &bytes, nullptr) == Status::Ok);
  MapView map;
  REQUIRE(load_map(blob.data(), bytes, &map) == Status::Ok);
  const RefineLayerView layer = refine_layer_view(map);
  REQUIRE(layer.point_count == 1);
  uint32_t begin = 0, end = 0, hint = 0;
  layer.find(RefineCell{10, 10, 1}, &begin, &end, &hint);
  REQUIRE(end == begin + 1);
  float xyz[3];
  layer.position_in(RefineCell{10, 10, 1}, layer.points[begin], xyz);
  const float quantum = layer.cell / 256.0f;  // refine_layer.h: within half of it per axis
  CHECK(std::fabs(xyz[0] - 10.5f) <= quantum);
  CHECK(std::fabs(xyz[1] - 10.1f) <= quantum);
  CHECK(std::fabs(xyz[2] - 1.1f) <= quantum);
}

}  // namespace test_map_builder
