#include "label_errors/label_errors.h"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "gsf/detail/bounded_hash_map.h"  // mix64
#include "gsf/detail/rng.h"

namespace gsf::label_errors {
namespace {

struct LabelPartners {
  uint16_t semantic;
  uint16_t partner[2];
  int count;
};
// SemanticKITTI ids (the simulator's classes); first partner the likelier (3 of 4 confusions when two).
constexpr LabelPartners kKittiPartners[] = {
    {10, {18, 20}, 2},  // car -> truck / other-vehicle
    {40, {48, 44}, 2},  // road -> sidewalk / parking
    {44, {40, 48}, 2},  // parking -> road / sidewalk
    {48, {40, 72}, 2},  // sidewalk -> road / terrain
    {49, {48, 40}, 2},  // other-ground -> sidewalk / road
    {50, {51, 0}, 1},   // building -> fence
    {51, {50, 70}, 2},  // fence -> building / vegetation
    {70, {72, 71}, 2},  // vegetation -> terrain / trunk
    {71, {80, 70}, 2},  // trunk -> pole / vegetation
    {72, {70, 48}, 2},  // terrain -> vegetation / sidewalk
    {80, {71, 81}, 2},  // pole -> trunk / traffic-sign
    {81, {80, 0}, 1},   // traffic-sign -> pole
};
// Raw nuScenes-lidarseg classes. The pairs a network on nuScenes mixes up: vehicle types among
// themselves, the flat classes with their neighbours, terrain with vegetation, manmade with vegetation
// (walls behind hedges, poles among trees), barriers with manmade and traffic cones.
constexpr LabelPartners kNuScenesPartners[] = {
    {2, {28, 14}, 2},   // pedestrian.adult -> manmade / bicycle
    {3, {2, 28}, 2},    // pedestrian.child -> adult / manmade
    {4, {2, 28}, 2},    // construction_worker -> adult / manmade
    {5, {2, 28}, 2},    // personal_mobility -> adult / manmade
    {6, {2, 28}, 2},    // police_officer -> adult / manmade
    {7, {2, 28}, 2},    // stroller -> adult / manmade
    {8, {2, 28}, 2},    // wheelchair -> adult / manmade
    {9, {28, 12}, 2},   // barrier -> manmade / traffic cone
    {10, {29, 24}, 2},  // debris -> static.other / driveable surface
    {11, {29, 9}, 2},   // pushable_pullable -> static.other / barrier
    {12, {9, 29}, 2},   // traffic cone -> barrier / static.other
    {13, {28, 14}, 2},  // bicycle rack -> manmade / bicycle
    {14, {21, 13}, 2},  // bicycle -> motorcycle / bicycle rack
    {15, {16, 23}, 2},  // bus.bendy -> bus.rigid / truck
    {16, {23, 15}, 2},  // bus.rigid -> truck / bus.bendy
    {17, {23, 18}, 2},  // car -> truck / construction vehicle
    {18, {23, 17}, 2},  // construction vehicle -> truck / car
    {19, {23, 17}, 2},  // ambulance -> truck / car
    {20, {17, 23}, 2},  // police car -> car / truck
    {21, {14, 0}, 1},   // motorcycle -> bicycle
    {22, {23, 18}, 2},  // trailer -> truck / construction vehicle
    {23, {17, 22}, 2},  // truck -> car / trailer
    {24, {26, 25}, 2},  // driveable surface -> sidewalk / flat.other
    {25, {26, 24}, 2},  // flat.other -> sidewalk / driveable surface
    {26, {24, 27}, 2},  // sidewalk -> driveable surface / terrain
    {27, {30, 26}, 2},  // terrain -> vegetation / sidewalk
    {28, {30, 29}, 2},  // manmade -> vegetation / static.other
    {29, {28, 30}, 2},  // static.other -> manmade / vegetation
    {30, {28, 27}, 2},  // vegetation -> manmade / terrain
};

const LabelPartners* partners_of(uint16_t sem, LabelSpace space) {
  if (space == LabelSpace::NuScenesLidarseg) {
    for (const auto& p : kNuScenesPartners)
      if (p.semantic == sem) return &p;
    return nullptr;
  }
  for (const auto& p : kKittiPartners)
    if (p.semantic == sem) return &p;
  return nullptr;
}

// The partner class chosen by `pick` (uniform in 0..3): the first, likelier one 3 times in 4 when there
// are two; the class itself when it has none.
uint16_t drawn_partner(uint16_t semantic, uint32_t pick, LabelSpace space) {
  const int n = label_partner_count(semantic, space);
  return label_partner(semantic, (n > 1 && pick == 3) ? 1 : 0, space);
}

}  // namespace

const char* label_space_name(LabelSpace space) {
  return space == LabelSpace::NuScenesLidarseg ? "nuscenes-lidarseg" : "semantic-kitti";
}

int label_partner_count(uint16_t semantic, LabelSpace space) {
  const LabelPartners* p = partners_of(semantic, space);
  return p ? p->count : 0;
}

uint16_t label_partner(uint16_t semantic, int k, LabelSpace space) {
  const LabelPartners* p = partners_of(semantic, space);
  return p && k >= 0 && k < p->count ? p->partner[k] : semantic;
}

void apply_label_noise(uint32_t* labels, uint32_t count, float p, uint64_t seed, LabelSpace space) {
  gsf::Rng rng(seed);
  for (uint32_t i = 0; i < count; ++i) {
    const float u = rng.uniform01();
    const uint32_t pick = rng.uniform(4);  // drawn for every point: the stream does not depend on labels
    if (u >= p) continue;
    const uint16_t sem = static_cast<uint16_t>(labels[i] & 0xFFFFu);
    labels[i] = (labels[i] & 0xFFFF0000u) | drawn_partner(sem, pick, space);
  }
}

void apply_object_confusion(uint32_t* labels, uint32_t count, float p, uint64_t seed) {
  uint32_t drawn_for = 0;  // the instance whose draw `confused` / `pick` hold (points come in runs)
  bool confused = false;
  uint32_t pick = 0;
  for (uint32_t i = 0; i < count; ++i) {
    const uint32_t instance = labels[i] >> 16;
    if (instance == 0) continue;  // stuff: no object to confuse
    if (instance != drawn_for) {
      gsf::Rng rng(gsf::mix64(seed ^ gsf::mix64(instance)));
      confused = rng.uniform01() < p;
      pick = rng.uniform(4);
      drawn_for = instance;
    }
    if (confused)
      labels[i] =
          (labels[i] & 0xFFFF0000u) | drawn_partner(static_cast<uint16_t>(labels[i]), pick, LabelSpace::SemanticKitti);
  }
}

float thin_miss_probability(float p, float range) {
  return p * std::clamp((range - kThinMissNear) / (kThinMissFar - kThinMissNear), 0.0f, 1.0f);
}

void apply_thin_miss(const float* xyzi, uint32_t* labels, uint32_t count, float p, uint64_t seed) {
  gsf::Rng rng(seed);
  for (uint32_t i = 0; i < count; ++i) {
    const float u = rng.uniform01();  // drawn for every point: the stream does not depend on labels
    const uint16_t sem = static_cast<uint16_t>(labels[i] & 0xFFFFu);
    if (sem != 80 && sem != 81 && sem != 71) continue;
    if (u >= thin_miss_probability(p, std::hypot(xyzi[4 * i], xyzi[4 * i + 1]))) continue;
    labels[i] = sem == 71 ? 70u : 50u;  // trunk -> vegetation; pole, sign -> building
  }
}

void apply_spurious_objects(const float* xyzi, uint32_t* labels, uint32_t count, float p, uint64_t seed) {
  if (count == 0 || p <= 0.0f) return;
  std::vector<uint32_t> ids;
  for (uint32_t i = 0; i < count; ++i)
    if (labels[i] >> 16) ids.push_back(labels[i] >> 16);
  std::sort(ids.begin(), ids.end());
  const size_t instances = size_t(std::unique(ids.begin(), ids.end()) - ids.begin());
  gsf::Rng rng(seed);
  const uint32_t n = static_cast<uint32_t>(std::floor(p * float(instances) + rng.uniform01()));
  for (uint32_t k = 0; k < n; ++k) {
    for (int attempt = 0; attempt < 64; ++attempt) {  // a wall or hedge point in range, if the scan has one
      const uint32_t s = rng.uniform(count);
      const uint16_t sem = static_cast<uint16_t>(labels[s] & 0xFFFFu);
      const float r = std::hypot(xyzi[4 * s], xyzi[4 * s + 1]);
      if ((sem != 50 && sem != 70) || !(r >= kSpuriousNear && r <= kSpuriousFar)) continue;
      const float cx = xyzi[4 * s], cy = xyzi[4 * s + 1];
      const uint32_t word = (kSpuriousInstanceBase + k) << 16;
      for (uint32_t i = 0; i < count; ++i) {
        const uint16_t c = static_cast<uint16_t>(labels[i] & 0xFFFFu);
        if ((c == 50 || c == 70) && std::hypot(xyzi[4 * i] - cx, xyzi[4 * i + 1] - cy) <= kSpuriousRadius)
          labels[i] = word | (c == 50 ? 80u : 71u);
      }
      break;
    }
  }
}

namespace {

// Object grouping without instance ids: points of one class in 26-connected cells of a kObjectCell grid.
// Cell keys pack (class, x, y, z) so that sorting them orders cells by class first; the cell indices are
// kept within 1..65534 so every neighbour key is a plain offset of the key.
constexpr int64_t kCellBias = 32768;

bool object_cell_key(uint16_t cls, const float* xyz, uint64_t* key) {
  uint64_t packed = uint64_t(cls) << 48;
  for (int a = 0; a < 3; ++a) {
    if (!std::isfinite(xyz[a])) return false;
    const double c = std::floor(double(xyz[a]) / kObjectCell) + double(kCellBias);
    if (!(c >= 1.0 && c <= 65534.0)) return false;  // beyond 16 km: not grouped
    packed |= uint64_t(c) << (32 - 16 * a);
  }
  *key = packed;
  return true;
}

int cell_coord(uint64_t key, int axis) { return static_cast<int>((key >> (32 - 16 * axis)) & 0xFFFFu); }

// Whether a component's class only counts as an object when thin (nuScenes static.manmade,
// static.vegetation: their poles and trunks are objects, their walls and hedges are not).
bool needs_thin_extent(uint16_t cls, LabelSpace space) {
  return space == LabelSpace::NuScenesLidarseg && (cls == 28 || cls == 30);
}

struct ObjectCells {
  std::vector<std::pair<uint64_t, uint32_t>> point_cells;  // (cell key, point), sorted
  std::vector<uint64_t> cells;                             // unique keys, sorted
  std::vector<uint32_t> cell_of;                           // per point_cells entry: index into cells
};

ObjectCells collect_object_cells(const float* xyzi, const uint32_t* labels, uint32_t count, LabelSpace space) {
  ObjectCells oc;
  for (uint32_t i = 0; i < count; ++i) {
    const uint16_t cls = static_cast<uint16_t>(labels[i] & 0xFFFFu);
    uint64_t key;
    if ((labels[i] >> 16) != 0 || !object_component_class(cls, space)) continue;  // instances have their ids
    if (object_cell_key(cls, xyzi + 4 * size_t(i), &key)) oc.point_cells.emplace_back(key, i);
  }
  std::sort(oc.point_cells.begin(), oc.point_cells.end());  // by key: the order of the points does not matter
  oc.cell_of.reserve(oc.point_cells.size());
  for (const auto& pc : oc.point_cells) {
    if (oc.cells.empty() || oc.cells.back() != pc.first) oc.cells.push_back(pc.first);
    oc.cell_of.push_back(static_cast<uint32_t>(oc.cells.size() - 1));
  }
  return oc;
}

uint32_t find_root(std::vector<uint32_t>& parent, uint32_t c) {
  while (parent[c] != c) c = parent[c] = parent[parent[c]];  // path halving
  return c;
}

// Union-find over the sorted cells, 26-connected within a class; each root is its component's smallest
// cell (the smaller root always wins), a key that does not depend on the point order.
std::vector<uint32_t> connect_cells(const std::vector<uint64_t>& cells) {
  std::vector<uint32_t> parent(cells.size());
  for (uint32_t c = 0; c < parent.size(); ++c) parent[c] = c;
  for (uint32_t c = 0; c < cells.size(); ++c)
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const int64_t offset = int64_t(dx) * (int64_t(1) << 32) + int64_t(dy) * (int64_t(1) << 16) + dz;
          if (offset <= 0) continue;  // each pair once, from its smaller key
          const uint64_t nb = cells[c] + uint64_t(offset);
          const auto it = std::lower_bound(cells.begin() + c, cells.end(), nb);
          if (it == cells.end() || *it != nb) continue;
          const uint32_t a = find_root(parent, c), b = find_root(parent, uint32_t(it - cells.begin()));
          if (a != b) parent[std::max(a, b)] = std::min(a, b);
        }
  // parent[c] <= c throughout, so in increasing order each parent is a root already when c is reached.
  for (uint32_t c = 0; c < parent.size(); ++c) parent[c] = parent[parent[c]];
  return parent;
}

// Per root cell: whether its component is an object (thin enough where the class needs it).
std::vector<bool> object_roots(const std::vector<uint64_t>& cells, const std::vector<uint32_t>& root,
                               LabelSpace space) {
  std::vector<int> lo(cells.size() * 2, 65535), hi(cells.size() * 2, 0);
  for (uint32_t c = 0; c < cells.size(); ++c)
    for (int a = 0; a < 2; ++a) {
      lo[2 * root[c] + a] = std::min(lo[2 * root[c] + a], cell_coord(cells[c], a));
      hi[2 * root[c] + a] = std::max(hi[2 * root[c] + a], cell_coord(cells[c], a));
    }
  std::vector<bool> object(cells.size(), false);
  const int thin_cells = static_cast<int>(std::floor(kThinObjectExtent / kObjectCell + 1e-3f));
  for (uint32_t c = 0; c < cells.size(); ++c) {
    if (root[c] != c) continue;
    const bool thin = hi[2 * c] - lo[2 * c] < thin_cells && hi[2 * c + 1] - lo[2 * c + 1] < thin_cells;
    object[c] = thin || !needs_thin_extent(static_cast<uint16_t>(cells[c] >> 48), space);
  }
  return object;
}

}  // namespace

