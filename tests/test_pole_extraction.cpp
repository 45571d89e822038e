// Geometric pole / trunk extraction from host classes (pole_extraction.h): known answers on synthetic
// scenes (a pole among a wall and a bush, a tree's trunk under its canopy, a pole in front of a wall),
// the tilt threshold, capacity overflow keeping the best by score, rigid-motion invariance, argument
// checks; and the real-data measurement: SemanticKITTI (poles/trunks relabelled into their hosts,
// precision/recall against the true ones) and nuScenes-lidarseg (counts per scan and per 100 m, and
// whether the single-scan extraction finds the map's poles again).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "arena_buffer.h"
#include "gsf/instance_clustering.h"
#include "gsf/pole_extraction.h"
#include "gsf/port/nuscenes.h"
#include "gsf/voxel_layer.h"
#include "test_cloud.h"

using namespace gsf;
using gsf_test::ArenaBuffer;
using gsf_test::Cloud;

namespace {

constexpr uint32_t kManmade = 50, kVeg = 70, kRoadId = 40;

struct Pipeline {
  VoxelConfig vc;
  PoleConfig pc;
  ArenaBuffer buf;
  VoxelLayer layer;
  PoleExtraction poles;
  VoxelStats vs;
  PoleStats ps;
  Pipeline(const VoxelConfig& v, const PoleConfig& p)
      : vc(v), pc(p), buf(VoxelLayer::required_bytes(v) + PoleExtraction::required_bytes(p, v.max_voxels)) {
    REQUIRE(layer.bind(buf.arena, vc) == Status::Ok);
    REQUIRE(poles.bind(buf.arena, pc, vc.max_voxels) == Status::Ok);
  }
  Status run(const ScanView& view) {
    const Status s = layer.build(view, &vs);
    if (s != Status::Ok && s != Status::CapacityExceeded) return s;
    return poles.build(layer, &ps);
  }
};

VoxelConfig near_config() {
  VoxelConfig v;
  v.min_range = 0.0f;
  return v;
}

void ground(Cloud& c, float half, float z = -1.7f) {
  for (float x = -half; x <= half; x += 0.25f)
    for (float y = -half; y <= half; y += 0.25f) c.add(x, y, z, kRoadId);
}

// A vertical (or tilted about the x axis by tilt_deg) cylinder of points from z0 up `height`.
void cylinder(Cloud& c, float x, float y, float z0, float height, float radius, uint32_t label, float tilt_deg = 0.0f) {
  const float t = tilt_deg * 3.14159265f / 180.0f;
  for (float h = 0.0f; h <= height; h += 0.05f)
    for (int k = 0; k < 10; ++k) {
      const float a = 6.2831853f * k / 10.0f + h;
      const float px = radius * std::cos(a), py = radius * std::sin(a);
      // Rotate (px, py, h) about the x axis by t.
      c.add(x + px, y + py * std::cos(t) - h * std::sin(t), z0 + py * std::sin(t) + h * std::cos(t), label);
    }
}

void wall(Cloud& c, float x, float y0, float y1, float z0, float z1, uint32_t label) {
  for (float y = y0; y <= y1; y += 0.1f)
    for (float z = z0; z <= z1; z += 0.1f) c.add(x, y, z, label);
}

void blob(Cloud& c, std::mt19937& rng, float x, float y, float z, float r, int n, uint32_t label) {
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (int k = 0; k < n;) {
    const float a = u(rng), b = u(rng), d = u(rng);
    if (a * a + b * b + d * d > 1.0f) continue;
    c.add(x + r * a, y + r * b, z + r * d, label);
    ++k;
  }
}

float hdist(const float a[3], const float b[3]) { return std::hypot(a[0] - b[0], a[1] - b[1]); }

}  // namespace

