#include "sim/world.h"

#include <algorithm>
#include <cmath>
#include <string_view>

#include "gsf/detail/bounded_hash_map.h"
#include "gsf/detail/rng.h"

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
    w.prims.push_back(Primitive{
        Shape::Box, sem, inst, {std::min(x0, x1), std::min(y0, y1), z0}, {std::max(x0, x1), std::max(y0, y1), z1}});
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

const char* zone_name(ZoneType z) {
  switch (z) {
    case ZoneType::Row: return "row";
    case ZoneType::Lattice: return "lattice";
    case ZoneType::Hall: return "hall";
    case ZoneType::Avenue: return "avenue";
  }
  return "row";
}

bool parse_zone(const char* name, ZoneType* out) {
  for (ZoneType z : {ZoneType::Row, ZoneType::Lattice, ZoneType::Hall, ZoneType::Avenue})
    if (std::string_view(name) == zone_name(z)) {
      *out = z;
      return true;
    }
  return false;
}

float xy_distance(const Primitive& p, float x, float y) {
  if (p.shape == Shape::Box) {
    const float dx = std::max({p.a[0] - x, 0.0f, x - p.b[0]}), dy = std::max({p.a[1] - y, 0.0f, y - p.b[1]});
    return std::hypot(dx, dy);
  }
  return std::max(0.0f, std::hypot(x - p.a[0], y - p.a[1]) - p.b[0]);
}

float World::road_length() const {
  float l = 0;
  for (const auto& r : roads) l += std::fabs(r.x1 - r.x0) + std::fabs(r.y1 - r.y0);
  return l;
}

bool World::in_zone(float x, float y) const {
  if (params.zone == ZoneType::Row || params.zone == ZoneType::Avenue)
    return params.repetitive_zone && x >= zone_x0 && x <= zone_x1 && std::fabs(y - zone_y) < 40.0f;
  return params.repetitive_zone && x >= zone_rect[0] && x <= zone_rect[2] && y >= zone_rect[1] && y <= zone_rect[3];
}

