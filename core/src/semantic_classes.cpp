#include "gsf/semantic_classes.h"

namespace gsf {

int class_from_kitti(uint32_t id) {
  switch (id & 0xFFFFu) {
    case 0:
    case 1:
    case 52:
    case 99: return kIgnoredClass;
    case 10:
    case 252: return kCar;
    case 11: return kBicycle;
    case 15: return kMotorcycle;
    case 18:
    case 258: return kTruck;
    case 13:
    case 16:
    case 20:
    case 256:
    case 257:
    case 259: return kOtherVehicle;
    case 30:
    case 254: return kPerson;
    case 31:
    case 253: return kBicyclist;
    case 32:
    case 255: return kMotorcyclist;
    case 40:
    case 60: return kRoad;  // lane-marking is road in SemanticKITTI's learning map
    case 44: return kParking;
    case 48: return kSidewalk;
    case 49: return kOtherGround;
    case 50: return kBuilding;
    case 51: return kFence;
    case 70: return kVegetation;
    case 71: return kTrunk;
    case 72: return kTerrain;
    case 80: return kPole;
    case 81: return kTrafficSign;
    default: return kUnknownClass;
  }
}

namespace {
struct ClassInfo {
  uint16_t kitti;
  float stability;
  const char* name;
};
constexpr ClassInfo kTable[kNumClasses] = {
    {10, 0.5f, "car"},           {11, 0.1f, "bicycle"}, {15, 0.1f, "motorcycle"},   {18, 0.1f, "truck"},
    {20, 0.1f, "other-vehicle"}, {30, 0.1f, "person"},  {31, 0.1f, "bicyclist"},    {32, 0.1f, "motorcyclist"},
    {40, 1.0f, "road"},          {44, 1.0f, "parking"}, {48, 1.0f, "sidewalk"},     {49, 1.0f, "other-ground"},
    {50, 1.0f, "building"},      {51, 1.0f, "fence"},   {70, 0.5f, "vegetation"},   {71, 1.0f, "trunk"},
    {72, 0.5f, "terrain"},       {80, 1.0f, "pole"},    {81, 1.0f, "traffic-sign"},
};
bool valid(int c) { return c >= 0 && c < kNumClasses; }
}  // namespace

uint16_t kitti_from_class(int c) { return valid(c) ? kTable[c].kitti : 0; }
float stability_weight(int c) { return valid(c) ? kTable[c].stability : 0.0f; }
const char* class_name(int c) { return valid(c) ? kTable[c].name : "invalid"; }

}  // namespace gsf
