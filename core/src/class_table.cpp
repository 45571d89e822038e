#include "gsf/class_table.h"

#include <cmath>
#include <cstring>

#include "gsf/detail/crc32.h"

namespace gsf {

const char* role_name(ClassRole role) {
  switch (role) {
    case ClassRole::Stuff: return "stuff";
    case ClassRole::Instance: return "instance";
    case ClassRole::PoleHost: return "host:pole";
    case ClassRole::TrunkHost: return "host:trunk";
  }
  return "invalid";
}

const char* to_string(ClassTableError e) {
  switch (e) {
    case ClassTableError::None: return "ok";
    case ClassTableError::TooManyEntries: return "too many entries";
    case ClassTableError::DuplicateId: return "duplicate raw id";
    case ClassTableError::BadClass: return "library class out of range";
    case ClassTableError::BadStability: return "stability not within [0, 1]";
    case ClassTableError::BadRole: return "role invalid (an ignored class can only be stuff)";
    case ClassTableError::ConflictingStability: return "another raw id of this library class has another stability";
    case ClassTableError::ConflictingRole: return "another raw id of this library class has another role";
    case ClassTableError::NameTooLong: return "name too long";
    case ClassTableError::Empty: return "no entries";
  }
  return "unknown error";
}

namespace {
ClassRole default_role(int c) {
  return (kDefaultInstanceClasses & class_bit(c)) ? ClassRole::Instance : ClassRole::Stuff;
}
bool valid_class(int c) { return c >= 0 && c < kNumClasses; }
}  // namespace

void ClassTable::clear() {
  count_ = 0;
  mapped_ = 0;
  for (int c = 0; c < kNumClasses; ++c) {
    stability_[c] = stability_weight(c);
    role_[c] = default_role(c);
  }
}

ClassTableError ClassTable::add(uint16_t raw_id, const char* name, int library_class, float stability, ClassRole role) {
  if (library_class != kIgnoredClass && !valid_class(library_class)) return ClassTableError::BadClass;
  if (!(stability >= 0.0f && stability <= 1.0f)) return ClassTableError::BadStability;  // NaN fails too
  if (static_cast<uint8_t>(role) > static_cast<uint8_t>(ClassRole::TrunkHost)) return ClassTableError::BadRole;
  if (library_class == kIgnoredClass && role != ClassRole::Stuff) return ClassTableError::BadRole;
  const size_t name_len = name ? std::strlen(name) : 0;
  if (name_len >= kClassTableNameBytes) return ClassTableError::NameTooLong;
  // Sorted insert position (binary search).
  uint32_t lo = 0, hi = count_;
  while (lo < hi) {
    const uint32_t mid = (lo + hi) / 2;
    if (entries_[mid].raw_id < raw_id) lo = mid + 1;
    else hi = mid;
  }
  if (lo < count_ && entries_[lo].raw_id == raw_id) return ClassTableError::DuplicateId;
  if (count_ >= kMaxClassTableEntries) return ClassTableError::TooManyEntries;
  if (valid_class(library_class)) {
    const ClassMask bit = class_bit(library_class);
    if (mapped_ & bit) {
      if (stability_[library_class] != stability) return ClassTableError::ConflictingStability;
      if (role_[library_class] != role) return ClassTableError::ConflictingRole;
    }
    mapped_ |= bit;
    stability_[library_class] = stability;
    role_[library_class] = role;
  }
  for (uint32_t i = count_; i > lo; --i) entries_[i] = entries_[i - 1];
  ClassTableEntry& e = entries_[lo];
  e.raw_id = raw_id;
  e.library_class = static_cast<int8_t>(library_class);
  e.role = role;
  std::memset(e.name, 0, sizeof(e.name));
  if (name_len) std::memcpy(e.name, name, name_len);
  ++count_;
  return ClassTableError::None;
}

const ClassTableEntry* ClassTable::find(uint32_t raw_label) const {
  const uint32_t id = raw_label & 0xFFFFu;
  uint32_t lo = 0, hi = count_;
  while (lo < hi) {
    const uint32_t mid = (lo + hi) / 2;
    if (entries_[mid].raw_id < id) lo = mid + 1;
    else hi = mid;
  }
  return lo < count_ && entries_[lo].raw_id == id ? &entries_[lo] : nullptr;
}

int ClassTable::library_class(uint32_t raw_label) const {
  const ClassTableEntry* e = find(raw_label);
  return e ? e->library_class : kUnknownClass;
}

float ClassTable::stability(int c) const { return valid_class(c) ? stability_[c] : 0.0f; }
ClassRole ClassTable::role(int c) const { return valid_class(c) ? role_[c] : ClassRole::Stuff; }

ClassMask ClassTable::mask(ClassRole r) const {
  ClassMask m = 0;
  for (int c = 0; c < kNumClasses; ++c)
    if (role_[c] == r) m |= class_bit(c);
  return m;
}

uint32_t ClassTable::id() const {
  // Canonical bytes, little-endian, independent of struct layout and host byte order.
  static const char kTag[6] = {'G', 'S', 'F', 'C', 'T', '1'};
  uint32_t crc = crc32_update(0, kTag, sizeof(kTag));
  uint8_t b[4];
  auto put32 = [&](uint32_t v) {
    for (int k = 0; k < 4; ++k) b[k] = static_cast<uint8_t>(v >> (8 * k));
    crc = crc32_update(crc, b, 4);
  };
  put32(count_);
  for (uint32_t i = 0; i < count_; ++i) {
    const ClassTableEntry& e = entries_[i];
    const uint8_t rec[4] = {static_cast<uint8_t>(e.raw_id & 0xFF), static_cast<uint8_t>(e.raw_id >> 8),
                            static_cast<uint8_t>(e.library_class), static_cast<uint8_t>(e.role)};
    crc = crc32_update(crc, rec, 4);
  }
  for (int c = 0; c < kNumClasses; ++c) {
    uint32_t bits;
    std::memcpy(&bits, &stability_[c], 4);
    put32(bits);
    const uint8_t r = static_cast<uint8_t>(role_[c]);
    crc = crc32_update(crc, &r, 1);
  }
  return crc;
}

int library_class_from_name(const char* name, uint32_t len) {
  if (name == nullptr) return kUnknownClass;
  if (len == 7 && std::memcmp(name, "ignored", 7) == 0) return kIgnoredClass;
  for (int c = 0; c < kNumClasses; ++c) {
    const char* n = class_name(c);
    if (std::strlen(n) == len && std::memcmp(n, name, len) == 0) return c;
  }
  return kUnknownClass;
}

namespace {

struct BuiltinEntry {
  uint16_t raw;
  const char* name;
  int8_t cls;
};

// SemanticKITTI's raw ids (semantic-kitti.yaml) with class_from_kitti()'s mapping.
constexpr BuiltinEntry kKitti[] = {
    {0, "unlabeled", kIgnoredClass},
    {1, "outlier", kIgnoredClass},
    {10, "car", kCar},
    {11, "bicycle", kBicycle},
    {13, "bus", kOtherVehicle},
    {15, "motorcycle", kMotorcycle},
    {16, "on-rails", kOtherVehicle},
    {18, "truck", kTruck},
    {20, "other-vehicle", kOtherVehicle},
    {30, "person", kPerson},
    {31, "bicyclist", kBicyclist},
    {32, "motorcyclist", kMotorcyclist},
    {40, "road", kRoad},
    {44, "parking", kParking},
    {48, "sidewalk", kSidewalk},
    {49, "other-ground", kOtherGround},
    {50, "building", kBuilding},
    {51, "fence", kFence},
    {52, "other-structure", kIgnoredClass},
    {60, "lane-marking", kRoad},
    {70, "vegetation", kVegetation},
    {71, "trunk", kTrunk},
    {72, "terrain", kTerrain},
    {80, "pole", kPole},
    {81, "traffic-sign", kTrafficSign},
    {99, "other-object", kIgnoredClass},
    {252, "moving-car", kCar},
    {253, "moving-bicyclist", kBicyclist},
    {254, "moving-person", kPerson},
    {255, "moving-motorcyclist", kMotorcyclist},
    {256, "moving-on-rails", kOtherVehicle},
    {257, "moving-bus", kOtherVehicle},
    {258, "moving-truck", kTruck},
    {259, "moving-other-vehicle", kOtherVehicle},
};

// nuScenes-lidarseg's 32 classes with port/nuscenes.cpp's mapping (README of the samples).
constexpr BuiltinEntry kNuScenes[] = {
    {0, "noise", kIgnoredClass},
    {1, "animal", kIgnoredClass},
    {2, "human.pedestrian.adult", kPerson},
    {3, "human.pedestrian.child", kPerson},
    {4, "human.pedestrian.construction_worker", kPerson},
    {5, "human.pedestrian.personal_mobility", kPerson},
    {6, "human.pedestrian.police_officer", kPerson},
    {7, "human.pedestrian.stroller", kPerson},
    {8, "human.pedestrian.wheelchair", kPerson},
    {9, "movable_object.barrier", kFence},
    {10, "movable_object.debris", kIgnoredClass},
    {11, "movable_object.pushable_pullable", kIgnoredClass},
    {12, "movable_object.trafficcone", kIgnoredClass},
    {13, "static_object.bicycle_rack", kIgnoredClass},
    {14, "vehicle.bicycle", kBicycle},
    {15, "vehicle.bus.bendy", kOtherVehicle},
    {16, "vehicle.bus.rigid", kOtherVehicle},
    {17, "vehicle.car", kCar},
    {18, "vehicle.construction", kOtherVehicle},
    {19, "vehicle.emergency.ambulance", kOtherVehicle},
    {20, "vehicle.emergency.police", kOtherVehicle},
    {21, "vehicle.motorcycle", kMotorcycle},
    {22, "vehicle.trailer", kOtherVehicle},
    {23, "vehicle.truck", kTruck},
    {24, "flat.driveable_surface", kRoad},
    {25, "flat.other", kOtherGround},
    {26, "flat.sidewalk", kSidewalk},
    {27, "flat.terrain", kTerrain},
    {28, "static.manmade", kBuilding},
    {29, "static.other", kIgnoredClass},
    {30, "static.vegetation", kVegetation},
    {31, "vehicle.ego", kIgnoredClass},
};

template <size_t N>
void fill(const BuiltinEntry (&src)[N], ClassTable* out, ClassRole (*role_of)(int)) {
  out->clear();
  for (const BuiltinEntry& e : src) {
    const ClassRole r = e.cls == kIgnoredClass ? ClassRole::Stuff : role_of(e.cls);
    // Built-ins are checked by the tests; add() cannot fail on them.
    (void)out->add(e.raw, e.name, e.cls, e.cls == kIgnoredClass ? 0.0f : stability_weight(e.cls), r);
  }
}

ClassRole kitti_role(int c) { return default_role(c); }
ClassRole nuscenes_role(int c) {
  if (c == kBuilding) return ClassRole::PoleHost;
  if (c == kVegetation) return ClassRole::TrunkHost;
  return default_role(c);
}

}  // namespace

void semantic_kitti_class_table(ClassTable* out) { fill(kKitti, out, kitti_role); }
void nuscenes_lidarseg_class_table(ClassTable* out) { fill(kNuScenes, out, nuscenes_role); }

}  // namespace gsf
