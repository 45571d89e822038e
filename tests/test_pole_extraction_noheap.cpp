// Zero heap allocations in pole extraction after bind: voxel layer + pole extraction over 50 rounds
// of varied scenes (poles, trunks under canopies, walls, bushes, an empty layer, a capacity overflow),
// and again with the real nuScenes scan among them ([real-data]), counted by the allocation counter. A separate
// executable from test_pole_extraction because the counter replaces operator new for the whole process.
#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "alloc_counter.h"
#include "arena_buffer.h"
#include "gsf/detail/pole_extraction.h"
#include "gsf/detail/voxel_layer.h"
#include "gsf/port/nuscenes.h"
#include "gsf/port/scan_buffer.h"
#include "skip.h"
#include "test_cloud.h"

using namespace gsf;

namespace {

gsf_test::Cloud scene(uint32_t seed) {
  gsf_test::Cloud c;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (float x = -20; x <= 20; x += 0.3f)
    for (float y = -20; y <= 20; y += 0.3f) c.add(x, y, -1.7f, 40u);
  for (int p = 0; p < 8; ++p) {
    const float px = -16 + 4.5f * p + u(rng), py = 6 * u(rng) - 3, h = 2.5f + 3 * u(rng);
    const uint32_t label = p % 2 ? 50u : 70u;
    for (float z = 0; z < h; z += 0.05f)
      for (int k = 0; k < 8; ++k) {
        const float a = 0.785f * k + z;
        c.add(px + 0.15f * std::cos(a), py + 0.15f * std::sin(a), -1.7f + z, label);
      }
    if (label == 70u)
      for (int k = 0; k < 1500; ++k) c.add(px + 4 * u(rng) - 2, py + 4 * u(rng) - 2, -1.7f + h + 2 * u(rng), 70u);
  }
  for (float y = -15; y <= 15; y += 0.1f)
    for (float z = -1.7f; z <= 3; z += 0.1f) c.add(-19.0f, y, z, 50u);
  for (int k = 0; k < 3000; ++k) c.add(10 + 3 * u(rng), 12 + 3 * u(rng), -1.7f + 1.5f * u(rng), 70u);
  return c;
}

// 50 rounds over the synthetic scenes (and, when given, the real scan every 5th round) in a measured
// region; no Catch2 assertion inside it (they may allocate): the tallies are checked after.
struct Rounds {
  uint64_t allocations = 0;
  uint32_t rounds = 0, ok = 0, capacity = 0, instances = 0, real_instances = 0;
};

Rounds run_rounds(const ScanView* real) {
  std::vector<gsf_test::Cloud> scans;
  for (uint32_t i = 0; i < 6; ++i) scans.push_back(scene(300 + i));
  gsf_test::Cloud no_hosts;  // only ground: zero host voxels
  for (float x = -10; x <= 10; x += 0.3f) no_hosts.add(x, 3.0f, -1.7f, 40u);
  scans.push_back(no_hosts);

  VoxelConfig vc;
  PoleConfig pc, few = pc;
  few.max_instances = 2;  // overflows on every synthetic scene
  gsf_test::ArenaBuffer arena(VoxelLayer::required_bytes(vc) + 2 * PoleExtraction::required_bytes(pc, vc.max_voxels));
  VoxelLayer layer;
  PoleExtraction poles, small;
  REQUIRE(layer.bind(arena.arena, vc) == Status::Ok);
  REQUIRE(poles.bind(arena.arena, pc, vc.max_voxels) == Status::Ok);
  REQUIRE(small.bind(arena.arena, few, vc.max_voxels) == Status::Ok);

  Rounds r;
  gsf_test::AllocationScope scope;
  for (uint32_t round = 0; round < 50; ++round) {
    const bool use_real = real != nullptr && round % 5 == 4;
    const ScanView view = use_real ? *real : scans[round % scans.size()].view();
    // Every other round as a single scan in its sensor frame (the beam-column row step runs too).
    const LayerFrame frame = round % 2 ? LayerFrame::Sensor : LayerFrame::World;
    PoleStats ps;
    if (layer.build(view, nullptr) != Status::Ok) continue;
    r.ok += poles.build(layer, &ps, frame) == Status::Ok;
    r.instances += poles.size();
    if (use_real) r.real_instances += poles.size();
    r.capacity += small.build(layer, &ps, frame) == Status::CapacityExceeded;
    ++r.rounds;
  }
  r.allocations = scope.allocations();
  return r;
}

}  // namespace

TEST_CASE("Pole extraction never allocates after bind") {
  const Rounds r = run_rounds(nullptr);
  CHECK(r.allocations == 0);
  CHECK(r.rounds == 50);
  CHECK(r.ok == 50);
  CHECK(r.capacity >= 30);
  CHECK(r.instances >= 200);
}

TEST_CASE("Pole extraction never allocates after bind, on a real nuScenes scan too", "[real-data]") {
  // The real scan is read before the measured region.
  port::OwnedScanBuffer buf(60000, false);
  port::NuScenesLidarsegSource src;
  const std::string root = std::string(GSF_DATA_DIR) + "/nuscenes-lidarseg-samples";
  GSF_SKIP_UNLESS(src.open(root, "0004") == Status::Ok, "no real data at " + root);
  REQUIRE(src.read(10, buf.buffer()) == Status::Ok);
  const ScanView real = buf.buffer().view();
  const Rounds r = run_rounds(&real);
  CHECK(r.allocations == 0);
  CHECK(r.rounds == 50);
  CHECK(r.ok == 50);
  CHECK(r.capacity >= 30);
  CHECK(r.instances >= 200);
  CHECK(r.real_instances >= 10 * 5);
}
