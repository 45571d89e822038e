// The dense semantic class table: SemanticKITTI ids <-> dense indices 0..kNumClasses-1, and the
// per-class stability weight of the paper's Table III.
//
// D (the logit dimension) is kNumClasses = 19, SemanticKITTI's learning classes. Raw ids that map to
// "unlabeled" in SemanticKITTI's learning map (0 unlabeled, 1 outlier, 52 other-structure,
// 99 other-object) give kIgnoredClass: valid input, not used. Ids that SemanticKITTI does not define
// give kUnknownClass, which scan validation reports.
//
// Stability (paper Table III, our mapping):
//   volatile   0.1: bicycle, motorcycle, truck, other-vehicle, person, bicyclist, motorcyclist
//   short-term 0.5: car, vegetation, terrain        (parked cars move; foliage and grass change)
//   long-term  1.0: road, parking, sidewalk, other-ground, building, fence, trunk, pole, traffic-sign
// Trunks are "nature" in the paper's wording but outlive foliage by decades, so we treat them as
// long-term infrastructure; the canopy (vegetation) carries the seasonal change.
#pragma once
#include <cstdint>

namespace gsf {

constexpr int kNumClasses = 19;
constexpr int kIgnoredClass = -1;
constexpr int kUnknownClass = -2;

enum SemanticClass : uint8_t {
  kCar = 0,
  kBicycle,
  kMotorcycle,
  kTruck,
  kOtherVehicle,
  kPerson,
  kBicyclist,
  kMotorcyclist,
  kRoad,
  kParking,
  kSidewalk,
  kOtherGround,
  kBuilding,
  kFence,
  kVegetation,
  kTrunk,
  kTerrain,
  kPole,
  kTrafficSign,
};

// SemanticKITTI semantic id (low 16 bits of a .label word) -> dense class, kIgnoredClass or kUnknownClass.
int class_from_kitti(uint32_t semantic_id);
// Dense class -> canonical SemanticKITTI id (e.g. kCar -> 10). 0 for out-of-range input.
uint16_t kitti_from_class(int dense_class);
// Paper Table III stability weight (0.1 / 0.5 / 1.0); 0 for out-of-range input.
float stability_weight(int dense_class);
const char* class_name(int dense_class);

// Bit mask over dense classes, e.g. which classes form instances.
using ClassMask = uint32_t;
constexpr ClassMask class_bit(int c) { return ClassMask(1u) << c; }
constexpr ClassMask kDefaultInstanceClasses =
    class_bit(kCar) | class_bit(kTrunk) | class_bit(kPole) | class_bit(kTrafficSign);

}  // namespace gsf