bool object_component_class(uint16_t semantic, LabelSpace space) {
  if (space == LabelSpace::NuScenesLidarseg)
    return (semantic >= 2 && semantic <= 23) || semantic == 28 || semantic == 30;
  return semantic == 10 || semantic == 71 || semantic == 80 || semantic == 81;
}

void apply_component_confusion(const float* xyzi, uint32_t* labels, uint32_t count, float p, uint64_t seed,
                               LabelSpace space) {
  if (!(p > 0)) return;
  const ObjectCells oc = collect_object_cells(xyzi, labels, count, space);
  const std::vector<uint32_t> root = connect_cells(oc.cells);
  const std::vector<bool> object = object_roots(oc.cells, root, space);
  std::vector<uint16_t> to(oc.cells.size(), 0);  // per root: the partner it becomes; 0 (no partner is 0): kept
  for (uint32_t c = 0; c < oc.cells.size(); ++c) {
    if (root[c] != c || !object[c]) continue;
    gsf::Rng rng(gsf::mix64(seed ^ gsf::mix64(oc.cells[c])));
    const bool confused = rng.uniform01() < p;
    const uint32_t pick = rng.uniform(4);
    const uint16_t cls = static_cast<uint16_t>(oc.cells[c] >> 48);
    if (confused && label_partner_count(cls, space) > 0) to[c] = drawn_partner(cls, pick, space);
  }
  for (size_t k = 0; k < oc.point_cells.size(); ++k) {
    const uint16_t t = to[root[oc.cell_of[k]]];
    if (t != 0) labels[oc.point_cells[k].second] = t;  // instance id 0 (grouped points have none)
  }
}

