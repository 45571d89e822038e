// Voxel layer and instance clustering on synthetic scans with known answers, bad input, capacity,
// invariance, and a real SemanticKITTI scan.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <random>
#include <vector>

#include "arena_buffer.h"
#include "gsf/detail/instance_clustering.h"
#include "gsf/detail/voxel_layer.h"
#include "skip.h"
#include "test_cloud.h"

namespace test_scene_graph {

using namespace gsf;

namespace {

using Cloud = gsf_test::Cloud;

// Ground (road / terrain), a pole at (10, 0), a trunk at (0, 12), a car box at (-10, -5).
Cloud synthetic_scene(float dx = 0, float dy = 0) {
  Cloud c;
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0, 1);
  for (float x = -30; x <= 30; x += 0.3f)
    for (float y = -30; y <= 30; y += 0.3f) c.add(x + dx, y + dy, -1.7f, std::fabs(y) < 5 ? 40u : 72u);
  for (int k = 0; k < 400; ++k) {
    const float a = 6.2831853f * u(rng), z = -1.7f + 6.0f * u(rng);
    c.add(10 + 0.1f * std::cos(a) + dx, 0.1f * std::sin(a) + dy, z, 80u);
  }
  for (int k = 0; k < 300; ++k) {
    const float a = 6.2831853f * u(rng), z = -1.7f + 3.0f * u(rng);
    c.add(0.25f * std::cos(a) + dx, 12 + 0.25f * std::sin(a) + dy, z, 71u);
  }
  for (int k = 0; k < 800; ++k) c.add(-12 + 4 * u(rng) + dx, -6 + 1.8f * u(rng) + dy, -1.4f + 1.2f * u(rng), 10u);
  return c;
}

using Buffer = gsf_test::ArenaBuffer;

}  // namespace

TEST_CASE("Voxel layer + clustering recover the synthetic objects") {
  VoxelConfig vc;
  ClusterConfig cc;
  Buffer buf(VoxelLayer::required_bytes(vc) + InstanceClustering::required_bytes(cc, vc.max_voxels) + 64);
  VoxelLayer layer;
  InstanceClustering clusters;
  REQUIRE(layer.bind(buf.arena, vc) == Status::Ok);
  REQUIRE(clusters.bind(buf.arena, cc, vc.max_voxels) == Status::Ok);
  const Cloud c = synthetic_scene();
  VoxelStats vs;
  REQUIRE(layer.build(c.view(), &vs) == Status::Ok);
  CHECK(vs.points_in == c.labels.size());
  CHECK(vs.voxels == layer.size());
  CHECK(vs.out_of_range > 0);  // ground corners beyond... within 2.5 m of the sensor
  ClusterStats cs;
  REQUIRE(clusters.build(layer, &cs) == Status::Ok);
  REQUIRE(clusters.size() == 3);
  int seen = 0;
  for (uint32_t i = 0; i < clusters.size(); ++i) {
    const Instance& in = clusters.instance(i);
    if (in.label == kPole) {
      CHECK(std::hypot(in.centroid[0] - 10, in.centroid[1]) < 0.1f);
      seen |= 1;
    }
    if (in.label == kTrunk) {
      CHECK(std::hypot(in.centroid[0], in.centroid[1] - 12) < 0.1f);
      seen |= 2;
    }
    if (in.label == kCar) {
      CHECK(std::hypot(in.centroid[0] + 10, in.centroid[1] + 5.1f) < 0.3f);
      seen |= 4;
    }
    CHECK(in.stability == stability_weight(in.label));
  }
  CHECK(seen == 7);
  // Voxel labels are the majority class: every pole voxel is labelled pole.
  const float pole_top[3] = {10.0f, 0.0f, 3.0f};
  const uint32_t v = layer.find(pole_top);
  REQUIRE(v != UINT32_MAX);
  CHECK(layer.voxel(v).label == kPole);
  CHECK(layer.voxel(v).prob[kPole] == Approx(1.0f));
}

TEST_CASE("Logits path gives the same labels as one-hot on clean data") {
  VoxelConfig vc;
  Buffer buf(2 * VoxelLayer::required_bytes(vc) + 64);
  VoxelLayer a, b;
  REQUIRE(a.bind(buf.arena, vc) == Status::Ok);
  REQUIRE(b.bind(buf.arena, vc) == Status::Ok);
  const Cloud c = synthetic_scene();
  std::vector<float> logits(c.labels.size() * kNumClasses, -3.0f);
  for (size_t i = 0; i < c.labels.size(); ++i) logits[i * kNumClasses + class_from_kitti(c.labels[i])] = 5.0f;
  ScanView with = c.view();
  with.logits = logits.data();
  with.logit_dim = kNumClasses;
  REQUIRE(a.build(c.view(), nullptr) == Status::Ok);
  REQUIRE(b.build(with, nullptr) == Status::Ok);
  REQUIRE(a.size() == b.size());
  uint32_t compared = 0;
  for (uint32_t i = 0; i < a.size(); ++i) {
    // A voxel split exactly between two classes is a tie either way; compare the rest.
    float p[kNumClasses];
    std::memcpy(p, a.voxel(i).prob, sizeof(p));
    std::sort(p, p + kNumClasses);
    if (p[kNumClasses - 1] - p[kNumClasses - 2] < 1e-3f) continue;
    CHECK(a.voxel(i).label == b.voxel(i).label);
    ++compared;
  }
  CHECK(compared > a.size() * 9 / 10);
}

