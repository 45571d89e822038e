// The object layer: instances clustered from the voxel layer. Known answers on synthetic scenes
// (an instance is exactly its object's points, so its centroid is their mean), tolerance / size /
// extent rules, capacity overflow, rigid-motion invariance, determinism, map-scale reuse, and a real
// SemanticKITTI scan against its ground-truth car instance ids.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "arena_buffer.h"
#include "gsf/detail/instance_clustering.h"
#include "gsf/detail/voxel_layer.h"
#include "skip.h"

namespace test_instance_clustering {

using namespace gsf;
using gsf_test::ArenaBuffer;

namespace {

struct Cloud {
  std::vector<float> pts;
  std::vector<uint32_t> labels;
  std::vector<int> object;  // ground-truth object id per point (-1: background)
  void add(float x, float y, float z, uint32_t label, int obj = -1) {
    pts.insert(pts.end(), {x, y, z, 0.0f});
    labels.push_back(label);
    object.push_back(obj);
  }
  ScanView view() const {
    ScanView v;
    v.points = pts.data();
    v.labels = labels.data();
    v.count = static_cast<uint32_t>(labels.size());
    return v;
  }
  // Mean of one object's points (double), and its size.
  uint32_t mean(int obj, double m[3]) const {
    uint32_t n = 0;
    m[0] = m[1] = m[2] = 0;
    for (size_t i = 0; i < object.size(); ++i)
      if (object[i] == obj) {
        for (int k = 0; k < 3; ++k) m[k] += pts[4 * i + k];
        ++n;
      }
    for (int k = 0; k < 3; ++k) m[k] /= n;
    return n;
  }
  Cloud moved(float yaw, float tx, float ty, float tz) const {
    Cloud c = *this;
    const float cs = std::cos(yaw), sn = std::sin(yaw);
    for (size_t i = 0; i < labels.size(); ++i) {
      const float x = pts[4 * i], y = pts[4 * i + 1];
      c.pts[4 * i] = cs * x - sn * y + tx;
      c.pts[4 * i + 1] = sn * x + cs * y + ty;
      c.pts[4 * i + 2] = pts[4 * i + 2] + tz;
    }
    return c;
  }
};

void add_pole(Cloud& c, std::mt19937& rng, float x, float y, float height, int n, int obj, float radius = 0.1f,
              uint32_t label = 80) {
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int k = 0; k < n; ++k) {
    const float a = 6.2831853f * u(rng);
    c.add(x + radius * std::cos(a), y + radius * std::sin(a), -1.2f + height * u(rng), label, obj);
  }
}

// Ground at z = -1.7 (road |y| < 5, terrain elsewhere); objects start at z = -1.2, a voxel layer above
// the ground's cells, so each object's voxels hold only its own points.
enum Obj { kPoleObj = 0, kTrunkObj, kCarObj, kSignObj };
Cloud street_scene() {
  Cloud c;
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (float x = -30; x <= 30; x += 0.3f)
    for (float y = -30; y <= 30; y += 0.3f) c.add(x, y, -1.7f, std::fabs(y) < 5 ? 40u : 72u);
  add_pole(c, rng, 10, 0, 6.0f, 400, kPoleObj);
  add_pole(c, rng, 0, 12, 3.0f, 300, kTrunkObj, 0.25f, 71u);
  for (int k = 0; k < 800; ++k) c.add(-12 + 4 * u(rng), -6 + 1.8f * u(rng), -1.2f + 1.2f * u(rng), 10u, kCarObj);
  for (int k = 0; k < 150; ++k) c.add(5.7f + 0.6f * u(rng), -8.0f, 1.5f + 0.6f * u(rng), 81u, kSignObj);
  return c;
}

struct Scene {
  VoxelConfig vc;
  ClusterConfig cc;
  ArenaBuffer buf;
  VoxelLayer layer;
  InstanceClustering clusters;
  VoxelStats vs;
  ClusterStats cs;
  Scene(const VoxelConfig& v, const ClusterConfig& c)
      : vc(v), cc(c), buf(VoxelLayer::required_bytes(v) + InstanceClustering::required_bytes(c, v.max_voxels)) {
    REQUIRE(layer.bind(buf.arena, vc) == Status::Ok);
    REQUIRE(clusters.bind(buf.arena, cc, vc.max_voxels) == Status::Ok);
  }
  Status run(const Cloud& cloud) {
    const Status s = layer.build(cloud.view(), &vs);
    if (s != Status::Ok && s != Status::CapacityExceeded) return s;
    return clusters.build(layer, &cs);
  }
  // Index of the instance with this label nearest to p, or -1.
  int nearest(uint8_t label, const double p[3], double* dist) const {
    int best = -1;
    *dist = 1e9;
    for (uint32_t i = 0; i < clusters.size(); ++i) {
      const Instance& in = clusters.instance(i);
      if (in.label != label) continue;
      const double d = std::sqrt((in.centroid[0] - p[0]) * (in.centroid[0] - p[0]) +
                                 (in.centroid[1] - p[1]) * (in.centroid[1] - p[1]) +
                                 (in.centroid[2] - p[2]) * (in.centroid[2] - p[2]));
      if (d < *dist) {
        *dist = d;
        best = static_cast<int>(i);
      }
    }
    return best;
  }
};

}  // namespace