void apply_label_errors(const LabelErrorRates& rates, LabelSpace space, const float* xyzi, uint32_t* labels,
                        uint32_t count, uint64_t scan_seed) {
  if (rates.object_confusion > 0) {
    const uint64_t seed = gsf::mix64(scan_seed ^ kObjectSalt);
    if (space == LabelSpace::SemanticKitti) apply_object_confusion(labels, count, rates.object_confusion, seed);
    apply_component_confusion(xyzi, labels, count, rates.object_confusion, gsf::mix64(seed ^ kComponentSalt), space);
  }
  if (rates.thin_miss > 0 && space == LabelSpace::SemanticKitti)
    apply_thin_miss(xyzi, labels, count, rates.thin_miss, gsf::mix64(scan_seed ^ kThinSalt));
  if (rates.label_noise > 0)
    apply_label_noise(labels, count, rates.label_noise, gsf::mix64(scan_seed ^ kNoiseSalt), space);
}

uint64_t real_scan_seed(uint64_t noise_seed, const std::string& sequence, uint32_t frame) {
  uint64_t name = 0xCBF29CE484222325ULL;  // FNV-1a of the sequence's name
  for (const char ch : sequence) name = (name ^ static_cast<uint8_t>(ch)) * 0x100000001B3ULL;
  return gsf::mix64(gsf::mix64(noise_seed ^ gsf::mix64(name)) + frame);
}

}  // namespace gsf::label_errors