TEST_CASE("A pole among a wall and a bush is extracted, and only the pole") {
  Cloud c;
  std::mt19937 rng(7);
  ground(c, 15.0f);
  cylinder(c, 5.0f, 3.0f, -1.7f, 5.0f, 0.12f, kManmade);            // the pole
  wall(c, -6.0f, -8.0f, 8.0f, -1.7f, 2.5f, kManmade);               // a building wall
  wall(c, 8.0f, -9.0f, -3.0f, -1.7f, 4.0f, kManmade);               // another, ending in a corner
  wall(c, 8.0f, -3.0f, -3.0f, -1.7f, 4.0f, kManmade);
  blob(c, rng, 2.0f, -6.0f, -0.9f, 1.3f, 4000, kVeg);               // a bush
  blob(c, rng, -2.0f, 7.0f, -1.0f, 0.4f, 300, kVeg);                // a small shrub (thin but low)
  Pipeline p(near_config(), PoleConfig());
  REQUIRE(p.run(c.view()) == Status::Ok);
  INFO("segments " << p.ps.segments << " wide " << p.ps.segments_wide << " crowded " << p.ps.segments_crowded
                   << " chains " << p.ps.chains << " short " << p.ps.rejected_short);
  REQUIRE(p.poles.size() == 1);
  const Instance& in = p.poles.instance(0);
  const float truth[3] = {5.0f, 3.0f, 0.8f};
  CHECK(in.label == kPole);
  CHECK(hdist(in.centroid, truth) < 0.05f);
  CHECK(std::fabs(in.centroid[2] - 0.8f) < 0.2f);
  CHECK(in.stability == 1.0f);
  CHECK(p.poles.info(0).height > 4.8f);
  CHECK(p.poles.info(0).tilt_deg < 1.0f);
  CHECK(p.poles.info(0).kind == kPoleKind);
  CHECK(p.ps.segments_wide > 10);  // the walls and the bush were looked at and refused
  // Every voxel of the instance is pole voxel, and every pole voxel above the ground is in it.
  uint32_t in_pole = 0, pole_voxels = 0;
  for (uint32_t v = 0; v < p.layer.size(); ++v) {
    const float* q = p.layer.voxel(v).centroid;
    const bool is_pole = std::hypot(q[0] - 5.0f, q[1] - 3.0f) < 0.3f && p.layer.voxel(v).label == kBuilding;
    pole_voxels += is_pole;
    if (p.poles.voxel_instance()[v] == 0) {
      CHECK(is_pole);
      ++in_pole;
    }
  }
  CHECK(in_pole == pole_voxels);
  CHECK(in_pole == in.voxel_count);
}

TEST_CASE("A trunk under its canopy is a trunk; a pole 0.7 m in front of a wall is not isolated") {
  Cloud c;
  std::mt19937 rng(11);
  ground(c, 15.0f);
  cylinder(c, -4.0f, 4.0f, -1.7f, 3.2f, 0.25f, kVeg);     // trunk
  blob(c, rng, -4.0f, 4.0f, 3.0f, 2.2f, 8000, kVeg);      // canopy
  wall(c, 6.1f, -8.0f, 8.0f, -1.7f, 3.0f, kManmade);
  cylinder(c, 5.4f, 0.0f, -1.7f, 5.0f, 0.12f, kManmade);  // pole 0.7 m in front of the wall
  Pipeline p(near_config(), PoleConfig());
  REQUIRE(p.run(c.view()) == Status::Ok);
  INFO("crowded " << p.ps.segments_crowded << " chains " << p.ps.chains);
  REQUIRE(p.poles.size() == 1);
  const Instance& in = p.poles.instance(0);
  const float truth[3] = {-4.0f, 4.0f, 0.0f};
  CHECK(in.label == kTrunk);
  CHECK(hdist(in.centroid, truth) < 0.1f);
  CHECK(p.poles.info(0).height >= 2.0f);
  CHECK(p.poles.info(0).height < 3.8f);  // the canopy is not part of it
  CHECK(p.ps.segments_crowded > 5);
  // 1.7 m away from the wall it is a pole.
  Cloud d;
  ground(d, 15.0f);
  wall(d, 6.1f, -8.0f, 8.0f, -1.7f, 3.0f, kManmade);
  cylinder(d, 4.4f, 0.0f, -1.7f, 5.0f, 0.12f, kManmade);
  REQUIRE(p.run(d.view()) == Status::Ok);
  REQUIRE(p.poles.size() == 1);
  CHECK(p.poles.instance(0).label == kPole);
}

TEST_CASE("Tilted poles: accepted up to max_tilt_deg, rejected beyond, tilt measured") {
  PoleConfig pc;
  REQUIRE(pc.max_tilt_deg == 12.0f);
  for (float tilt : {0.0f, 4.0f, 8.0f, 11.0f, 14.0f, 20.0f, 30.0f}) {
    Cloud c;
    ground(c, 10.0f);
    cylinder(c, 3.0f, 2.0f, -1.7f, 5.0f, 0.12f, kManmade, tilt);
    Pipeline p(near_config(), pc);
    REQUIRE(p.run(c.view()) == Status::Ok);
    INFO("tilt " << tilt << ": instances " << p.poles.size() << " rejected_tilt " << p.ps.rejected_tilt
                 << " rejected_thick " << p.ps.rejected_thick << " chains " << p.ps.chains);
    if (tilt <= 11.0f) {
      REQUIRE(p.poles.size() == 1);
      CHECK(std::fabs(p.poles.info(0).tilt_deg - tilt) < 1.0f);
      CHECK(p.poles.info(0).thickness < 0.5f);
    } else {
      CHECK(p.poles.size() == 0);
      CHECK(p.ps.rejected_tilt == 1);
    }
  }
}