TEST_CASE("Each synthetic object becomes one instance whose centroid is the mean of its points") {
  Scene s{VoxelConfig(), ClusterConfig()};
  const Cloud c = street_scene();
  REQUIRE(s.run(c) == Status::Ok);
  REQUIRE(s.clusters.size() == 4);
  CHECK(s.cs.instances == 4);
  CHECK(s.cs.rejected_extent == 0);
  const uint8_t labels[4] = {kPole, kTrunk, kCar, kTrafficSign};
  for (int obj = 0; obj < 4; ++obj) {
    double m[3], d = 0;
    const uint32_t n = c.mean(obj, m);
    const int k = s.nearest(labels[obj], m, &d);
    INFO("object " << obj);
    REQUIRE(k >= 0);
    CHECK(d < 1e-3);  // float accumulation only
    const Instance& in = s.clusters.instance(static_cast<uint32_t>(k));
    CHECK(in.point_count == n);
    CHECK(in.stability == stability_weight(in.label));
  }
  // Against the geometry: pole axis at (10, 0), trunk at (0, 12).
  double d = 0;
  const double pole_axis[3] = {10, 0, 1.8}, trunk_axis[3] = {0, 12, 0.3};
  const Instance& pole = s.clusters.instance(static_cast<uint32_t>(s.nearest(kPole, pole_axis, &d)));
  CHECK(std::hypot(pole.centroid[0] - 10.0, pole.centroid[1]) < 0.03);
  CHECK((pole.extent[2] > 5.6f && pole.extent[2] < 6.8f));
  CHECK(pole.extent[0] < 1.0f);
  const Instance& trunk = s.clusters.instance(static_cast<uint32_t>(s.nearest(kTrunk, trunk_axis, &d)));
  CHECK(std::hypot(trunk.centroid[0], trunk.centroid[1] - 12.0) < 0.03);

  // Voxel -> instance map agrees with the instances.
  const uint32_t* vi = s.clusters.voxel_instance();
  std::vector<uint32_t> voxels(4, 0), points(4, 0);
  for (uint32_t v = 0; v < s.layer.size(); ++v) {
    if (vi[v] == UINT32_MAX) {
      CHECK(!(kDefaultInstanceClasses & class_bit(s.layer.voxel(v).label)));
      continue;
    }
    REQUIRE(vi[v] < 4);
    CHECK(s.layer.voxel(v).label == s.clusters.instance(vi[v]).label);
    ++voxels[vi[v]];
    points[vi[v]] += s.layer.voxel(v).count;
  }
  for (uint32_t k = 0; k < 4; ++k) {
    CHECK(voxels[k] == s.clusters.instance(k).voxel_count);
    CHECK(points[k] == s.clusters.instance(k).point_count);
  }
  // Discovery order = order of the first voxel.
  for (uint32_t k = 1; k < 4; ++k) CHECK(s.clusters.instance(k - 1).first_voxel < s.clusters.instance(k).first_voxel);
}

