// A label set described as plain data: which raw label id (what a dataset or a segmentation network
// writes per point) is which library class (the dense classes of semantic_classes.h, or ignored), the
// role of each library class (instance, stuff, or a "geometric instance host" whose thin vertical
// structures pole_extraction.h turns into pole / trunk instances), and the stability weight of each
// library class (paper Table III: volatile 0.1, short-term 0.5, long-term 1.0).
//
// No heap, no I/O: a ClassTable is a fixed-size struct the caller owns (about 12 KB). It is filled
// either by a built-in (semantic_kitti_class_table, nuscenes_lidarseg_class_table) or entry by entry
// through add() (what the port layer's text parser, port/class_table_file.h, does), which validates
// every entry. Raw ids are 16-bit: lookups use the low 16 bits of a label word, as SemanticKITTI's
// .label words carry the instance id in the high 16 bits.
//
// Rules add() enforces (each failure returns a ClassTableError naming the problem):
//   - raw ids are unique; at most kMaxClassTableEntries entries;
//   - library_class is 0..kNumClasses-1 or kIgnoredClass;
//   - stability is finite and within [0, 1];
//   - an ignored entry has role Stuff (it never reaches a voxel, so it cannot be an instance or host);
//   - all raw ids that map to the same library class agree on its stability and role, because after
//     voxelisation only the library class survives (a per-raw-id difference could not be honoured).
// Library classes that no entry maps to keep the library defaults: stability_weight(c), and role
// Instance for kDefaultInstanceClasses, Stuff otherwise. Roles then give the masks the stages take:
// instance_classes() (InstanceClustering), pole_host_classes() / trunk_host_classes() (PoleExtraction).
//
// id(): CRC-32 of the table's canonical bytes (see docs/data-formats.md): "GSFCT1", the entry count,
// each entry in raw-id order (raw id, library class, role) and the 19 class stabilities and roles.
// Names are not part of it, so renaming a raw class keeps the id; any change of mapping, role or
// weight changes it. A map can record the id it was built with and refuse a query with another table.
#pragma once
#include <cstdint>

#include "gsf/semantic_classes.h"
#include "gsf/status.h"

namespace gsf {

constexpr uint32_t kMaxClassTableEntries = 256;
constexpr uint32_t kClassTableNameBytes = 40;  // raw class names: at most 39 characters

enum class ClassRole : uint8_t {
  Stuff = 0,      // contributes voxels (fields, refinement) but never an instance
  Instance = 1,   // clustered into instances (instance_clustering.h)
  PoleHost = 2,   // stuff whose thin vertical structures become kPole instances (pole_extraction.h)
  TrunkHost = 3,  // stuff whose thin vertical structures become kTrunk instances
};
const char* role_name(ClassRole role);

struct ClassTableEntry {
  uint16_t raw_id;
  int8_t library_class;  // 0..kNumClasses-1, or kIgnoredClass
  ClassRole role;
  char name[kClassTableNameBytes];  // NUL-terminated; informational only
};

enum class ClassTableError : uint8_t {
  None = 0,
  TooManyEntries,        // more than kMaxClassTableEntries
  DuplicateId,           // raw id already in the table
  BadClass,              // library class neither 0..kNumClasses-1 nor kIgnoredClass
  BadStability,          // not finite or outside [0, 1]
  BadRole,               // role value out of range, or a role other than Stuff on an ignored entry
  ConflictingStability,  // another raw id of the same library class has another stability
  ConflictingRole,       // another raw id of the same library class has another role
  NameTooLong,           // name of kClassTableNameBytes characters or more
  Empty,                 // finish() on a table without entries
};
const char* to_string(ClassTableError e);

class ClassTable {
 public:
  // An empty table (library defaults for every class, no raw ids): everything looks up as unknown.
  ClassTable() { clear(); }
  void clear();

  // Adds one raw id. On failure the table is unchanged and the returned error says why.
  ClassTableError add(uint16_t raw_id, const char* name, int library_class, float stability, ClassRole role);

  // Raw label word (low 16 bits used) -> library class, kIgnoredClass, or kUnknownClass (not listed).
  int library_class(uint32_t raw_label) const;
  // The entry of a raw id, or nullptr.
  const ClassTableEntry* find(uint32_t raw_label) const;

  uint32_t size() const { return count_; }
  const ClassTableEntry& entry(uint32_t i) const { return entries_[i]; }  // raw-id order

  float stability(int library_class) const;  // 0 for out-of-range input, like stability_weight()
  ClassRole role(int library_class) const;   // Stuff for out-of-range input
  ClassMask instance_classes() const { return mask(ClassRole::Instance); }
  ClassMask pole_host_classes() const { return mask(ClassRole::PoleHost); }
  ClassMask trunk_host_classes() const { return mask(ClassRole::TrunkHost); }
  ClassMask stuff_classes() const { return mask(ClassRole::Stuff) | pole_host_classes() | trunk_host_classes(); }
  // Library classes that at least one raw id maps to.
  ClassMask mapped_classes() const { return mapped_; }

  uint32_t id() const;

 private:
  ClassMask mask(ClassRole r) const;

  ClassTableEntry entries_[kMaxClassTableEntries];
  uint32_t count_ = 0;
  float stability_[kNumClasses];
  ClassRole role_[kNumClasses];
  ClassMask mapped_ = 0;
};

// SemanticKITTI (the label set the library was written for): reproduces class_from_kitti() and
// stability_weight() for every id 0..65535, instance classes kDefaultInstanceClasses, no hosts.
void semantic_kitti_class_table(ClassTable* out);

// nuScenes-lidarseg's 32 classes (uint8 0..31 in the lidarseg files): the library classes of
// port/nuscenes.cpp's mapping (nuscenes_to_kitti, then class_from_kitti); 31 vehicle.ego is ignored
// (the reader drops it); 28 static.manmade -> building as pole host, 30 static.vegetation ->
// vegetation as trunk host; instance class car (17). nuScenes has no pole, trunk or sign class.
void nuscenes_lidarseg_class_table(ClassTable* out);

// Library class from its name as class_name() spells it ("car", "traffic-sign", ...), or "ignored"
// -> kIgnoredClass. `len` bytes of `name` (no NUL needed). kUnknownClass when it names no class.
int library_class_from_name(const char* name, uint32_t len);

}  // namespace gsf
