// The simulator: geometry ground truth, stable instance ids, determinism, the repetitive zone, the time gap.
#include <catch2/catch.hpp>

#include <cmath>
#include <map>

#include "sim/simulation.h"

using namespace gsf::sim;

TEST_CASE("A scan transformed by its pose lands on the known geometry") {
  const SimConfig sc = SimConfig::tiny();
  const World w = generate_world(sc.world);
  const Raycaster rc(w);
  const Drive d = mapping_drive(w, sc);
  SimScan s;
  rc.scan(d.poses[3], sc.lidar, 1, &s);
  REQUIRE(s.size() > 5000);
  std::map<uint32_t, const Primitive*> poles;
  for (const auto& p : w.prims)
    if (p.semantic == 80 && p.shape == Shape::Cylinder) poles[p.instance] = &p;
  int pole_points = 0, road_points = 0;
  std::map<uint16_t, int> classes;
  for (uint32_t i = 0; i < s.size(); ++i) {
    const Eigen::Vector3d q = d.poses[3] * Eigen::Vector3d(s.xyzi[4 * i], s.xyzi[4 * i + 1], s.xyzi[4 * i + 2]);
    const uint16_t sem = s.labels[i] & 0xFFFF;
    classes[sem]++;
    if (sem == 80 && poles.count(s.labels[i] >> 16)) {
      const Primitive* p = poles[s.labels[i] >> 16];
      CHECK(std::fabs(std::hypot(q.x() - p->a[0], q.y() - p->a[1]) - p->b[0]) < 0.12);  // on the surface (+noise)
      ++pole_points;
    }
    if (sem == 40) {
      CHECK(std::fabs(q.z()) < 0.1);
      ++road_points;
    }
  }
  CHECK(pole_points > 20);
  CHECK(road_points > s.size() / 10);
  CHECK(classes.count(50));  // buildings
  CHECK(classes.count(72));  // terrain
}

TEST_CASE("Same seed -> identical scans; instance ids are stable across scans") {
  const SimConfig sc = SimConfig::tiny();
  const World a = generate_world(sc.world), b = generate_world(sc.world);
  REQUIRE(a.prims.size() == b.prims.size());
  const Raycaster ra(a), rb(b);
  const Drive d = mapping_drive(a, sc);
  SimScan s1, s2, s3;
  ra.scan(d.poses[5], sc.lidar, 9, &s1);
  rb.scan(d.poses[5], sc.lidar, 9, &s2);
  CHECK(s1.xyzi == s2.xyzi);
  CHECK(s1.labels == s2.labels);
  WorldParams other = sc.world;
  other.seed += 1;
  CHECK(generate_world(other).prims.size() != a.prims.size());
  // The same pole seen from two poses keeps its id.
  ra.scan(d.poses[6], sc.lidar, 10, &s3);
  std::map<uint32_t, int> ids1, ids3;
  for (uint32_t l : s1.labels) if ((l & 0xFFFF) == 80) ids1[l >> 16]++;
  for (uint32_t l : s3.labels) if ((l & 0xFFFF) == 80) ids3[l >> 16]++;
  int shared = 0;
  for (const auto& kv : ids1) shared += ids3.count(kv.first) ? 1 : 0;
  CHECK(shared >= 2);
}

TEST_CASE("The repetitive zone repeats its instances by one period; the time gap spares infrastructure") {
  const SimConfig sc = SimConfig::tiny();
  const World w = generate_world(sc.world);
  std::vector<std::pair<float, float>> cols;
  for (const auto& p : w.prims)
    if (p.semantic == 80 && w.in_zone(p.a[0], p.a[1])) cols.push_back({p.a[0], p.a[1]});
  REQUIRE(cols.size() >= 8);
  for (const auto& c : cols) {  // every column has its twin one period further (unless at the end)
    if (c.first + sc.world.zone_period > w.zone_x1 + 1e-3f) continue;
    bool twin = false;
    for (const auto& d : cols) twin = twin || (std::fabs(d.first - c.first - sc.world.zone_period) < 1e-3f && d.second == c.second);
    CHECK(twin);
  }
  for (const auto& p : w.prims)  // no other instances in the zone
    if (p.instance && w.in_zone(p.a[0], p.a[1])) CHECK(p.semantic == 80);
  const World later = apply_time_gap(w, sc.time_gap);
  auto count = [](const World& x, uint16_t sem) {
    int n = 0;
    for (const auto& p : x.prims) n += p.semantic == sem;
    return n;
  };
  CHECK(count(later, 10) < count(w, 10));  // some cars gone
  for (uint16_t sem : {50, 71, 80, 81}) CHECK(count(later, sem) == count(w, sem));
  const Drive q = query_drive(w, sc);
  int zone = 0;
  for (bool z : q.in_zone) zone += z;
  CHECK(zone >= 4);
}