TEST_CASE("Tolerance joins and splits; classes never mix; size and extent rules reject blobs") {
  Scene s{VoxelConfig(), ClusterConfig()};
  std::mt19937 rng(4);
  Cloud near_pair, far_pair, pole_and_sign, blobs;
  add_pole(near_pair, rng, 10.0f, 0, 4.0f, 300, 0);
  add_pole(near_pair, rng, 10.5f, 0, 4.0f, 300, 1);  // axes 0.5 m apart: within the 0.6 m tolerance
  REQUIRE(s.run(near_pair) == Status::Ok);
  CHECK(s.clusters.size() == 1);
  add_pole(far_pair, rng, 10.0f, 0, 4.0f, 300, 0);
  add_pole(far_pair, rng, 12.0f, 0, 4.0f, 300, 1);
  REQUIRE(s.run(far_pair) == Status::Ok);
  CHECK(s.clusters.size() == 2);
  add_pole(pole_and_sign, rng, 10.0f, 0, 4.0f, 300, 0);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int k = 0; k < 150; ++k) pole_and_sign.add(9.5f + u(rng), 0.15f, 2.0f + 0.6f * u(rng), 81u, 1);  // touching
  REQUIRE(s.run(pole_and_sign) == Status::Ok);
  REQUIRE(s.clusters.size() == 2);
  CHECK(s.clusters.instance(0).label != s.clusters.instance(1).label);

  // A 5 m wide "pole" wall (extent) and a one-voxel pole fragment (min_voxels) are rejected.
  for (int k = 0; k < 2000; ++k) blobs.add(-15 + 5 * u(rng), 8.0f, -1.2f + 3 * u(rng), 80u);
  for (int k = 0; k < 5; ++k) blobs.add(20.05f + 0.01f * k, 0.05f, 0.05f, 80u);
  add_pole(blobs, rng, 10.0f, 0, 4.0f, 300, 0);
  REQUIRE(s.run(blobs) == Status::Ok);
  CHECK(s.cs.components == 3);
  CHECK(s.cs.rejected_extent == 1);
  CHECK(s.cs.rejected_small == 1);
  REQUIRE(s.clusters.size() == 1);
  CHECK(std::fabs(s.clusters.instance(0).centroid[0] - 10.0f) < 0.05f);

  // The rules come from the config.
  ClusterConfig loose;
  loose.min_voxels[kPole] = 1;
  loose.max_extent[kPole] = 10.0f;
  loose.instance_classes = class_bit(kPole);
  Scene t{VoxelConfig(), loose};
  REQUIRE(t.run(blobs) == Status::Ok);
  CHECK(t.clusters.size() == 3);
  const Cloud street = street_scene();
  REQUIRE(t.run(street) == Status::Ok);
  REQUIRE(t.clusters.size() == 1);  // only the pole class forms instances
  CHECK(t.clusters.instance(0).label == kPole);
}

TEST_CASE("A far pole hit by every few beams is one instance across the vertical gaps; a larger gap splits it") {
  // A pole 40 m away seen by beams 1 deg apart: one voxel every 0.7 m of its height, two points each.
  auto sparse_pole = [](Cloud& c, float x, float y, float z0, int beams, int obj) {
    for (int k = 0; k < beams; ++k)
      for (int p = 0; p < 2; ++p) c.add(x + 0.05f * p, y, z0 + 0.7f * k, 80u, obj);
  };
  Cloud one, split, side_by_side;
  sparse_pole(one, 40.0f, 0.0f, -1.2f, 6, 0);
  Scene s{VoxelConfig(), ClusterConfig()};
  REQUIRE(ClusterConfig().vertical_tolerance[kPole] == 2.0f);
  REQUIRE(s.run(one) == Status::Ok);
  REQUIRE(s.clusters.size() == 1);
  double m[3], d = 0;
  one.mean(0, m);
  REQUIRE(s.nearest(kPole, m, &d) == 0);
  CHECK(d < 1e-3);
  CHECK(s.clusters.instance(0).voxel_count == 6);

  // The same pole with the spherical tolerance alone falls apart into six one-voxel pieces, all too small.
  ClusterConfig spherical;
  spherical.vertical_tolerance[kPole] = 0.0f;
  Scene t{VoxelConfig(), spherical};
  REQUIRE(t.run(one) == Status::Ok);
  CHECK(t.clusters.size() == 0);
  CHECK(t.cs.components == 6);
  CHECK(t.cs.rejected_small == 6);

  // A 2.8 m gap (four beams missing, e.g. a van in front) is beyond 2 m: two instances.
  sparse_pole(split, 40.0f, 0.0f, -1.2f, 3, 0);
  sparse_pole(split, 40.0f, 0.0f, 3.0f, 3, 1);
  REQUIRE(s.run(split) == Status::Ok);
  CHECK(s.clusters.size() == 2);
  // Across, the tolerance stays 0.6 m: two poles 1 m apart stay two.
  sparse_pole(side_by_side, 40.0f, 0.0f, -1.2f, 6, 0);
  sparse_pole(side_by_side, 40.0f, 1.0f, -1.2f, 6, 1);
  REQUIRE(s.run(side_by_side) == Status::Ok);
  CHECK(s.clusters.size() == 2);

  // A negative or huge vertical tolerance is refused at bind.
  ClusterConfig bad;
  bad.vertical_tolerance[kTrunk] = -1.0f;
  ArenaBuffer buf(InstanceClustering::required_bytes(ClusterConfig(), 1000));
  InstanceClustering c;
  CHECK(c.bind(buf.arena, bad, 1000) == Status::InvalidArgument);
  bad.vertical_tolerance[kTrunk] = 10.0f;
  CHECK(c.bind(buf.arena, bad, 1000) == Status::InvalidArgument);
}

