// Internal (gsf/detail): a pipeline stage or building block, not part of the stable interface; it may
// change between versions. The stable interface is localizer.h, config.h, map_format.h, scan.h, status.h,
// platform.h, class_table.h, georeference.h, stage_configs.h, stage_results.h and the C API gsf.h.
// Pose refinement against the map's point layer (paper Table IV "w/ rf"): point-to-plane ICP from the
// global pose, on long-term structure only (stability weight 1: buildings, poles, fences, ground...).
//
// The map's refinement layer (refine_layer.h) already holds the points sorted into the grid with their
// normals (the builder computed them), so the refiner reads it in place; its workspace is the query
// buffers only. Per scan: up to max_points query voxel centroids
// of long-term classes, a bounded number of Gauss-Newton iterations with a shrinking correspondence
// radius, nearest neighbours from the 27 surrounding cells (visited nearest first, cells farther than
// the best so far skipped, each cell's point range looked up once while the query point stays in its
// cell), a 6x6 solve per iteration. A pole or trunk voxel whose nearest map point has no normal (a
// column) adds its horizontal offset from it instead: in a car park of columns on flat ground that is
// all that holds x, y and heading. An update under 1 cm and 0.05 deg ends the middle radii: the last
// (tightest) radius runs next, so a start already on the map (tracking) costs two iterations, not all.
// The refined pose is accepted only if it keeps enough inliers and stays within max_correction of the
// global pose; otherwise the global pose is returned unchanged (refinement never makes it worse by
// jumping to a different place).
#pragma once
#include <cstdint>

#include <Eigen/Geometry>

#include "gsf/class_table.h"
#include "gsf/detail/arena.h"
#include "gsf/detail/refine_layer.h"
#include "gsf/detail/voxel_layer.h"
#include "gsf/stage_configs.h"
#include "gsf/status.h"

namespace gsf {

struct RefineStats {
  uint32_t query_points = 0, inliers = 0, iterations = 0;
  double rmse = 0;
  bool accepted = false;
};

class Refiner {
 public:
  static size_t required_bytes(const RefineConfig& config);
  Status bind(Arena& arena, const RefineConfig& config);
  // The map's layer (read in place; must outlive the refiner's use). ConfigMismatch when its cell is not
  // config.cell.
  Status set_map(const RefineLayerView& layer);
  Status refine(const VoxelLayer& query, const Eigen::Isometry3d& initial, Eigen::Isometry3d* refined,
                RefineStats* stats);
  // The same on a smaller budget (tracking, whose start is already close): at most `points` query points
  // and `iterations` iterations (each capped by the config's; 0 keeps the config's).
  Status refine(const VoxelLayer& query, const Eigen::Isometry3d& initial, Eigen::Isometry3d* refined,
                RefineStats* stats, uint32_t points, uint32_t iterations);
  // Which classes are long-term (stability 1) from this label set (not copied); nullptr (the default):
  // stability_weight().
  void set_classes(const ClassTable* table) { classes_ = table; }

 private:
  struct NearestSearch;  // one query point's search of the 27 cells around it (refine.cpp)
  // The steps of refine(): the query points, then per iteration the normal equations and the update.
  uint32_t pick_query_points(const VoxelLayer& layer);
  uint32_t add_correspondence_rows(const Eigen::Isometry3d& t, uint32_t q, float r2, uint32_t* tile_hint,
                                   Eigen::Matrix<double, 6, 6>* H, Eigen::Matrix<double, 6, 1>* g, double* err);
  const MapRefinePoint* find_nearest(uint32_t i, const float pf[3], float r2, uint32_t* tile_hint, float nearest[3]);
  static bool apply_update(const Eigen::Matrix<double, 6, 6>& H, const Eigen::Matrix<double, 6, 1>& g,
                           Eigen::Isometry3d* t, bool* settled);
  bool long_term(int label) const { return (classes_ ? classes_->stability(label) : stability_weight(label)) >= 1.0f; }
  RefineConfig config_{};
  const ClassTable* classes_ = nullptr;
  RefineLayerView map_{};
  float* query_ = nullptr;  // max_points x 3
  // Per query point, the grid cell it fell in at the last iteration and the point ranges of the cells
  // around it (27 per point; begin kNotLooked until looked up): the pose moves little between
  // iterations, so the same cells are found again without searching the layer.
  uint64_t* query_cell_ = nullptr;   // max_points
  uint32_t* query_begin_ = nullptr;  // max_points x 27
  uint32_t* query_end_ = nullptr;    // max_points x 27
  uint8_t* query_pole_ = nullptr;    // max_points: 1 for a pole or trunk voxel (point-to-point rows)
  bool bound_ = false;
};

}  // namespace gsf
