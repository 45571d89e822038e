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

}  // namespace gsf::label_errors