bool World::near_zone(float x, float y) const {
  if (!params.repetitive_zone || in_zone(x, y)) return false;
  const float dx = std::max({zone_rect[0] - x, 0.0f, x - zone_rect[2]});
  const float dy = std::max({zone_rect[1] - y, 0.0f, y - zone_rect[3]});
  return std::hypot(dx, dy) <= kNearZone;
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
  // The zone's road: row and avenue run a road through the zone; lattice and hall have an approach road
  // up to the zone rectangle and a plain floor inside it.
  const bool road_zone = params.zone == ZoneType::Row || params.zone == ZoneType::Avenue;
  if (params.repetitive_zone && road_zone && x >= gx && x <= zone_x1 + params.zone_margin)
    dmin = std::min(dmin, std::fabs(y - zone_y));
  if (params.repetitive_zone && !road_zone && x >= gx && x <= zone_rect[0])
    dmin = std::min(dmin, std::fabs(y - zone_y));
  if (dmin <= hw) return kRoad;
  if (dmin <= hw + sw) return kSidewalk;
  if (params.repetitive_zone && !road_zone && x >= zone_rect[0] && x <= zone_rect[2] && y >= zone_rect[1] &&
      y <= zone_rect[3])
    return params.zone == ZoneType::Lattice ? kParking : kOtherGround;
  if (params.repetitive_zone && road_zone && !params.legacy_row_cues() && x > gx + hw + sw &&
      x <= zone_x1 + params.zone_margin && std::fabs(y - zone_y) < 40.0f)
    return params.zone == ZoneType::Row ? kParking : kOtherGround;  // plain floor: cues are the only stuff
  if (params.repetitive_zone && params.legacy_row_cues() && x > gx + hw + sw && x <= zone_x1 + params.zone_margin &&
      std::fabs(y - zone_y) < 40.0f) {
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
  if (bi >= 0 && bj >= 0 && bi < params.blocks_x && bj < params.blocks_y && (bi + 2 * bj) % 3 == 0 && ly > hw + sw &&
      ly < hw + sw + 6.0f)
    return kParking;
  return kTerrain;
}

namespace {

// Records primitives [first, end) as one repeated instance of the zone.
void add_zone_instance(World& w, size_t first, float x, float y, float radius) {
  for (size_t i = first; i < w.prims.size(); ++i) w.zone_repeated_prims.push_back(static_cast<uint32_t>(i));
  w.zone_instances.push_back(ZoneInstance{w.prims[first].instance, x, y, radius, false});
}

struct Rect {
  float x0, y0, x1, y1;
};

// The paper's Fig. 1 car park: the road extends past the city by zone_margin without any instance, then
// zone_length of road lined by four rows of identical columns every zone_period. Legacy stuff (demo,
// tiny): per half-period and side a random kind of bushes / fence / low wall / nothing, plus ground
// patches (World::ground_class); otherwise cues by cue_density (place_cues) on a plain parking floor.
void row_zone(Gen& g, std::vector<Rect>* keep_out) {
  World& w = g.w;
  const WorldParams& p = w.params;
  const float hw = p.road_width / 2, sw = p.sidewalk_width;
  w.zone_rect[0] = w.zone_x0;
  w.zone_rect[1] = w.zone_y - 40;
  w.zone_rect[2] = w.zone_x1;
  w.zone_rect[3] = w.zone_y + 40;
  const float rows[4] = {-(hw + sw + 1.5f), -(hw + sw + 7.5f), hw + sw + 1.5f, hw + sw + 7.5f};
  for (float x = w.zone_x0; x <= w.zone_x1 + 1e-3f; x += p.zone_period)
    for (float ry : rows) {
      const size_t first = w.prims.size();
      g.cylinder(kPole, g.id(), x, w.zone_y + ry, 0.0f, 0.3f, 4.5f);
      add_zone_instance(w, first, x, w.zone_y + ry, 0.3f);
    }
  *keep_out = {Rect{w.zone_x0 - 1e3f, w.zone_y - hw - sw - 0.2f, w.zone_x1 + 1e3f, w.zone_y + hw + sw + 0.2f}};
  if (!p.legacy_row_cues()) return;
  for (float x = w.zone_x0 - p.zone_period; x <= w.zone_x1 + p.zone_period; x += p.zone_period / 2)
    for (int side = -1; side <= 1; side += 2) {
      const size_t first = w.prims.size();
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
      for (size_t i = first; i < w.prims.size(); ++i) w.zone_cue_prims.push_back(static_cast<uint32_t>(i));
    }
}

// y of the grid road the approach leaves from, and the first x a zone instance may take.
float approach_y(const WorldParams& p) { return p.block_size * static_cast<float>(p.blocks_y / 2); }

// Aisles of a 2-D zone: x-aisles (along x) k = 0..ny at y0a + k * sy, from xa to xb; mapping drives the
// even ones (+x), queries the odd ones (-x, i.e. the other direction); y-aisles k = 0..nx at x0a + k * sx
// from ya to yb, queries only on odd k, in alternating directions (perpendicular crossings).
void add_aisles(World& w, std::vector<Rect>* keep_out, int nx, int ny, float x0a, float sx, float y0a, float sy,
                float xa, float xb, float ya, float yb) {
  constexpr float kAisleWidth = 3.0f;  // lanes 0.75 m off the aisle centre line
  constexpr float kClear = 2.25f;      // cues keep this far from a used aisle's centre line
  for (int k = 0; k <= ny; ++k) {
    const float y = y0a + k * sy;
    RoadSegment r{xa, y, xb, y, true};
    r.drives = (k % 2 == 0) ? kMapDrive : kQueryDrive;
    r.width = kAisleWidth;
    w.roads.push_back(r);
    keep_out->push_back(Rect{xa - 1e3f, y - kClear, xb + 1e3f, y + kClear});
  }
  for (int k = 1; k <= nx; k += 2) {
    const float x = x0a + k * sx;
    RoadSegment r = (k % 4 == 1) ? RoadSegment{x, ya, x, yb, true} : RoadSegment{x, yb, x, ya, true};
    r.drives = kQueryDrive;
    r.width = kAisleWidth;
    w.roads.push_back(r);
    keep_out->push_back(Rect{x - kClear, ya - 1e3f, x + kClear, yb + 1e3f});
  }
}

void approach_road(World& w, std::vector<Rect>* keep_out) {
  RoadSegment a{w.params.blocks_x * w.params.block_size, w.zone_y, w.zone_rect[0], w.zone_y, false};
  a.approach = true;
  w.roads.push_back(a);
  keep_out->push_back(Rect{a.x0, w.zone_y - w.params.road_width / 2 - w.params.sidewalk_width - 0.2f, a.x1 + 2.0f,
                           w.zone_y + w.params.road_width / 2 + w.params.sidewalk_width + 0.2f});
}

// A 2-D square lattice car park: lattice_nx x lattice_ny identical columns (pole, r 0.3 m, 4.5 m) at
// exactly (x0 + i s, y0 + j s); every gap between column rows is an aisle; parking floor.
void lattice_zone(Gen& g, std::vector<Rect>* keep_out) {
  World& w = g.w;
  const WorldParams& p = w.params;
  const float s = p.lattice_spacing;
  w.zone_y = approach_y(p);
  const float x0 = w.city_x1 + p.zone_margin;
  const float y0 = w.zone_y + s / 2 - static_cast<float>(p.lattice_ny / 2) * s;  // aisle ny/2 is the approach's
  const float x1 = x0 + (p.lattice_nx - 1) * s, y1 = y0 + (p.lattice_ny - 1) * s;
  w.zone_rect[0] = x0 - s;
  w.zone_rect[1] = y0 - s;
  w.zone_rect[2] = x1 + s;
  w.zone_rect[3] = y1 + s;
  w.zone_x0 = w.zone_rect[0];
  w.zone_x1 = w.zone_rect[2];
  for (int j = 0; j < p.lattice_ny; ++j)
    for (int i = 0; i < p.lattice_nx; ++i) {
      const float x = x0 + i * s, y = y0 + j * s;
      const size_t first = w.prims.size();
      g.cylinder(kPole, g.id(), x, y, 0.0f, 0.3f, 4.5f);
      add_zone_instance(w, first, x, y, 0.3f);
    }
  add_aisles(w, keep_out, p.lattice_nx, p.lattice_ny, x0 - s / 2, s, y0 - s / 2, s, w.zone_rect[0], w.zone_rect[2],
             w.zone_rect[1], w.zone_rect[3]);
  approach_road(w, keep_out);
}

// A pillared hall / open deck: hall_nx x hall_ny pillars (hall_dx x hall_dy apart; square 0.7 m boxes
// or 0.45 m-radius cylinders of pole class, 4 m) inside a low perimeter wall (building, one height in
// 1.2..3 m per hall) with entrance gaps placed 180-degree symmetrically; concrete (other-ground) floor.
void hall_zone(Gen& g, std::vector<Rect>* keep_out) {
  World& w = g.w;
  const WorldParams& p = w.params;
  const float dx = p.hall_dx, dy = p.hall_dy;
  w.zone_y = approach_y(p);
  const float x0 = w.city_x1 + p.zone_margin;
  const float y0 = w.zone_y + dy / 2 - static_cast<float>(p.hall_ny / 2) * dy;
  const float x1 = x0 + (p.hall_nx - 1) * dx, y1 = y0 + (p.hall_ny - 1) * dy;
  const float wx0 = x0 - dx / 2 - 4.0f, wx1 = x1 + dx / 2 + 4.0f, wy0 = y0 - dy / 2 - 3.5f, wy1 = y1 + dy / 2 + 3.5f;
  w.zone_rect[0] = wx0;
  w.zone_rect[1] = wy0;
  w.zone_rect[2] = wx1;
  w.zone_rect[3] = wy1;
  w.zone_x0 = wx0;
  w.zone_x1 = wx1;
  const bool square = g.chance(0.5f);
  const float half = square ? 0.35f : 0.45f;
  for (int j = 0; j < p.hall_ny; ++j)
    for (int i = 0; i < p.hall_nx; ++i) {
      const float x = x0 + i * dx, y = y0 + j * dy;
      const size_t first = w.prims.size();
      if (square) g.box(kPole, g.id(), x - half, y - half, 0.0f, x + half, y + half, 4.0f);
      else g.cylinder(kPole, g.id(), x, y, 0.0f, half, 4.0f);
      add_zone_instance(w, first, x, y, half);
    }
  // Walls with gaps: west at the approach aisle (ny/2), east at its 180-degree image, south at y-aisle 1,
  // north at its image (nx - 1).
  const float h = g.uni(1.2f, 3.0f), t = 0.3f;
  const int kc = p.hall_ny / 2;
  const float west_gap = y0 - dy / 2 + kc * dy, east_gap = y0 - dy / 2 + (p.hall_ny - kc) * dy;
  const float south_gap = x0 - dx / 2 + dx, north_gap = x0 - dx / 2 + (p.hall_nx - 1) * dx;
  auto wall_x = [&](float x, float gap) {  // a wall along y at x, gap centred at y = gap
    const float ga = gap - 3.5f, gb = gap + 3.5f;
    w.zone_structure_prims.push_back(static_cast<uint32_t>(w.prims.size()));
    g.box(kBuilding, 0, x - t / 2, wy0, 0.0f, x + t / 2, ga, h);
    w.zone_structure_prims.push_back(static_cast<uint32_t>(w.prims.size()));
    g.box(kBuilding, 0, x - t / 2, gb, 0.0f, x + t / 2, wy1, h);
  };
  auto wall_y = [&](float y, float gap) {
    const float ga = gap - 3.0f, gb = gap + 3.0f;
    w.zone_structure_prims.push_back(static_cast<uint32_t>(w.prims.size()));
    g.box(kBuilding, 0, wx0, y - t / 2, 0.0f, ga, y + t / 2, h);
    w.zone_structure_prims.push_back(static_cast<uint32_t>(w.prims.size()));
    g.box(kBuilding, 0, gb, y - t / 2, 0.0f, wx1, y + t / 2, h);
  };
  wall_x(wx0, west_gap);
  wall_x(wx1, east_gap);
  wall_y(wy0, south_gap);
  wall_y(wy1, north_gap);
  add_aisles(w, keep_out, p.hall_nx, p.hall_ny, x0 - dx / 2, dx, y0 - dy / 2, dy, wx0 + 1.5f, wx1 - 1.5f, wy0 + 1.5f,
             wy1 - 1.5f);
  approach_road(w, keep_out);
}

// A boulevard: the road continues from the city through avenue_length of two identical rows of trees
// (trunk + crown, one size) or lamp posts (pole + arm over the road), every avenue_period on both
// sides, and zone_margin beyond; nothing else instantiable; paved (other-ground) verges.
void avenue_zone(Gen& g, std::vector<Rect>* keep_out) {
  World& w = g.w;
  const WorldParams& p = w.params;
  const float hw = p.road_width / 2, sw = p.sidewalk_width, gx = p.blocks_x * p.block_size;
  w.zone_y = approach_y(p);
  w.zone_x0 = w.city_x1 + p.zone_margin;
  const int n = static_cast<int>(std::floor(p.avenue_length / p.avenue_period)) + 1;
  w.zone_x1 = w.zone_x0 + (n - 1) * p.avenue_period;
  w.zone_rect[0] = w.zone_x0;
  w.zone_rect[1] = w.zone_y - 40;
  w.zone_rect[2] = w.zone_x1;
  w.zone_rect[3] = w.zone_y + 40;
  w.roads.push_back(RoadSegment{gx, w.zone_y, w.zone_x1 + p.zone_margin, w.zone_y, true});
  const bool trees = g.chance(0.5f);
  const float off = hw + sw - 0.8f;
  for (int i = 0; i < n; ++i)
    for (int side = -1; side <= 1; side += 2) {
      const float x = w.zone_x0 + i * p.avenue_period, y = w.zone_y + side * off;
      const size_t first = w.prims.size();
      const uint32_t id = g.id();
      if (trees) {
        g.cylinder(kTrunk, id, x, y, 0.0f, 0.22f, 3.5f);
        g.sphere(kVegetation, 0, x, y, 4.75f, 2.2f);
      } else {  // lamp post: mast + arm reaching over the road
        g.cylinder(kPole, id, x, y, 0.0f, 0.13f, 8.0f);
        const float ya = y - side * 1.6f;
        g.box(kPole, id, x - 0.06f, std::min(y, ya), 7.8f, x + 0.06f, std::max(y, ya), 7.95f);
      }
      add_zone_instance(w, first, x, y, trees ? 0.22f : 0.13f);
    }
  *keep_out = {Rect{w.zone_x0 - 1e3f, w.zone_y - hw - sw - 0.2f, w.zone_x1 + 1e3f, w.zone_y + hw + sw + 0.2f}};
}

bool overlaps(const Rect& r, const float* lo, const float* hi) {
  return lo[0] < r.x1 && hi[0] > r.x0 && lo[1] < r.y1 && hi[1] > r.y0;
}

// Cues by cue_density: exactly round(density x N) repeated instances are drawn; each tries to get one cue
// (bush, hedge, terrain island, fence segment or low wall; random type, size and place 0.6..3.2 m off)
// whose footprint is within kCueRadius of it, clear of the drives' bands and farther than kCueRadius
// from every instance not drawn. Instances not drawn thus have nothing distinctive within 6 m.
void place_cues(Gen& g, const std::vector<Rect>& keep_out) {
  World& w = g.w;
  const size_t n = w.zone_instances.size();
  const float density = std::clamp(w.params.effective_cue_density(), 0.0f, 1.0f);
  const size_t k = std::min(n, static_cast<size_t>(std::lround(density * static_cast<float>(n))));
  std::vector<uint32_t> order(n);
  for (size_t i = 0; i < n; ++i) order[i] = static_cast<uint32_t>(i);
  for (size_t i = 0; i < k; ++i) std::swap(order[i], order[i + g.rng.uniform(static_cast<uint32_t>(n - i))]);
  std::vector<bool> drawn(n, false);
  for (size_t i = 0; i < k; ++i) drawn[order[i]] = true;
  std::sort(order.begin(), order.begin() + static_cast<long>(k));  // place in instance order
  for (size_t c = 0; c < k; ++c) {
    const ZoneInstance zi = w.zone_instances[order[c]];
    for (int attempt = 0; attempt < 80; ++attempt) {
      const int kind = static_cast<int>(g.rng.uniform(5));
      const float ang = g.uni(0.0f, 6.2831853f), d = g.uni(zi.radius + 0.6f, 3.2f);
      const float cx = zi.x + d * std::cos(ang), cy = zi.y + d * std::sin(ang);
      const bool along_x = g.chance(0.5f);
      Primitive q;
      if (kind == 0) {  // bush
        q = Primitive{Shape::Sphere, kVegetation, 0, {cx, cy, g.uni(0.1f, 0.4f)}, {g.uni(0.4f, 0.9f), 0, 0}};
      } else {
        float len = 0, wid = 0, h = 0;
        uint16_t sem = kVegetation;
        switch (kind) {
          case 1:
            sem = kVegetation;
            len = g.uni(1.2f, 2.6f);
            wid = g.uni(0.4f, 0.7f);
            h = g.uni(0.7f, 1.3f);
            break;  // hedge
          case 2:
            sem = kTerrain;
            len = g.uni(1.0f, 2.4f);
            wid = g.uni(0.8f, 1.8f);
            h = 0.15f;
            break;  // island
          case 3:
            sem = kFence;
            len = g.uni(1.0f, 2.6f);
            wid = 0.06f;
            h = g.uni(1.0f, 1.7f);
            break;  // fence
          default:
            sem = kBuilding;
            len = g.uni(1.0f, 2.6f);
            wid = 0.25f;
            h = g.uni(0.6f, 1.4f);
            break;  // low wall
        }
        const float hx = (along_x ? len : wid) / 2, hy = (along_x ? wid : len) / 2;
        q = Primitive{Shape::Box, sem, 0, {cx - hx, cy - hy, 0.0f}, {cx + hx, cy + hy, h}};
      }
      float lo[2], hi[2];
      if (q.shape == Shape::Box) {
        lo[0] = q.a[0];
        lo[1] = q.a[1];
        hi[0] = q.b[0];
        hi[1] = q.b[1];
      } else {
        lo[0] = q.a[0] - q.b[0];
        lo[1] = q.a[1] - q.b[0];
        hi[0] = q.a[0] + q.b[0];
        hi[1] = q.a[1] + q.b[0];
      }
      bool ok = xy_distance(q, zi.x, zi.y) <= kCueRadius - 0.5f;
      for (const Rect& r : keep_out) ok = ok && !overlaps(r, lo, hi);
      for (size_t j = 0; j < n && ok; ++j) {
        const ZoneInstance& o = w.zone_instances[j];
        const float dist = xy_distance(q, o.x, o.y);
        ok = dist >= o.radius + 0.3f && (drawn[j] || dist > kCueRadius + 0.25f);
      }
      if (!ok) continue;
      w.zone_cue_prims.push_back(static_cast<uint32_t>(w.prims.size()));
      w.prims.push_back(q);
      break;
    }
  }
}

// The road grid (and the row zone's road), and where the repetitive zone lies along x.
void lay_roads(World& w, const WorldParams& p) {
  const float B = p.block_size;
  const float gx = p.blocks_x * B, gy = p.blocks_y * B;
  for (int j = 0; j <= p.blocks_y; ++j) w.roads.push_back(RoadSegment{0, j * B, gx, j * B, false});
  for (int i = 0; i <= p.blocks_x; ++i) w.roads.push_back(RoadSegment{i * B, 0, i * B, gy, false});
  w.zone_y = 0.0f;
  w.zone_x0 = gx + p.zone_margin;
  w.zone_x1 = w.zone_x0 + p.zone_length;
  if (p.repetitive_zone && p.zone == ZoneType::Row)
    w.roads.push_back(RoadSegment{gx, 0.0f, w.zone_x1 + p.zone_margin, 0.0f, true});
}

// Whether `along` a grid road is within `margin` of a crossing's sidewalks.
bool near_crossing(const WorldParams& p, float along, float margin) {
  const float B = p.block_size, hw = p.road_width / 2, sw = p.sidewalk_width;
  const float m = std::fmod(along, B);
  return m < hw + sw + margin || m > B - hw - sw - margin;
}

// Street furniture along both sides of every grid road: poles (some with signs), trees, parked cars.
void furnish_roads(Gen& g) {
  const WorldParams& p = g.w.params;
  const float B = p.block_size, hw = p.road_width / 2, sw = p.sidewalk_width;
  const float gx = p.blocks_x * B, gy = p.blocks_y * B;
  for (int j = 0; j <= p.blocks_y; ++j)
    for (int side = -1; side <= 1; side += 2) {
      const float y = j * B;
      if ((j == 0 && side < 0) || (j == p.blocks_y && side > 0)) {}  // outer edges still get furniture
      for (float x = g.uni(3, 12); x < gx; x += g.uni(22, 38))
        if (!near_crossing(p, x, 2)) g.pole(x, y + side * (hw + 0.4f), g.chance(0.3f), 0, -float(side));
      if (g.chance(0.7f))
        for (float x = g.uni(4, 10); x < gx; x += g.uni(11, 19))
          if (!near_crossing(p, x, 3)) g.tree(x, y + side * (hw + sw - 0.8f));
      for (float x = g.uni(5, 12); x < gx; x += g.uni(6.5f, 9.5f))
        if (!near_crossing(p, x, 6) && g.chance(0.55f)) g.car(x, y + side * (hw - 1.2f), true);
    }
  for (int i = 0; i <= p.blocks_x; ++i)
    for (int side = -1; side <= 1; side += 2) {
      const float x = i * B;
      for (float y = g.uni(3, 12); y < gy; y += g.uni(22, 38))
        if (!near_crossing(p, y, 2)) g.pole(x + side * (hw + 0.4f), y, g.chance(0.3f), -float(side), 0);
      if (g.chance(0.6f))
        for (float y = g.uni(4, 10); y < gy; y += g.uni(11, 19))
          if (!near_crossing(p, y, 3)) g.tree(x + side * (hw + sw - 0.8f), y);
      for (float y = g.uni(5, 12); y < gy; y += g.uni(6.5f, 9.5f))
        if (!near_crossing(p, y, 6) && g.chance(0.5f)) g.car(x + side * (hw - 1.2f), y, false);
    }
}

// One block (bi, bj): buildings around the perimeter, a fence, bushes, a standalone sign, a parking lot.
void fill_block(Gen& g, int bi, int bj) {
  const WorldParams& p = g.w.params;
  const float B = p.block_size, hw = p.road_width / 2, sw = p.sidewalk_width;
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
  for (int k = 0; k < 6; ++k)
    g.bush(g.uni(x0 + 1, x1 - 1), g.chance(0.5f) ? y0 + g.uni(0.5f, 2.0f) : y1 - g.uni(0.5f, 2.0f));
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

// The repetitive zone of the world's type, its distinctive cues, and which of its instances have one.
void add_repetitive_zone(Gen& g) {
  World& w = g.w;
  std::vector<Rect> keep_out;  // bands the drives use: cues stay out of them
  switch (w.params.zone) {
    case ZoneType::Row: row_zone(g, &keep_out); break;
    case ZoneType::Lattice: lattice_zone(g, &keep_out); break;
    case ZoneType::Hall: hall_zone(g, &keep_out); break;
    case ZoneType::Avenue: avenue_zone(g, &keep_out); break;
  }
  if (!w.params.legacy_row_cues()) place_cues(g, keep_out);
  for (ZoneInstance& zi : w.zone_instances) {
    zi.cued = false;
    for (uint32_t c : w.zone_cue_prims) zi.cued = zi.cued || xy_distance(w.prims[c], zi.x, zi.y) <= kCueRadius;
  }
}

// World bounds: the grid and the zone with 40 m around.
void set_bounds(World& w) {
  const WorldParams& p = w.params;
  const float gx = p.blocks_x * p.block_size, gy = p.blocks_y * p.block_size;
  w.min_xy[0] = -40;
  w.min_xy[1] = -40;
  w.max_xy[0] = (p.repetitive_zone ? w.zone_x1 + p.zone_margin : gx) + 40;
  w.max_xy[1] = gy + 40;
  if (p.repetitive_zone && p.zone != ZoneType::Row) {
    for (const RoadSegment& r : w.roads) w.max_xy[0] = std::max(w.max_xy[0], std::max(r.x0, r.x1) + 40);
    w.min_xy[1] = std::min(w.min_xy[1], w.zone_rect[1] - 40);
    w.max_xy[0] = std::max(w.max_xy[0], w.zone_rect[2] + 40);
    w.max_xy[1] = std::max(w.max_xy[1], w.zone_rect[3] + 40);
  }
}

}  // namespace

World generate_world(const WorldParams& p) {
  World w;
  w.params = p;
  Gen g{w, gsf::Rng(p.seed)};
  lay_roads(w, p);
  furnish_roads(g);
  for (int bi = 0; bi < p.blocks_x; ++bi)
    for (int bj = 0; bj < p.blocks_y; ++bj) fill_block(g, bi, bj);
  const float gx = p.blocks_x * p.block_size, hw = p.road_width / 2, sw = p.sidewalk_width;
  w.city_x1 = gx + hw + sw;  // poles, trees and cars of the grid stay within the outer sidewalks
  if (p.repetitive_zone) add_repetitive_zone(g);
  set_bounds(w);
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
      if (car_action == 2) {
        q.a[0] += dx;
        q.b[0] += dx;
        q.a[1] += dy;
        q.b[1] += dy;
      }
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