TEST_CASE("Clustering's cell search finds exactly the components of the all-pairs connection rule") {
  // Random poles (cylinder rule) and cars (sphere rule, 1 m) at random positions and densities: the
  // components clustering reports equal those of joining every pair of same-label voxels within the
  // rule (union-find over all pairs), so the cells the search skips never hold a neighbour.
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  ClusterConfig cc;
  for (int c = 0; c < kNumClasses; ++c) {
    cc.min_voxels[c] = 1;
    cc.max_extent[c] = 100.0f;
  }
  cc.max_instances = 4000;
  for (int trial = 0; trial < 6; ++trial) {
    Cloud cloud;
    const int n = 400 + 300 * trial;
    const float span = 6.0f + 2.0f * float(trial);
    for (int k = 0; k < n; ++k) {
      const bool pole = u(rng) < 0.6f;
      cloud.add(-3.0f + span * u(rng), 20.0f + span * u(rng), -1.0f + 4.0f * u(rng), pole ? 80u : 10u);
    }
    VoxelConfig vc;
    vc.min_range = 0.0f;
    Scene s{vc, cc};
    REQUIRE(s.run(cloud) == Status::Ok);
    const uint32_t nv = s.layer.size();
    std::vector<uint32_t> parent(nv);
    for (uint32_t i = 0; i < nv; ++i) parent[i] = i;
    auto root = [&](uint32_t i) {
      while (parent[i] != i) i = parent[i] = parent[parent[i]];
      return i;
    };
    for (uint32_t i = 0; i < nv; ++i)
      for (uint32_t j = i + 1; j < nv; ++j) {
        const Voxel &a = s.layer.voxel(i), &b = s.layer.voxel(j);
        if (a.label != b.label || !(kDefaultInstanceClasses & class_bit(a.label))) continue;
        const float ex = a.centroid[0] - b.centroid[0], ey = a.centroid[1] - b.centroid[1],
                    ez = a.centroid[2] - b.centroid[2];
        const float tol = cc.tolerance[a.label], vtol = cc.vertical_tolerance[a.label];
        const bool joined = vtol > tol ? (ex * ex + ey * ey <= tol * tol && std::fabs(ez) <= vtol)
                                       : (ex * ex + ey * ey + ez * ez <= tol * tol);
        if (joined) parent[root(i)] = root(j);
      }
    const uint32_t* vi = s.clusters.voxel_instance();
    INFO("trial " << trial << ": " << nv << " voxels, " << s.clusters.size() << " instances");
    uint32_t mismatches = 0;
    for (uint32_t i = 0; i < nv; ++i)
      for (uint32_t j = i + 1; j < nv; ++j) {
        if (vi[i] == UINT32_MAX || vi[j] == UINT32_MAX) continue;
        mismatches += (vi[i] == vi[j]) != (root(i) == root(j));
      }
    CHECK(mismatches == 0);
    CHECK(s.clusters.size() > 10);
  }
}

