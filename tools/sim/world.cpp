#include "sim/world.h"

#include <algorithm>
#include <cmath>

#include "gsf/bounded_hash_map.h"
#include "gsf/rng.h"

namespace gsf::sim {
namespace {

constexpr uint16_t kRoad = 40, kParking = 44, kSidewalk = 48, kOtherGround = 49, kBuilding = 50, kFence = 51,
                   kVegetation = 70, kTrunk = 71, kTerrain = 72, kPole = 80, kSign = 81, kCar = 10;

struct Gen {
  World& w;
  gsf::Rng rng;
  float uni(float lo, float hi) { return lo + (hi - lo) * rng.uniform01(); }
  bool chance(float p) { return rng.uniform01() < p; }

  void box(uint16_t sem, uint32_t inst, float x0, float y0, float z0, float x1, float y1, float z1) {
    w.prims.push_back(Primitive{Shape::Box, sem, inst, {std::min(x0, x1), std::min(y0, y1), z0},
                                {std::max(x0, x1), std::max(y0, y1), z1}});
  }
  void cylinder(uint16_t sem, uint32_t inst, float x, float y, float z0, float r, float h) {
    w.prims.push_back(Primitive{Shape::Cylinder, sem, inst, {x, y, z0}, {r, h, 0}});
  }
  void sphere(uint16_t sem, uint32_t inst, float x, float y, float z, float r) {
    w.prims.push_back(Primitive{Shape::Sphere, sem, inst, {x, y, z}, {r, 0, 0}});
  }
  uint32_t id() { return w.next_instance++; }

