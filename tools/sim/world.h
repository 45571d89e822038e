// Procedural semantic urban world for the simulator: a road grid with sidewalks, parking strips,
// terrain, buildings, fences, trees (trunk + crown), bushes, poles, traffic signs and parked cars, plus
// one repetitive zone whose instance layout repeats, told apart only by irregular "stuff" (cues):
//   row     the paper's Fig. 1: a long road lined by four rows of identical columns (1-D translation);
//   lattice a 2-D square lattice car park of identical columns (90/180 deg rotations + 2-D translations);
//   hall    a pillared hall / open deck: a rectangular pillar lattice inside low perimeter walls;
//   avenue  a straight road between two identical rows of trees or lamp posts.
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
  uint16_t semantic;  // SemanticKITTI id
  uint32_t instance;  // 0 for stuff
  float a[3];         // Box: min corner; Cylinder: base centre; Sphere: centre
  float b[3];         // Box: max corner; Cylinder: (radius, height, 0); Sphere: (radius, 0, 0)
};

enum class ZoneType : uint8_t { Row = 0, Lattice = 1, Hall = 2, Avenue = 3 };
const char* zone_name(ZoneType zone);
bool parse_zone(const char* name, ZoneType* out);  // "row", "lattice", "hall", "avenue"

struct WorldParams {
  uint64_t seed = 1;
  int blocks_x = 4, blocks_y = 3;  // city blocks of the road grid
  float block_size = 100.0f;       // m between road centre lines
  float road_width = 10.0f;        // m
  float sidewalk_width = 3.0f;     // m
  bool repetitive_zone = true;
  float zone_length = 300.0f;  // m of road inside the zone
  float zone_period = 10.0f;   // m; the column lattice repeats by this translation
  float zone_margin = 60.0f;   // m without other instances before/after the zone
  ZoneType zone = ZoneType::Row;
  // Share (0..1) of the zone's repeated instances that get one distinctive cue (bush, hedge, terrain
  // island, fence segment or low wall) within 6 m; the others have nothing but repeated structure and
  // plain floor within 6 m. < 0: the zone's default: for `row` the legacy per-half-period stuff and
  // ground patches (demo/tiny, friendly: nearly every column has stuff beside it), 0.5 otherwise.
  float cue_density = -1.0f;
  int lattice_nx = 6, lattice_ny = 4;  // lattice: columns along x, rows along y
  float lattice_spacing = 8.0f;        // m, both directions (square lattice)
  int hall_nx = 8, hall_ny = 3;        // hall: pillars along x, rows along y
  float hall_dx = 10.0f, hall_dy = 7.5f;
  float avenue_length = 240.0f;  // m of avenue (trees or lamp posts on both sides)
  float avenue_period = 12.0f;   // m between consecutive trees / lamp posts

  bool legacy_row_cues() const { return zone == ZoneType::Row && cue_density < 0.0f; }
  float effective_cue_density() const { return cue_density < 0.0f ? 0.5f : cue_density; }
};

// Which drives use a road segment.
constexpr uint8_t kMapDrive = 1, kQueryDrive = 2;

// Roads as centre-line segments (axis-aligned), for drives.
struct RoadSegment {
  float x0, y0, x1, y1;
  bool in_zone;
  uint8_t drives = kMapDrive | kQueryDrive;
  float width = 0.0f;     // m; 0 = params.road_width (lanes are a quarter of it off the centre line)
  bool approach = false;  // the approach road into a lattice / hall zone (queries denser)
};

// A repeated instance of the zone (column, pillar, tree, lamp post) and whether it got a cue.
struct ZoneInstance {
  uint32_t id;
  float x, y;    // footprint centre
  float radius;  // footprint half-size
  bool cued;
};

struct World {
  WorldParams params;
  std::vector<Primitive> prims;
  std::vector<RoadSegment> roads;
  float min_xy[2] = {0, 0}, max_xy[2] = {0, 0};
  float zone_x0 = 0, zone_x1 = 0, zone_y = 0;  // the zone road runs along y = zone_y, x in [x0, x1]
  float zone_rect[4] = {0, 0, 0, 0};           // x0, y0, x1, y1: the zone (in_zone) as a rectangle
  uint32_t next_instance = 1;
  // Bookkeeping of the generated zone (the world before any time gap): its repeated instances, the
  // primitives that make them up, the cue primitives and the regular structure (hall walls).
  std::vector<ZoneInstance> zone_instances;
  std::vector<uint32_t> zone_repeated_prims, zone_cue_prims, zone_structure_prims;
  float city_x1 = 0;  // largest x any city instance can reach

  // Ground class (SemanticKITTI id) at (x, y).
  uint16_t ground_class(float x, float y) const;
  bool in_zone(float x, float y) const;
  // Within kNearZone m of the zone rectangle but not inside.
  bool near_zone(float x, float y) const;
  float road_length() const;
};

constexpr float kNearZone = 60.0f;
constexpr float kCueRadius = 6.0f;  // "nothing distinctive within 6 m"

// Horizontal distance from (x, y) to a primitive's footprint (0 inside).
float xy_distance(const Primitive& p, float x, float y);

World generate_world(const WorldParams& params);

struct TimeGapParams {
  uint64_t seed = 99;
  float cars_removed = 0.25f;       // share of parked cars gone
  float cars_moved = 0.20f;         // share moved a few metres along the kerb
  float vegetation_change = 0.25f;  // relative growth/shrink of crowns and bushes
  float bushes_cut = 0.10f;         // share of bushes removed
};
// The same world "months later": cars moved/removed, vegetation grown/cut; infrastructure identical.
World apply_time_gap(const World& world, const TimeGapParams& params);

}  // namespace gsf::sim