TEST_CASE("Instance overflow keeps the largest by point count, deterministically; the next scan is fine") {
  ClusterConfig cc;
  cc.max_instances = 5;
  Scene s{VoxelConfig(), cc};
  std::mt19937 rng(8);
  Cloud many;
  // Poles of distinct sizes in an order that is not sorted by size.
  const int sizes[12] = {120, 300, 90, 250, 60, 310, 200, 80, 290, 100, 270, 70};
  for (int i = 0; i < 12; ++i) add_pole(many, rng, -20.0f + 4 * i, 6.0f, 4.0f, sizes[i], i);
  REQUIRE(s.run(many) == Status::CapacityExceeded);
  CHECK(s.cs.components == 12);
  CHECK(s.cs.dropped_capacity == 7);
  REQUIRE(s.clusters.size() == 5);
  const int kept[5] = {1, 3, 5, 8, 10};  // the five largest, in discovery (scan) order
  for (int k = 0; k < 5; ++k) {
    const Instance& in = s.clusters.instance(static_cast<uint32_t>(k));
    CHECK(in.point_count == static_cast<uint32_t>(sizes[kept[k]]));
    CHECK(std::fabs(in.centroid[0] - (-20.0f + 4 * kept[k])) < 0.05f);
  }
  // Dropped components map to no instance.
  uint32_t assigned = 0;
  for (uint32_t v = 0; v < s.layer.size(); ++v) assigned += s.clusters.voxel_instance()[v] != UINT32_MAX;
  uint32_t kept_voxels = 0;
  for (uint32_t k = 0; k < 5; ++k) kept_voxels += s.clusters.instance(k).voxel_count;
  CHECK(assigned == kept_voxels);

  const std::vector<Instance> first(s.clusters.instances(), s.clusters.instances() + 5);
  const std::vector<uint32_t> first_map(s.clusters.voxel_instance(), s.clusters.voxel_instance() + s.layer.size());
  REQUIRE(s.run(many) == Status::CapacityExceeded);
  CHECK(std::memcmp(first.data(), s.clusters.instances(), sizeof(Instance) * 5) == 0);
  CHECK(std::memcmp(first_map.data(), s.clusters.voxel_instance(), sizeof(uint32_t) * first_map.size()) == 0);

  // Ties go to the earlier discovered component.
  ClusterConfig one;
  one.max_instances = 1;
  Scene t{VoxelConfig(), one};
  Cloud tie;
  std::mt19937 r1(1), r2(1);
  add_pole(tie, r1, 15.0f, 0.0f, 4.0f, 200, 0);
  add_pole(tie, r2, 5.0f, 0.0f, 4.0f, 200, 1);  // same shape and size, discovered second
  REQUIRE(t.run(tie) == Status::CapacityExceeded);
  REQUIRE(t.clusters.size() == 1);
  CHECK(std::fabs(t.clusters.instance(0).centroid[0] - 15.0f) < 0.05f);

  // Under capacity again: Ok and complete.
  Cloud few;
  for (int i = 0; i < 3; ++i) add_pole(few, rng, 8.0f, -6.0f + 6 * i, 4.0f, 150, i);
  REQUIRE(s.run(few) == Status::Ok);
  CHECK(s.clusters.size() == 3);
  CHECK(s.cs.dropped_capacity == 0);
}

TEST_CASE("A rigid motion of the scan moves the instance centroids with it") {
  Scene a{VoxelConfig(), ClusterConfig()}, b{VoxelConfig(), ClusterConfig()};
  const Cloud c = street_scene();
  REQUIRE(a.run(c) == Status::Ok);
  // Off-grid translation (voxel boundaries move through the objects) and a yaw.
  const float yaw = 0.7f, t[3] = {3.37f, -1.91f, 0.23f};
  const Cloud m = c.moved(yaw, t[0], t[1], t[2]);
  REQUIRE(b.run(m) == Status::Ok);
  REQUIRE(a.clusters.size() == b.clusters.size());
  for (uint32_t i = 0; i < a.clusters.size(); ++i) {
    const Instance& in = a.clusters.instance(i);
    const double p[3] = {std::cos(yaw) * in.centroid[0] - std::sin(yaw) * in.centroid[1] + t[0],
                         std::sin(yaw) * in.centroid[0] + std::cos(yaw) * in.centroid[1] + t[1], in.centroid[2] + t[2]};
    double d = 0;
    const int k = b.nearest(in.label, p, &d);
    REQUIRE(k >= 0);
    CHECK(d < 1e-3);
    CHECK(b.clusters.instance(static_cast<uint32_t>(k)).point_count == in.point_count);
  }
}