  // A pole, optionally carrying a sign plate facing the road (normal along `nx, ny`).
  void pole(float x, float y, bool with_sign, float nx, float ny) {
    const float h = uni(5.5f, 8.0f);
    cylinder(kPole, id(), x, y, 0.0f, 0.12f, h);
    if (with_sign) {
      const float z = uni(2.2f, 3.2f), half = uni(0.3f, 0.45f);
      const uint32_t s = id();
      // thin plate offset towards the road, perpendicular to the normal
      const float cx = x + 0.2f * nx, cy = y + 0.2f * ny;
      if (std::fabs(nx) > std::fabs(ny)) box(kSign, s, cx - 0.04f, cy - half, z, cx + 0.04f, cy + half, z + 2 * half);
      else box(kSign, s, cx - half, cy - 0.04f, z, cx + half, cy + 0.04f, z + 2 * half);
    }
  }
  void tree(float x, float y) {
    const float h = uni(2.5f, 3.8f), r = uni(1.6f, 2.8f);
    cylinder(kTrunk, id(), x, y, 0.0f, uni(0.15f, 0.28f), h + 0.5f);
    sphere(kVegetation, 0, x, y, h + r * 0.8f, r);
  }
  void bush(float x, float y) { sphere(kVegetation, 0, x, y, uni(0.2f, 0.5f), uni(0.6f, 1.3f)); }
  // A parked car aligned with x (along_x) or y.
  void car(float x, float y, bool along_x) {
    const uint32_t c = id();
    const float l = uni(3.9f, 4.8f) / 2, wd = uni(1.7f, 1.9f) / 2, cl = l * 0.55f;
    if (along_x) {
      box(kCar, c, x - l, y - wd, 0.25f, x + l, y + wd, 1.2f);
      box(kCar, c, x - cl, y - wd + 0.1f, 1.2f, x + cl * 0.8f, y + wd - 0.1f, 1.75f);
    } else {
      box(kCar, c, x - wd, y - l, 0.25f, x + wd, y + l, 1.2f);
      box(kCar, c, x - wd + 0.1f, y - cl, 1.2f, x + wd - 0.1f, y + cl * 0.8f, 1.75f);
    }
  }
};

}  // namespace

float World::road_length() const {
  float l = 0;
  for (const auto& r : roads) l += std::fabs(r.x1 - r.x0) + std::fabs(r.y1 - r.y0);
  return l;
}

bool World::in_zone(float x, float y) const {
  return params.repetitive_zone && x >= zone_x0 && x <= zone_x1 && std::fabs(y - zone_y) < 40.0f;
}

uint16_t World::ground_class(float x, float y) const {
  const float hw = params.road_width / 2, sw = params.sidewalk_width;
  const float B = params.block_size;
  const float gx = params.blocks_x * B, gy = params.blocks_y * B;
  float dmin = 1e9f;
  // distance to the nearest road centre line (grid + zone extension)
  if (x >= -hw - sw && x <= gx + hw + sw) {
    const float j = std::round(y / B);
    if (j >= 0 && j <= params.blocks_y) dmin = std::min(dmin, std::fabs(y - j * B));
  }
  if (y >= -hw - sw && y <= gy + hw + sw) {
    const float i = std::round(x / B);
    if (i >= 0 && i <= params.blocks_x) dmin = std::min(dmin, std::fabs(x - i * B));
  }
  if (params.repetitive_zone && x >= gx && x <= zone_x1 + params.zone_margin) dmin = std::min(dmin, std::fabs(y - zone_y));
  if (dmin <= hw) return kRoad;
  if (dmin <= hw + sw) return kSidewalk;
  if (params.repetitive_zone && x > gx + hw + sw && x <= zone_x1 + params.zone_margin && std::fabs(y - zone_y) < 40.0f) {
    // Irregular ground patches per zone period and side (the "stuff" that tells periods apart).
    const int cell = static_cast<int>(std::floor((x - zone_x0) / (params.zone_period / 2)));
    const int side = y > zone_y ? 1 : 0;
    const int band = static_cast<int>((std::fabs(y - zone_y) - hw - sw) / 6.0f);
    uint64_t h = gsf::mix64(params.seed * 7919u + uint64_t(cell + 100000) * 31u + side * 17u + band);
    switch (h % 4) {
      case 0: return kTerrain;
      case 1: return kParking;
      case 2: return kOtherGround;
      default: return kTerrain;
    }
  }
  // Parking strips on some blocks along their lower edge.
  const int bi = static_cast<int>(std::floor(x / B)), bj = static_cast<int>(std::floor(y / B));
  const float ly = y - bj * B;
  if (bi >= 0 && bj >= 0 && bi < params.blocks_x && bj < params.blocks_y && (bi + 2 * bj) % 3 == 0 &&
      ly > hw + sw && ly < hw + sw + 6.0f)
    return kParking;
  return kTerrain;
}

World generate_world(const WorldParams& p) {
  World w;
  w.params = p;
  Gen g{w, gsf::Rng(p.seed)};
  const float B = p.block_size, hw = p.road_width / 2, sw = p.sidewalk_width;
  const float gx = p.blocks_x * B, gy = p.blocks_y * B;
  for (int j = 0; j <= p.blocks_y; ++j) w.roads.push_back(RoadSegment{0, j * B, gx, j * B, false});
  for (int i = 0; i <= p.blocks_x; ++i) w.roads.push_back(RoadSegment{i * B, 0, i * B, gy, false});
  w.zone_y = 0.0f;
  w.zone_x0 = gx + p.zone_margin;
  w.zone_x1 = w.zone_x0 + p.zone_length;
  if (p.repetitive_zone) w.roads.push_back(RoadSegment{gx, 0.0f, w.zone_x1 + p.zone_margin, 0.0f, true});

  auto near_crossing = [&](float along, float margin) {
    const float m = std::fmod(along, B);
    return m < hw + sw + margin || m > B - hw - sw - margin;
  };
  // Street furniture along both sides of every grid road.
  for (int j = 0; j <= p.blocks_y; ++j)
    for (int side = -1; side <= 1; side += 2) {
      const float y = j * B;
      if ((j == 0 && side < 0) || (j == p.blocks_y && side > 0)) {}  // outer edges still get furniture
      for (float x = g.uni(3, 12); x < gx; x += g.uni(22, 38))
        if (!near_crossing(x, 2)) g.pole(x, y + side * (hw + 0.4f), g.chance(0.3f), 0, -float(side));
      if (g.chance(0.7f))
        for (float x = g.uni(4, 10); x < gx; x += g.uni(11, 19))
          if (!near_crossing(x, 3)) g.tree(x, y + side * (hw + sw - 0.8f));
      for (float x = g.uni(5, 12); x < gx; x += g.uni(6.5f, 9.5f))
        if (!near_crossing(x, 6) && g.chance(0.55f)) g.car(x, y + side * (hw - 1.2f), true);
    }
  for (int i = 0; i <= p.blocks_x; ++i)
    for (int side = -1; side <= 1; side += 2) {
      const float x = i * B;
      for (float y = g.uni(3, 12); y < gy; y += g.uni(22, 38))
        if (!near_crossing(y, 2)) g.pole(x + side * (hw + 0.4f), y, g.chance(0.3f), -float(side), 0);
      if (g.chance(0.6f))
        for (float y = g.uni(4, 10); y < gy; y += g.uni(11, 19))
          if (!near_crossing(y, 3)) g.tree(x + side * (hw + sw - 0.8f), y);
      for (float y = g.uni(5, 12); y < gy; y += g.uni(6.5f, 9.5f))
        if (!near_crossing(y, 6) && g.chance(0.5f)) g.car(x + side * (hw - 1.2f), y, false);
    }
  // Blocks: buildings around the perimeter, fences, bushes, standalone signs, parking lots.
  for (int bi = 0; bi < p.blocks_x; ++bi)
    for (int bj = 0; bj < p.blocks_y; ++bj) {
      const float x0 = bi * B + hw + sw, y0 = bj * B + hw + sw, x1 = (bi + 1) * B - hw - sw, y1 = (bj + 1) * B - hw - sw;
      const bool parking = (bi + 2 * bj) % 3 == 0;
      // bottom / top rows of buildings
      for (int row = 0; row < 2; ++row) {
        float x = x0 + g.uni(1, 6);
        while (x < x1 - 10) {
          const float len = std::min(g.uni(12, 35), x1 - x - 2), depth = g.uni(10, 18), h = g.uni(6, 24);
          const float setback = (row == 0 && parking) ? 8.0f : g.uni(2, 6);
          if (row == 0) g.box(kBuilding, g.id(), x, y0 + setback, 0, x + len, y0 + setback + depth, h);
          else g.box(kBuilding, g.id(), x, y1 - setback - depth, 0, x + len, y1 - setback, h);
          x += len + g.uni(4, 14);
        }
      }
      // left / right columns of buildings in the middle band
      for (int col = 0; col < 2; ++col) {
        float y = y0 + 26 + g.uni(0, 6);
        while (y < y1 - 30) {
          const float len = std::min(g.uni(10, 25), y1 - 26 - y), depth = g.uni(10, 16), h = g.uni(6, 20);
          if (len < 6) break;
          const float setback = g.uni(2, 6);
          if (col == 0) g.box(kBuilding, g.id(), x0 + setback, y, 0, x0 + setback + depth, y + len, h);
          else g.box(kBuilding, g.id(), x1 - setback - depth, y, 0, x1 - setback, y + len, h);
          y += len + g.uni(5, 12);
        }
      }
      if (g.chance(0.5f)) {  // a fence along the sidewalk
        const float fx = x0 + g.uni(5, 30), fl = g.uni(10, 30);
        g.box(kFence, 0, fx, y1 - 0.6f, 0, std::min(fx + fl, x1 - 2), y1 - 0.5f, g.uni(1.0f, 1.8f));
      }
      for (int k = 0; k < 6; ++k) g.bush(g.uni(x0 + 1, x1 - 1), g.chance(0.5f) ? y0 + g.uni(0.5f, 2.0f) : y1 - g.uni(0.5f, 2.0f));
      if (g.chance(0.6f)) {  // a standalone sign near the kerb
        const float sx = g.uni(x0 + 10, x1 - 10);
        g.cylinder(kPole, g.id(), sx, y0 + 0.5f, 0.0f, 0.06f, 2.4f);
        const uint32_t s = g.id();
        g.box(kSign, s, sx - 0.35f, y0 + 0.2f, 2.0f, sx + 0.35f, y0 + 0.28f, 2.7f);
      }
      if (parking)  // cars in the parking strip
        for (float x = x0 + g.uni(2, 6); x < x1 - 4; x += g.uni(2.6f, 3.4f))
          if (g.chance(0.5f)) g.car(x, y0 + 3.0f, false);
    }
  // The repetitive zone: identical columns on a lattice with period zone_period along x (four rows),
  // nothing else instantiable; irregular vegetation, fences and low walls per period and side.
  if (p.repetitive_zone) {
    const float rows[4] = {-(hw + sw + 1.5f), -(hw + sw + 7.5f), hw + sw + 1.5f, hw + sw + 7.5f};
    for (float x = w.zone_x0; x <= w.zone_x1 + 1e-3f; x += p.zone_period)
      for (float ry : rows) g.cylinder(kPole, g.id(), x, w.zone_y + ry, 0.0f, 0.3f, 4.5f);
    for (float x = w.zone_x0 - p.zone_period; x <= w.zone_x1 + p.zone_period; x += p.zone_period / 2)
      for (int side = -1; side <= 1; side += 2) {
        const float base = w.zone_y + side * (hw + sw);
        const int kind = static_cast<int>(g.rng.uniform(5));
        if (kind == 0 || kind == 1) {
          const int nb = 1 + static_cast<int>(g.rng.uniform(3));
          for (int k = 0; k < nb; ++k) g.bush(x + g.uni(0.5f, 4.5f), base + side * g.uni(3.0f, 12.0f));
        } else if (kind == 2) {
          const float yy = base + side * g.uni(4.0f, 11.0f);
          g.box(kFence, 0, x + g.uni(0, 1), yy - 0.05f, 0, x + g.uni(2.5f, 5.0f), yy + 0.05f, g.uni(1.0f, 1.6f));
        } else if (kind == 3) {
          const float yy = base + side * g.uni(10.0f, 13.0f);
          g.box(kBuilding, 0, x + g.uni(0, 1), yy - 0.2f, 0, x + g.uni(3.0f, 5.0f), yy + 0.2f, g.uni(1.5f, 2.8f));
        }  // kind 4: open ground
      }
  }
  // World bounds.
  w.min_xy[0] = -40; w.min_xy[1] = -40;
  w.max_xy[0] = (p.repetitive_zone ? w.zone_x1 + p.zone_margin : gx) + 40;
  w.max_xy[1] = gy + 40;
  return w;
}

World apply_time_gap(const World& in, const TimeGapParams& tp) {
  World w = in;
  w.prims.clear();
  gsf::Rng rng(tp.seed);
  // Cars come as two boxes with one instance id: decide per instance.
  uint32_t last_car = 0;
  int car_action = 0;  // 0 keep, 1 remove, 2 move
  float dx = 0, dy = 0;
  for (const Primitive& p : in.prims) {
    Primitive q = p;
    if (p.semantic == kCar) {
      if (p.instance != last_car) {
        last_car = p.instance;
        const float u = rng.uniform01();
        car_action = u < tp.cars_removed ? 1 : (u < tp.cars_removed + tp.cars_moved ? 2 : 0);
        const float shift = (rng.uniform01() < 0.5f ? -1.0f : 1.0f) * (2.0f + 4.0f * rng.uniform01());
        const bool along_x = (p.b[0] - p.a[0]) > (p.b[1] - p.a[1]);
        dx = along_x ? shift : 0.0f;
        dy = along_x ? 0.0f : shift;
      }
      if (car_action == 1) continue;
      if (car_action == 2) { q.a[0] += dx; q.b[0] += dx; q.a[1] += dy; q.b[1] += dy; }
    } else if (p.semantic == kVegetation && p.shape == Shape::Sphere) {
      const bool bush = p.a[2] < 1.0f;
      if (bush && rng.uniform01() < tp.bushes_cut) continue;
      q.b[0] *= 1.0f + tp.vegetation_change * (2.0f * rng.uniform01() - 1.0f);
    }
    w.prims.push_back(q);
  }
  return w;
}

}  // namespace gsf::sim