TEST_CASE("Bad points are counted and skipped; empty scans and bad views are rejected") {
  VoxelConfig vc;
  Buffer buf(VoxelLayer::required_bytes(vc) + 64);
  VoxelLayer layer;
  REQUIRE(layer.bind(buf.arena, vc) == Status::Ok);
  Cloud c;
  c.add(5, 0, 0, 80);
  c.add(std::nanf(""), 0, 0, 80);
  c.add(INFINITY, 1, 0, 80);
  c.add(0.5f, 0, 0, 80);  // inside min_range
  c.add(500, 0, 0, 80);   // beyond max_range
  c.add(6, 0, 0, 12345);  // unknown label id
  c.add(7, 0, 0, 0);      // unlabeled: ignored
  VoxelStats st;
  REQUIRE(layer.build(c.view(), &st) == Status::Ok);
  CHECK(st.non_finite == 2);
  CHECK(st.out_of_range == 2);
  CHECK(st.unknown_label == 1);
  CHECK(st.ignored == 1);
  CHECK(layer.size() == 1);
  Cloud empty;
  CHECK(layer.build(empty.view(), nullptr) == Status::InvalidInput);
  Cloud all_bad;
  all_bad.add(std::nanf(""), 0, 0, 80);
  CHECK(layer.build(all_bad.view(), nullptr) == Status::InvalidInput);
  ScanView no_labels = c.view();
  no_labels.labels = nullptr;
  CHECK(layer.build(no_labels, nullptr) == Status::InvalidArgument);
  REQUIRE(layer.build(c.view(), nullptr) == Status::Ok);  // still usable
  CHECK(layer.size() == 1);
}

TEST_CASE("Capacity overflow is reported, deterministic, and the layer stays usable") {
  VoxelConfig vc;
  vc.max_voxels = 500;
  ClusterConfig cc;
  cc.max_instances = 2;
  Buffer buf(VoxelLayer::required_bytes(vc) + InstanceClustering::required_bytes(cc, vc.max_voxels) + 64);
  VoxelLayer layer;
  InstanceClustering clusters;
  REQUIRE(layer.bind(buf.arena, vc) == Status::Ok);
  REQUIRE(clusters.bind(buf.arena, cc, vc.max_voxels) == Status::Ok);
  const Cloud c = synthetic_scene();
  VoxelStats st;
  CHECK(layer.build(c.view(), &st) == Status::CapacityExceeded);
  CHECK(layer.size() == 500);
  CHECK(st.dropped_points > 0);
  std::vector<Voxel> first(layer.voxels(), layer.voxels() + layer.size());
  CHECK(layer.build(c.view(), nullptr) == Status::CapacityExceeded);
  CHECK(std::memcmp(first.data(), layer.voxels(), first.size() * sizeof(Voxel)) == 0);
  // Instance capacity: keep the largest two.
  VoxelConfig big;
  Buffer buf2(VoxelLayer::required_bytes(big) + InstanceClustering::required_bytes(cc, big.max_voxels) + 64);
  VoxelLayer l2;
  InstanceClustering c2;
  REQUIRE(l2.bind(buf2.arena, big) == Status::Ok);
  REQUIRE(c2.bind(buf2.arena, cc, big.max_voxels) == Status::Ok);
  REQUIRE(l2.build(c.view(), nullptr) == Status::Ok);
  ClusterStats cs;
  CHECK(c2.build(l2, &cs) == Status::CapacityExceeded);
  REQUIRE(c2.size() == 2);
  CHECK(cs.dropped_capacity == 1);
  for (uint32_t i = 0; i < 2; ++i) CHECK(c2.instance(i).label != kTrunk);  // the smallest one went
}

