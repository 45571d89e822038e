// Pose refinement against the map's point layer (paper Table IV "w/ rf"): point-to-plane ICP from the
// global pose, on long-term structure only (stability weight 1: buildings, poles, fences, ground...).
//
// At init the map's refinement points are put in a uniform-grid hash (CSR) and each gets a normal from
// the PCA of its grid neighbourhood - all in the arena. Per scan: up to max_points query voxel centroids
// of long-term classes, a bounded number of Gauss-Newton iterations with a shrinking correspondence
// radius, nearest neighbours from the 27 surrounding cells, a 6x6 solve per iteration.
// The refined pose is accepted only if it keeps enough inliers and stays within max_correction of the
// global pose; otherwise the global pose is returned unchanged (refinement never makes it worse by
// jumping to a different place).
#pragma once
#include <cstdint>

#include <Eigen/Geometry>

#include "gsf/arena.h"
#include "gsf/bounded_hash_map.h"
#include "gsf/class_table.h"
#include "gsf/status.h"
#include "gsf/voxel_layer.h"

namespace gsf {

struct RefineConfig {
  bool enabled = false;
  uint32_t max_points = 2000;      // query points used (deterministic stride subsample)
  uint32_t max_map_points = 1u << 18;  // capacity for the map's refinement layer
  uint32_t iterations = 10;
  float radius_start = 1.5f;       // m, correspondence radius of the first iteration (<= 1.5 cell)
  float radius_end = 0.5f;         // m, of the last
  float cell = 1.0f;               // m, grid cell (>= the map's refine voxel)
  float max_correction = 3.0f;     // m, larger moves are rejected
  uint32_t min_inliers = 100;
};

struct RefineStats {
  uint32_t query_points = 0, inliers = 0, iterations = 0;
  double rmse = 0;
  bool accepted = false;
};

class Refiner {
 public:
  static size_t required_bytes(const RefineConfig& config);
  Status bind(Arena& arena, const RefineConfig& config);
  // Indexes the map points (x, y, z, label) x n and estimates normals. InvalidArgument if n exceeds capacity.
  Status set_map(const float* points, uint32_t n);
  Status refine(const VoxelLayer& query, const Eigen::Isometry3d& initial, Eigen::Isometry3d* refined, RefineStats* stats);
  // Which classes are long-term (stability 1) from this label set (not copied); nullptr (the default):
  // stability_weight().
  void set_classes(const ClassTable* table) { classes_ = table; }

 private:
  bool long_term(int label) const { return (classes_ ? classes_->stability(label) : stability_weight(label)) >= 1.0f; }
  struct Cell { uint32_t begin, count; };
  uint64_t cell_key(float x, float y, float z) const;
  RefineConfig config_{};
  const ClassTable* classes_ = nullptr;
  BoundedHashMap<Cell> cells_;
  uint32_t* order_ = nullptr;   // map point ids grouped by cell
  float* points_ = nullptr;     // n x 3 (copied for locality)
  float* normals_ = nullptr;    // n x 3 (0 vector: no reliable normal)
  float* query_ = nullptr;      // max_points x 3
  uint32_t n_ = 0;
  bool bound_ = false;
};

}  // namespace gsf
