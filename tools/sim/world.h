// Procedural semantic urban world for the simulator: a road grid with sidewalks, parking strips,
// terrain, buildings, fences, trees (trunk + crown), bushes, poles, traffic signs and parked cars, plus
// the repetitive zone of the paper's Fig. 1: a long road lined by a lattice of identical columns whose
// instance layout repeats by translation, told apart only by irregular "stuff" around them.
// Geometry is simple primitives (axis-aligned boxes, vertical cylinders, spheres) over a z = 0 ground
// whose class comes from the road layout. Every object carries a SemanticKITTI id and, for things, a
// stable instance id.
#pragma once
#include <cstdint>
#include <vector>

namespace gsf::sim {

enum class Shape : uint8_t { Box, Cylinder, Sphere };

struct Primitive {
  Shape shape;
  uint16_t semantic;   // SemanticKITTI id
  uint32_t instance;   // 0 for stuff
  float a[3];          // Box: min corner; Cylinder: base centre; Sphere: centre
  float b[3];          // Box: max corner; Cylinder: (radius, height, 0); Sphere: (radius, 0, 0)
};

struct WorldParams {
  uint64_t seed = 1;
  int blocks_x = 4, blocks_y = 3;   // city blocks of the road grid
  float block_size = 100.0f;        // m between road centre lines
  float road_width = 10.0f;         // m
  float sidewalk_width = 3.0f;      // m
  bool repetitive_zone = true;
  float zone_length = 300.0f;       // m of road inside the zone
  float zone_period = 10.0f;        // m; the column lattice repeats by this translation
  float zone_margin = 60.0f;        // m without other instances before/after the zone
};

// Roads as centre-line segments (axis-aligned), for drives.
struct RoadSegment {
  float x0, y0, x1, y1;
  bool in_zone;
};

struct World {
  WorldParams params;
  std::vector<Primitive> prims;
  std::vector<RoadSegment> roads;
  float min_xy[2] = {0, 0}, max_xy[2] = {0, 0};
  float zone_x0 = 0, zone_x1 = 0, zone_y = 0;  // the zone road runs along y = zone_y, x in [x0, x1]
  uint32_t next_instance = 1;

  // Ground class (SemanticKITTI id) at (x, y).
  uint16_t ground_class(float x, float y) const;
  bool in_zone(float x, float y) const;
  float road_length() const;
};

World generate_world(const WorldParams& params);

struct TimeGapParams {
  uint64_t seed = 99;
  float cars_removed = 0.25f;   // share of parked cars gone
  float cars_moved = 0.20f;     // share moved a few metres along the kerb
  float vegetation_change = 0.25f;  // relative growth/shrink of crowns and bushes
  float bushes_cut = 0.10f;     // share of bushes removed
};
// The same world "months later": cars moved/removed, vegetation grown/cut; infrastructure identical.
World apply_time_gap(const World& world, const TimeGapParams& params);

}  // namespace gsf::sim