TEST_CASE("Capacity overflow keeps the best by score, whatever the storage order") {
  Cloud c;
  ground(c, 20.0f);
  // Six poles in increasing height in point order: "the first three" would be the three shortest.
  const float heights[6] = {2.4f, 3.0f, 3.6f, 4.2f, 4.8f, 5.4f};
  for (int k = 0; k < 6; ++k) cylinder(c, -10.0f + 4.0f * k, 5.0f, -1.7f, heights[k], 0.12f, kManmade);
  PoleConfig all;
  Pipeline p(near_config(), all);
  REQUIRE(p.run(c.view()) == Status::Ok);
  REQUIRE(p.poles.size() == 6);
  CHECK(p.ps.dropped_capacity == 0);
  PoleConfig three;
  three.max_instances = 3;
  Pipeline q(near_config(), three);
  REQUIRE(q.run(c.view()) == Status::CapacityExceeded);
  CHECK(q.ps.dropped_capacity == 3);
  CHECK(q.ps.instances == 3);
  REQUIRE(q.poles.size() == 3);
  for (uint32_t k = 0; k < 3; ++k) {
    INFO("kept " << k << " at x " << q.poles.instance(k).centroid[0] << " height " << q.poles.info(k).height);
    CHECK(q.poles.instance(k).centroid[0] > 1.0f);  // the three tallest: x = 2, 6, 10
    CHECK(q.poles.info(k).height > 4.0f);
    if (k > 0) CHECK(q.poles.instance(k - 1).first_voxel < q.poles.instance(k).first_voxel);
    CHECK(q.poles.info(k).first_voxel == q.poles.instance(k).first_voxel);
  }
  // Voxels of dropped poles map to no instance; kept ones to theirs.
  uint32_t mapped = 0;
  for (uint32_t v = 0; v < q.layer.size(); ++v) {
    const uint32_t k = q.poles.voxel_instance()[v];
    if (k == UINT32_MAX) continue;
    REQUIRE(k < 3);
    CHECK(std::fabs(q.layer.voxel(v).centroid[0] - q.poles.instance(k).centroid[0]) < 0.5f);
    ++mapped;
  }
  CHECK(mapped == q.poles.instance(0).voxel_count + q.poles.instance(1).voxel_count + q.poles.instance(2).voxel_count);
  // The next, smaller scene is fine again.
  Cloud one;
  ground(one, 10.0f);
  cylinder(one, 1.0f, 1.0f, -1.7f, 4.0f, 0.12f, kManmade);
  REQUIRE(q.run(one.view()) == Status::Ok);
  CHECK(q.poles.size() == 1);
}

TEST_CASE("A rigid motion of the scene moves the extracted instances with it") {
  Cloud c;
  std::mt19937 rng(5);
  ground(c, 20.0f);
  const float spots[5][2] = {{-8, 3}, {-3, -6}, {4, 7}, {9, -2}, {1, 1}};
  for (int k = 0; k < 5; ++k) cylinder(c, spots[k][0], spots[k][1], -1.7f, 3.0f + 0.5f * k, 0.08f + 0.04f * k,
                                       k % 2 ? kVeg : kManmade);
  wall(c, -14.0f, -10.0f, 10.0f, -1.7f, 3.0f, kManmade);
  blob(c, rng, 6.0f, -9.0f, -0.8f, 1.5f, 4000, kVeg);
  Pipeline p(near_config(), PoleConfig());
  REQUIRE(p.run(c.view()) == Status::Ok);
  REQUIRE(p.poles.size() == 5);
  std::vector<Instance> base(p.poles.instances(), p.poles.instances() + p.poles.size());
  for (float yaw : {0.3f, 1.1f, 2.9f}) {
    const float cs = std::cos(yaw), sn = std::sin(yaw), tx = 13.3f, ty = -7.1f, tz = 0.4f;
    Cloud m = c;
    for (size_t i = 0; i < m.labels.size(); ++i) {
      const float x = c.pts[4 * i], y = c.pts[4 * i + 1];
      m.pts[4 * i] = cs * x - sn * y + tx;
      m.pts[4 * i + 1] = sn * x + cs * y + ty;
      m.pts[4 * i + 2] = c.pts[4 * i + 2] + tz;
    }
    REQUIRE(p.run(m.view()) == Status::Ok);
    INFO("yaw " << yaw);
    REQUIRE(p.poles.size() == base.size());
    for (const Instance& b : base) {
      const float moved[3] = {cs * b.centroid[0] - sn * b.centroid[1] + tx, sn * b.centroid[0] + cs * b.centroid[1] + ty,
                              b.centroid[2] + tz};
      float best = 1e9f;
      uint8_t label = 255;
      for (uint32_t k = 0; k < p.poles.size(); ++k) {
        const float d = hdist(p.poles.instance(k).centroid, moved);
        if (d < best) { best = d; label = p.poles.instance(k).label; }
      }
      CHECK(best < 0.1f);
      CHECK(label == b.label);
    }
  }
}