TEST_CASE("Clustering validates bind and build arguments; required_bytes is what bind takes") {
  ClusterConfig cc;
  const size_t need = InstanceClustering::required_bytes(cc, 5000);
  {
    ArenaBuffer buf(need);
    Arena exact(buf.words.data(), need);
    InstanceClustering c;
    CHECK(c.bind(exact, cc, 5000) == Status::Ok);
    CHECK(exact.used() == need);
    Arena short_arena(buf.words.data(), need - 1);
    InstanceClustering d;
    CHECK(d.bind(short_arena, cc, 5000) == Status::BufferTooSmall);
  }
  ArenaBuffer buf(need + VoxelLayer::required_bytes(VoxelConfig()));
  InstanceClustering c;
  VoxelLayer layer;
  ClusterStats st;
  CHECK(c.build(layer, &st) == Status::NotInitialized);
  ClusterConfig bad = cc;
  bad.max_instances = 0;
  CHECK(c.bind(buf.arena, bad, 5000) == Status::InvalidArgument);
  bad = cc;
  bad.tolerance[kPole] = 0.0f;
  CHECK(c.bind(buf.arena, bad, 5000) == Status::InvalidArgument);
  bad = cc;
  bad.tolerance[kCar] = std::nanf("");
  CHECK(c.bind(buf.arena, bad, 5000) == Status::InvalidArgument);
  bad = cc;
  bad.tolerance[kTrunk] = 10.0f;  // would make the neighbour search unbounded in practice
  CHECK(c.bind(buf.arena, bad, 5000) == Status::InvalidArgument);
  bad = cc;
  bad.max_extent[kTrafficSign] = -1.0f;
  CHECK(c.bind(buf.arena, bad, 5000) == Status::InvalidArgument);
  CHECK(c.bind(buf.arena, cc, 0) == Status::InvalidArgument);
  CHECK(buf.arena.used() == 0);
  // A layer with more voxels than the clustering was sized for.
  REQUIRE(c.bind(buf.arena, cc, 100) == Status::Ok);
  REQUIRE(layer.bind(buf.arena, VoxelConfig()) == Status::Ok);
  REQUIRE(layer.build(street_scene().view(), nullptr) == Status::Ok);
  REQUIRE(layer.size() > 100);
  CHECK(c.build(layer, &st) == Status::InvalidArgument);
  CHECK(c.size() == 0);
}

TEST_CASE("Map scale: sizes from the config cluster a 300 m x 300 m layer with 400 poles") {
  VoxelConfig vc;
  vc.min_range = 0.0f;
  vc.max_range = 1000.0f;
  vc.max_voxels = 120000;
  vc.max_columns = 30000;
  ClusterConfig cc;
  cc.max_instances = 1000;
  Scene s{vc, cc};
  Cloud c;
  std::mt19937 rng(12);
  for (float x = -150; x < 150; x += 1.0f)
    for (float y = -150; y < 150; y += 1.0f) c.add(x + 0.5f, y + 0.5f, -1.7f, 72u);
  int obj = 0;
  for (int i = 0; i < 20; ++i)
    for (int j = 0; j < 20; ++j) add_pole(c, rng, -142.5f + 15 * i, -142.5f + 15 * j, 5.0f, 200, obj++);
  REQUIRE(s.run(c) == Status::Ok);
  CHECK(s.vs.voxels > 90000);
  REQUIRE(s.clusters.size() == 400);
  std::vector<double> sum(400 * 4, 0.0);  // one pass: x, y, z, n per pole
  for (size_t i = 0; i < c.object.size(); ++i)
    if (c.object[i] >= 0) {
      double* a = &sum[4 * static_cast<size_t>(c.object[i])];
      for (int k = 0; k < 3; ++k) a[k] += c.pts[4 * i + k];
      a[3] += 1;
    }
  uint32_t exact = 0;
  for (int o = 0; o < 400; ++o) {
    const double* a = &sum[4 * static_cast<size_t>(o)];
    const double m[3] = {a[0] / a[3], a[1] / a[3], a[2] / a[3]};
    double d = 0;
    exact += s.nearest(kPole, m, &d) >= 0 && d < 1e-3;
  }
  CHECK(exact == 400);
}

