// Zero heap allocations in the scene-graph layers after bind: voxel layer + instance clustering +
// radius gathers over 50 varied scans (clean, with logits, with NaN/Inf points, empty, over capacity,
// and again with the real SemanticKITTI scan among them: [real-data]), counted by the allocation counter.
#include <catch2/catch.hpp>

#include <cmath>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "alloc_counter.h"
#include "arena_buffer.h"
#include "gsf/detail/instance_clustering.h"
#include "gsf/detail/voxel_layer.h"
#include "skip.h"
#include "test_cloud.h"

using namespace gsf;

namespace {

using Scan = gsf_test::Cloud;

Scan street(uint32_t seed, bool with_logits, bool with_bad_points) {
  Scan s;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const float ox = 4 * u(rng), oy = 4 * u(rng);
  for (int p = 0; p < 8; ++p)
    for (int k = 0; k < 150; ++k) {
      const float a = 6.2831853f * u(rng);
      s.add(-25 + 7 * p + 0.1f * std::cos(a) + ox, 7 + 0.1f * std::sin(a) + oy, -1.2f + 5 * u(rng), p % 3 ? 80u : 71u);
    }
  for (int k = 0; k < 600; ++k) s.add(-10 + 4 * u(rng) + ox, -6 + 1.8f * u(rng) + oy, -1.2f + 1.3f * u(rng), 10u);
  // Ground last, so a small layer fills up with it after the objects are in.
  for (float x = -30; x <= 30; x += 0.4f)
    for (float y = -15; y <= 15; y += 0.4f) s.add(x + ox, y + oy, -1.7f, std::fabs(y) < 4 ? 40u : 72u);
  if (with_bad_points)
    for (int k = 0; k < 50; ++k) s.add(k % 2 ? std::nanf("") : INFINITY, 1.0f, 0.0f, k % 3 ? 80u : 4242u);
  if (with_logits) {
    s.logits.assign(s.labels.size() * kNumClasses, -2.0f);
    for (size_t i = 0; i < s.labels.size(); ++i) {
      const int c = class_from_kitti(s.labels[i]);
      if (c >= 0) s.logits[i * kNumClasses + c] = 3.0f + u(rng);
    }
  }
  return s;
}

bool read_real(Scan* s) {
  const std::string root = std::string(GSF_DATA_DIR) + "/semantickitti-samples/sequences/00/";
  std::ifstream fb(root + "velodyne/000052.bin", std::ios::binary | std::ios::ate);
  std::ifstream fl(root + "labels/000052.label", std::ios::binary | std::ios::ate);
  if (!fb || !fl) return false;
  const size_t nb = static_cast<size_t>(fb.tellg());
  s->pts.resize(nb / 4);
  s->labels.resize(nb / 16);
  fb.seekg(0);
  fl.seekg(0);
  fb.read(reinterpret_cast<char*>(s->pts.data()), static_cast<std::streamsize>(s->pts.size() * 4));
  fl.read(reinterpret_cast<char*>(s->labels.data()), static_cast<std::streamsize>(s->labels.size() * 4));
  return static_cast<bool>(fb) && static_cast<bool>(fl);
}

// 50 rounds over `scans` in a measured region; no Catch2 assertion inside it (they may allocate): the
// tallies are checked after, against the work every kind of input must have done.
void check_rounds(const std::vector<Scan>& scans) {
  VoxelConfig vc;
  ClusterConfig cc;
  VoxelConfig tight = vc;  // a second pipeline that overflows every capacity
  tight.max_voxels = 2000;
  tight.max_columns = 64;
  ClusterConfig few = cc;
  few.max_instances = 2;
  gsf_test::ArenaBuffer buf(VoxelLayer::required_bytes(vc) + InstanceClustering::required_bytes(cc, vc.max_voxels) +
                            VoxelLayer::required_bytes(tight) +
                            InstanceClustering::required_bytes(few, tight.max_voxels));
  VoxelLayer layer, small_layer;
  InstanceClustering clusters, small_clusters;
  REQUIRE(layer.bind(buf.arena, vc) == Status::Ok);
  REQUIRE(clusters.bind(buf.arena, cc, vc.max_voxels) == Status::Ok);
  REQUIRE(small_layer.bind(buf.arena, tight) == Status::Ok);
  REQUIRE(small_clusters.bind(buf.arena, few, tight.max_voxels) == Status::Ok);
  static uint32_t gathered[100000];

  uint32_t runs = 0, ok_voxel = 0, invalid = 0, capacity = 0, instances = 0, gather_hits = 0;
  gsf_test::AllocationScope scope;
  for (uint32_t round = 0; round < 50; ++round) {
    const Scan& s = scans[round % scans.size()];
    VoxelStats vs;
    ClusterStats cs;
    const Status a = layer.build(s.view(), &vs);
    ok_voxel += a == Status::Ok;
    invalid += a == Status::InvalidInput;
    if (a == Status::Ok && clusters.build(layer, &cs) == Status::Ok) {
      instances += clusters.size();
      for (uint32_t k = 0; k < clusters.size(); ++k)
        gather_hits += layer.gather_within(clusters.instance(k).centroid, 8.0f, k % 2 == 0, gathered, 100000);
    }
    const Status b = small_layer.build(s.view(), &vs);
    if (b == Status::CapacityExceeded) {
      capacity += small_clusters.build(small_layer, &cs) == Status::CapacityExceeded;
      const float origin[3] = {0, 0, 0};
      gather_hits += small_layer.gather_within(origin, 1e9f, false, gathered, 100000);
    }
    ++runs;
  }
  const uint64_t allocations = scope.allocations();
  CHECK(allocations == 0);
  CHECK(runs == 50);
  // The region did real work on every kind of input.
  const uint32_t per_cycle = static_cast<uint32_t>(scans.size());
  CHECK(invalid == (50 + per_cycle - 1 - 8) / per_cycle);  // the empty scan, once per cycle
  CHECK(ok_voxel == 50 - invalid);
  CHECK(capacity >= 40);  // every synthetic round overflows voxels, columns and instances
  CHECK(instances > 200);
  CHECK(gather_hits > 10000);
}

// All inputs are prepared (heap) before the measured region.
std::vector<Scan> synthetic_scans() {
  std::vector<Scan> scans;
  for (uint32_t i = 0; i < 8; ++i) scans.push_back(street(100 + i, i % 2 == 1, i % 4 == 2));
  scans.emplace_back();  // empty scan: InvalidInput
  return scans;
}

}  // namespace

TEST_CASE("Voxel layer, clustering and gathers never allocate after bind") {
  check_rounds(synthetic_scans());

  // The counter is live in this executable (negative control).
  gsf_test::AllocationScope control;
  std::vector<int> grow(100, 1);
  gsf_test::escape(grow.data());
  CHECK(control.allocations() > 0);
}

TEST_CASE("Voxel layer, clustering and gathers never allocate after bind, on a real SemanticKITTI scan too",
          "[real-data]") {
  std::vector<Scan> scans = synthetic_scans();
  Scan real;
  GSF_SKIP_UNLESS(read_real(&real), "no real data at " + std::string(GSF_DATA_DIR) + "/semantickitti-samples");
  scans.push_back(real);
  check_rounds(scans);
}
