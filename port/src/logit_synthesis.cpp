#include "gsf/port/logit_synthesis.h"

#include <cmath>

#include "gsf/detail/bounded_hash_map.h"
#include "gsf/detail/rng.h"
#include "gsf/semantic_classes.h"

namespace gsf::port {
namespace {

struct Confusion {
  float p;
  int n;
  int partners[3];
};

Confusion confusion_of(int c) {
  switch (c) {
    case kVegetation: return {0.08f, 1, {kTerrain}};
    case kTerrain: return {0.08f, 2, {kVegetation, kSidewalk}};
    case kPole: return {0.10f, 2, {kTrunk, kTrafficSign}};
    case kTrunk: return {0.08f, 2, {kPole, kVegetation}};
    case kTrafficSign: return {0.10f, 1, {kPole}};
    case kCar: return {0.04f, 2, {kTruck, kOtherVehicle}};
    case kRoad: return {0.03f, 1, {kParking}};
    case kParking: return {0.10f, 2, {kRoad, kSidewalk}};
    case kSidewalk: return {0.05f, 2, {kTerrain, kParking}};
    case kBuilding: return {0.04f, 1, {kFence}};
    case kFence: return {0.10f, 1, {kBuilding}};
    default: return {0.0f, 0, {0}};
  }
}

}  // namespace

float confusion_probability(int c) { return confusion_of(c).p; }
int confusion_partner_count(int c) { return confusion_of(c).n; }
int confusion_partner(int c, int k) { return confusion_of(c).partners[k]; }

void synthesize_logits(const LogitModel& m, uint64_t scan_id, const uint32_t* labels, uint32_t count, float* out,
                       uint32_t* relabel, const ClassTable* classes) {
  // Library class -> the label set's lowest raw id of it (UINT32_MAX: none), for relabelling.
  uint32_t raw_of[kNumClasses];
  for (int c = 0; c < kNumClasses; ++c) raw_of[c] = classes ? UINT32_MAX : kitti_from_class(c);
  if (classes)
    for (uint32_t e = classes->size(); e-- > 0;) {  // raw-id order, backwards: the lowest id wins
      const ClassTableEntry& en = classes->entry(e);
      if (en.library_class >= 0) raw_of[en.library_class] = en.raw_id;
    }
  for (uint32_t i = 0; i < count; ++i) {
    gsf::Rng rng(gsf::mix64(m.seed ^ gsf::mix64(scan_id * 0x9E3779B97F4A7C15ULL + i)));
    float* l = out + size_t(i) * kNumClasses;
    for (int k = 0; k < kNumClasses; k += 2) {  // Box-Muller pairs
      const float u1 = rng.uniform01() + 1e-7f, u2 = rng.uniform01();
      const float r = m.noise_sigma * std::sqrt(-2.0f * std::log(u1));
      l[k] = r * std::cos(6.2831853f * u2);
      if (k + 1 < kNumClasses) l[k + 1] = r * std::sin(6.2831853f * u2);
    }
    const int c = classes ? classes->library_class(labels[i]) : class_from_kitti(labels[i]);
    int predicted = c;
    if (c >= 0) {
      const Confusion conf = confusion_of(c);
      const float u = rng.uniform01();
      if (conf.n > 0 && u < conf.p * m.confusion_scale)
        predicted = conf.partners[rng.uniform(static_cast<uint32_t>(conf.n))];
      l[predicted] += m.margin;
      if (predicted != c) l[c] += 0.5f * m.margin;
    }
    if (relabel) {
      int best = 0;
      for (int k = 1; k < kNumClasses; ++k)
        if (l[k] > l[best]) best = k;
      relabel[i] = c >= 0 && raw_of[best] != UINT32_MAX ? (raw_of[best] | (labels[i] & 0xFFFF0000u)) : labels[i];
    }
  }
}

}  // namespace gsf::port