TEST_CASE("Real SemanticKITTI scans: car instances against the ground-truth instance ids", "[real-data]") {
  const char* frames[] = {"00/velodyne/000052.bin", "00/velodyne/000850.bin", "08/velodyne/000720.bin"};
  // Distinct 0.4 m cells of the labelled points within [2.5, 80] m, counted independently (Python,
  // double precision floor(x / 0.4)).
  const uint32_t expected_voxels[] = {8828, 11363, 14089};
  const std::string root = std::string(GSF_DATA_DIR) + "/semantickitti-samples/sequences/";
  Scene s{VoxelConfig(), ClusterConfig()};
  for (int fi = 0; fi < 3; ++fi) {
    const char* f = frames[fi];
    std::string bin = root + f, lab = bin;
    lab.replace(lab.find("velodyne"), 8, "labels");
    lab.replace(lab.size() - 3, 3, "label");
    std::ifstream fb(bin, std::ios::binary | std::ios::ate), fl(lab, std::ios::binary | std::ios::ate);
    GSF_SKIP_UNLESS(fb && fl, "no real data at " + bin);
    const size_t nb = static_cast<size_t>(fb.tellg()), nl = static_cast<size_t>(fl.tellg());
    REQUIRE(nb % 16 == 0);
    REQUIRE(nl == nb / 4);
    Cloud c;
    c.pts.resize(nb / 4);
    c.labels.resize(nl / 4);
    fb.seekg(0);
    fl.seekg(0);
    fb.read(reinterpret_cast<char*>(c.pts.data()), static_cast<std::streamsize>(nb));
    fl.read(reinterpret_cast<char*>(c.labels.data()), static_cast<std::streamsize>(nl));
    REQUIRE((fb && fl));
    INFO(f);
    REQUIRE(s.run(c) == Status::Ok);
    CHECK(s.vs.unknown_label == 0);
    CHECK(s.vs.non_finite == 0);
    // A point exactly on a cell boundary may round differently in float; allow a handful.
    CHECK(s.vs.voxels + 5 >= expected_voxels[fi]);
    CHECK(s.vs.voxels <= expected_voxels[fi] + 5);

    // Per ground-truth car (>= 50 points in range): which instance holds most of its points.
    std::map<uint32_t, std::map<uint32_t, uint32_t>> share;  // gt word -> instance -> points
    std::map<uint32_t, uint32_t> gt_points;
    const float r0 = s.vc.min_range, r1 = s.vc.max_range;
    for (size_t i = 0; i < c.labels.size(); ++i) {
      if ((c.labels[i] & 0xFFFF) != 10 || (c.labels[i] >> 16) == 0) continue;
      const float* p = &c.pts[4 * i];
      const float r = std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
      if (r < r0 || r > r1) continue;
      ++gt_points[c.labels[i]];
      const uint32_t v = s.layer.find(p);
      const uint32_t k = v == UINT32_MAX ? UINT32_MAX : s.clusters.voxel_instance()[v];
      if (k != UINT32_MAX && s.clusters.instance(k).label == kCar) ++share[c.labels[i]][k];
    }
    uint32_t gt_cars = 0, recovered = 0;
    std::map<uint32_t, int> owners;  // instance -> number of GT cars it holds the majority of
    for (const auto& g : gt_points) {
      if (g.second < 50) continue;
      ++gt_cars;
      uint32_t best = 0, best_k = UINT32_MAX;
      for (const auto& kv : share[g.first])
        if (kv.second > best) {
          best = kv.second;
          best_k = kv.first;
        }
      if (2 * best >= g.second) {
        ++recovered;
        ++owners[best_k];
      }
    }
    uint32_t cars = 0, poles = 0, trunks = 0, signs = 0;
    for (uint32_t k = 0; k < s.clusters.size(); ++k) {
      const uint8_t l = s.clusters.instance(k).label;
      cars += l == kCar;
      poles += l == kPole;
      trunks += l == kTrunk;
      signs += l == kTrafficSign;
    }
    WARN(f << ": " << gt_cars << " GT cars (>= 50 pts), " << recovered
           << " with >= half their points in one car instance, " << owners.size()
           << " distinct owners; instances: " << cars << " cars, " << poles << " poles, " << trunks << " trunks, "
           << signs << " signs; voxels " << s.vs.voxels);
    CHECK(gt_cars >= 3);
    CHECK(recovered * 10 >= gt_cars * 8);        // >= 80% of real cars found as one piece
    CHECK(owners.size() * 10 >= recovered * 7);  // parked rows merge at 1 m, but not wholesale
    CHECK(cars <= gt_points.size() + 10);        // few spurious car blobs
    CHECK(s.clusters.size() <= s.cc.max_instances);
    CHECK(poles + trunks + signs >= 2);  // the street furniture the localizer needs
  }
}

}  // namespace test_instance_clustering