TEST_CASE("Translating the scan translates the instances; gather_within matches brute force") {
  VoxelConfig vc;
  ClusterConfig cc;
  Buffer buf(2 * (VoxelLayer::required_bytes(vc) + InstanceClustering::required_bytes(cc, vc.max_voxels)) + 64);
  VoxelLayer l1, l2;
  InstanceClustering c1, c2;
  REQUIRE(l1.bind(buf.arena, vc) == Status::Ok);
  REQUIRE(l2.bind(buf.arena, vc) == Status::Ok);
  REQUIRE(c1.bind(buf.arena, cc, vc.max_voxels) == Status::Ok);
  REQUIRE(c2.bind(buf.arena, cc, vc.max_voxels) == Status::Ok);
  const Cloud a = synthetic_scene(), b = synthetic_scene(0.8f, -2.4f);  // multiples of the voxel size
  REQUIRE(l1.build(a.view(), nullptr) == Status::Ok);
  REQUIRE(l2.build(b.view(), nullptr) == Status::Ok);
  REQUIRE(c1.build(l1, nullptr) == Status::Ok);
  REQUIRE(c2.build(l2, nullptr) == Status::Ok);
  REQUIRE(c1.size() == c2.size());
  for (uint32_t i = 0; i < c1.size(); ++i) {
    bool found = false;
    for (uint32_t j = 0; j < c2.size(); ++j)
      found = found || (c1.instance(i).label == c2.instance(j).label &&
                        std::hypot(c1.instance(i).centroid[0] + 0.8f - c2.instance(j).centroid[0],
                                   c1.instance(i).centroid[1] - 2.4f - c2.instance(j).centroid[1]) < 0.05f);
    CHECK(found);
  }
  const float center[3] = {3.0f, -2.0f, 0.0f};
  for (bool horizontal : {true, false}) {
    std::vector<uint32_t> got(l1.size());
    uint32_t total = 0;
    const uint32_t n = l1.gather_within(center, 7.5f, horizontal, got.data(), l1.size(), &total);
    CHECK(n == total);
    std::vector<uint32_t> brute;
    for (uint32_t i = 0; i < l1.size(); ++i) {
      const float* p = l1.voxel(i).centroid;
      const float dz = horizontal ? 0.0f : p[2] - center[2];
      if ((p[0] - 3) * (p[0] - 3) + (p[1] + 2) * (p[1] + 2) + dz * dz <= 7.5f * 7.5f) brute.push_back(i);
    }
    got.resize(n);
    std::sort(got.begin(), got.end());
    CHECK(got == brute);
  }
}

TEST_CASE("Real SemanticKITTI scan: instances in a plausible range", "[real-data]") {
  const std::string root = std::string(GSF_DATA_DIR) + "/semantickitti-samples/sequences/00/";
  std::ifstream fb(root + "velodyne/000052.bin", std::ios::binary), fl(root + "labels/000052.label", std::ios::binary);
  GSF_SKIP_UNLESS(fb && fl, "no real data at " + root + "velodyne/000052.bin");
  std::vector<float> pts((std::istreambuf_iterator<char>(fb)), {});
  (void)pts;
  fb.clear();
  fb.seekg(0, std::ios::end);
  const size_t nb = static_cast<size_t>(fb.tellg());
  fb.seekg(0);
  std::vector<float> xyzi(nb / 4);
  fb.read(reinterpret_cast<char*>(xyzi.data()), static_cast<std::streamsize>(nb));
  std::vector<uint32_t> labels(nb / 16);
  fl.read(reinterpret_cast<char*>(labels.data()), static_cast<std::streamsize>(labels.size() * 4));
  REQUIRE(fl.gcount() == static_cast<std::streamsize>(labels.size() * 4));
  // Ground-truth instances of our instance classes.
  std::vector<uint32_t> gt;
  for (uint32_t l : labels) {
    const int c = class_from_kitti(l & 0xFFFF);
    if ((l >> 16) && c >= 0 && (kDefaultInstanceClasses & class_bit(c)) &&
        std::find(gt.begin(), gt.end(), l) == gt.end())
      gt.push_back(l);
  }
  VoxelConfig vc;
  ClusterConfig cc;
  Buffer buf(VoxelLayer::required_bytes(vc) + InstanceClustering::required_bytes(cc, vc.max_voxels) + 64);
  VoxelLayer layer;
  InstanceClustering clusters;
  REQUIRE(layer.bind(buf.arena, vc) == Status::Ok);
  REQUIRE(clusters.bind(buf.arena, cc, vc.max_voxels) == Status::Ok);
  ScanView v;
  v.points = xyzi.data();
  v.labels = labels.data();
  v.count = static_cast<uint32_t>(labels.size());
  VoxelStats st;
  REQUIRE(layer.build(v, &st) == Status::Ok);
  CHECK(st.unknown_label == 0);
  REQUIRE(clusters.build(layer, nullptr) == Status::Ok);
  INFO("clustered " << clusters.size() << " instances, ground truth has " << gt.size());
  CHECK(gt.size() >= 5);
  CHECK(clusters.size() >= gt.size() / 2);
  CHECK(clusters.size() <= gt.size() * 3 + 10);
}

}  // namespace test_scene_graph
