// Internal (gsf/detail): a pipeline stage or building block, not part of the stable interface; it may
// change between versions. The stable interface is localizer.h, config.h, map_format.h, scan.h, status.h,
// platform.h, class_table.h, georeference.h, stage_configs.h, stage_results.h and the C API gsf.h.
// The object layer (top of the scene graph): instances clustered inside instantiable classes.
//
// Connected components over the voxel layer: two voxels of the same instantiable class are connected
// when their centroids are within the class tolerance (searched through neighbouring voxel cells, BFS
// with an explicit queue - no recursion). Thin vertical classes (poles, trunks, signs) connect across a
// vertical gap up to vertical_tolerance within the horizontal tolerance: a spinning LiDAR's beams
// are degrees apart, so a pole 30 m away is hit every ~0.6 m of its height (32 beams over 35 deg) and
// 60 m away every ~1.2 m; with one spherical tolerance it fell apart into single-voxel pieces that
// min_voxels rejects, and a query saw no pole the map had (suite approach roads). A component becomes an instance if it
// has at least min_voxels and its horizontal extent is at most max_extent for its class (rejects walls of "poles").
// Capacity: at most max_instances are kept - the largest by point count (ties: earlier discovery) -
// and build() returns Status::CapacityExceeded as a warning; the kept instances are valid.
// Instances are ordered by discovery (voxel order), so the result is deterministic.
// Cost: per voxel of an instantiable class (2 ceil(tolerance / voxel_size) + 1)^3 hash lookups (343 for
// the car default at 0.4 m voxels; with a vertical tolerance (2r + 1)^2 (2 ceil(vertical_tolerance /
// voxel_size) + 1): 275 for a pole at 0.6 / 2.0 m); bind() caps both tolerances below 10 m. Memory: bind() sizes
// everything from max_voxels and max_instances, so the map builder can cluster a whole accumulated map with a large
// arena. build() returns InvalidArgument if the layer holds more than max_voxels voxels and NotInitialized before a
// successful bind().
#pragma once
#include <cstdint>

#include "gsf/class_table.h"
#include "gsf/detail/arena.h"
#include "gsf/detail/voxel_layer.h"
#include "gsf/semantic_classes.h"
#include "gsf/stage_configs.h"
#include "gsf/status.h"

namespace gsf {

struct Instance {
  float centroid[3];
  float extent[3];  // axis-aligned bbox size
  float stability;  // stability_weight(label)
  uint32_t voxel_count;
  uint32_t point_count;
  uint32_t first_voxel;  // discovery order key
  uint8_t label;         // dense class
  uint8_t pad[3];
};

struct ClusterStats {
  uint32_t components = 0, rejected_small = 0, rejected_extent = 0, dropped_capacity = 0, instances = 0;
};

class InstanceClustering {
 public:
  static size_t required_bytes(const ClusterConfig& config, uint32_t max_voxels);
  Status bind(Arena& arena, const ClusterConfig& config, uint32_t max_voxels);
  Status build(const VoxelLayer& voxels, ClusterStats* stats);
  // Stability of each instance's class from this label set (not copied); nullptr (the default):
  // stability_weight(), the library's Table III.
  void set_classes(const ClassTable* table) { classes_ = table; }

  uint32_t size() const { return count_; }
  const Instance& instance(uint32_t i) const { return instances_[i]; }
  const Instance* instances() const { return instances_; }
  // Instance id of each voxel after build (UINT32_MAX for voxels in no kept instance).
  const uint32_t* voxel_instance() const { return voxel_instance_; }

 private:
  struct Reach;  // how far one label's voxels connect (instance_clustering.cpp)
  // The steps of build(): per seed a component, described, judged and kept; then discovery order.
  uint32_t grow_component(const VoxelLayer& layer, uint32_t seed, uint32_t comp);
  void add_neighbours(const VoxelLayer& layer, uint32_t v, uint32_t comp, const Reach& r, uint32_t* tail);
  Instance describe_component(const VoxelLayer& layer, uint32_t seed, uint32_t size) const;
  void keep_largest(const Instance& in, uint32_t comp, ClusterStats* stats);
  void order_by_discovery(uint32_t n);
  ClusterConfig config_{};
  const ClassTable* classes_ = nullptr;
  Instance* instances_ = nullptr;
  uint32_t* queue_ = nullptr;
  uint32_t* voxel_instance_ = nullptr;  // during build: component id; after: kept instance id
  uint32_t* component_to_instance_ = nullptr;
  uint32_t max_voxels_ = 0;
  uint32_t max_components_ = 0;
  uint32_t count_ = 0;
  bool bound_ = false;
};

}  // namespace gsf