TEST_CASE("Pole extraction validates bind and build arguments; required_bytes is what bind takes") {
  PoleConfig pc;
  const uint32_t nv = 5000;
  {
    ArenaBuffer buf(PoleExtraction::required_bytes(pc, nv));
    PoleExtraction p;
    CHECK(p.bind(buf.arena, pc, nv) == Status::Ok);
    CHECK(buf.arena.used() == PoleExtraction::required_bytes(pc, nv));
  }
  {
    ArenaBuffer buf(PoleExtraction::required_bytes(pc, nv) - 64);
    PoleExtraction p;
    CHECK(p.bind(buf.arena, pc, nv) == Status::BufferTooSmall);
  }
  auto bad = [&](PoleConfig c, uint32_t voxels = 100) {
    ArenaBuffer buf(1 << 20);
    PoleExtraction p;
    return p.bind(buf.arena, c, voxels) == Status::InvalidArgument;
  };
  PoleConfig c = pc;
  CHECK(bad(c, 0));
  c.max_instances = 0; CHECK(bad(c)); c = pc;
  c.trunk_hosts |= c.pole_hosts; CHECK(bad(c)); c = pc;
  c.max_diameter[1] = 0.0f; CHECK(bad(c)); c = pc;
  c.max_diameter[0] = NAN; CHECK(bad(c)); c = pc;
  c.min_height[0] = -1.0f; CHECK(bad(c)); c = pc;
  c.max_tilt_deg = 0.0f; CHECK(bad(c)); c = pc;
  c.max_tilt_deg = 90.0f; CHECK(bad(c)); c = pc;
  c.link_radius = 0.0f; CHECK(bad(c)); c = pc;
  c.ring_width = -0.1f; CHECK(bad(c)); c = pc;
  c.max_gap = INFINITY; CHECK(bad(c)); c = pc;
  c.stability[0] = 1.5f; CHECK(bad(c)); c = pc;

  Cloud s;
  ground(s, 10.0f);
  cylinder(s, 3.0f, 2.0f, -1.7f, 4.0f, 0.12f, kManmade);
  ArenaBuffer lbuf(VoxelLayer::required_bytes(near_config()));
  VoxelLayer layer;
  REQUIRE(layer.bind(lbuf.arena, near_config()) == Status::Ok);
  REQUIRE(layer.build(s.view(), nullptr) == Status::Ok);
  PoleExtraction unbound;
  PoleStats st;
  st.segments = 77;
  CHECK(unbound.build(layer, &st) == Status::NotInitialized);
  CHECK(st.segments == 0);
  {
    ArenaBuffer buf(PoleExtraction::required_bytes(pc, 100));
    PoleExtraction small;
    REQUIRE(small.bind(buf.arena, pc, 100) == Status::Ok);
    CHECK(small.build(layer, &st) == Status::InvalidArgument);  // layer holds more than 100 voxels
  }
  {
    PoleConfig wide = pc;
    wide.ring_width = 7.0f;  // 18 cells of 0.4 m
    ArenaBuffer buf(PoleExtraction::required_bytes(wide, near_config().max_voxels));
    PoleExtraction p;
    REQUIRE(p.bind(buf.arena, wide, near_config().max_voxels) == Status::Ok);
    CHECK(p.build(layer, &st) == Status::InvalidArgument);
  }
  // Hosts from a class table; no host classes -> nothing.
  ClassTable kitti, nusc;
  semantic_kitti_class_table(&kitti);
  nuscenes_lidarseg_class_table(&nusc);
  PoleConfig from_nusc;
  from_nusc.set_hosts(nusc);
  CHECK(from_nusc.pole_hosts == class_bit(kBuilding));
  CHECK(from_nusc.trunk_hosts == class_bit(kVegetation));
  CHECK(from_nusc.stability[kPoleKind] == stability_weight(kPole));
  CHECK(from_nusc.stability[kTrunkKind] == stability_weight(kTrunk));
  PoleConfig from_kitti;
  from_kitti.set_hosts(kitti);
  Pipeline none(near_config(), from_kitti);
  CHECK(none.run(s.view()) == Status::Ok);
  CHECK(none.poles.size() == 0);
  CHECK(none.ps.host_voxels == 0);
}
