// Internal (gsf/detail): a pipeline stage or building block, not part of the stable interface; it may
// change between versions. The stable interface is localizer.h, config.h, map_format.h, scan.h, status.h,
// platform.h, class_table.h, georeference.h, stage_configs.h, stage_results.h and the C API gsf.h.
//
// The answer's height from every correspondence that agrees with it. Verification chooses x, y and yaw
// in the bird's-eye view and cannot see height, so the answer's z is whatever its hypothesis had: for a
// shift vote, the mean vertical offset of its few supporting votes. An instance centroid's height depends
// on how much of the trunk or pole the scan saw (a tree beside the sensor loses its crown to the vertical
// field of view; the map saw it whole), and three such votes put answers at the right place 5-6 m too
// high or low (held-out avenue zones, docs/results.md). Every selected correspondence that the answer
// places within `radius` in the bird's-eye view testifies to the height; their weighted median vertical
// offset, robust to the few cut-off trunks, becomes the answer's z when at least min_count agree.
#pragma once
#include <cstdint>

#include <Eigen/Geometry>

namespace gsf {

class VoxelLayer;

struct HeightSample {
  float offset;  // map z - (R a)_z of one correspondence
  float weight;
  uint32_t index;  // its position among the correspondences (the order of equal offsets)
};

// a, b: n x 3 query / map positions, w: n weights (> 0); scratch: n samples. Sets T's z to the weighted
// median offset of the correspondences within `radius` of T in x and y if there are at least min_count
// of them, and returns how many there were; 0: T unchanged (fewer than min_count).
uint32_t consensus_height(const float* a, const float* b, const float* w, uint32_t n, float radius, uint32_t min_count,
                          HeightSample* scratch, Eigen::Isometry3d* T);

// The answer's roll and pitch, before its height. A hypothesis' TLS pose has whatever roll and pitch fit
// its few mid-height centroids best; their heights are good to a metre and biased by what the scan cut
// off (far trunks lose their crowns to the vertical field of view, near ones their bases), so the fit
// leans answers at the right place by several degrees (ARE p99 5.7 deg on level simulated worlds) and through
// the height lifts a few of them 6-8 m (docs/results.md). Verification chose x, y and yaw and sees
// neither. The scan's own ground shows the sensor's lean against the ground it stands on, and the map's
// refinement layer the ground's lean at the answer (a grade, a map frame not quite level): the answer
// takes the roll and pitch that lay the one on the other.
//
// The scan's ground: the normal (sensor frame, pointing up) of a plane fitted to the ground-class
// voxels (kGroundClasses) within kGroundRadiusM of the sensor in the bird's-eye view, fitted again
// without those more than kGroundBandM off the first plane (kerbs, verges, a parked car's floor). False,
// up unchanged, with fewer than kGroundMinVoxels.
constexpr float kGroundRadiusM = 20.0f;
constexpr float kGroundBandM = 0.25f;
constexpr uint32_t kGroundMinVoxels = 50;
constexpr uint32_t kGroundMinMapPoints = 50;  // level map points RefineLayerView::ground_near must keep
bool scan_ground_up(const VoxelLayer& voxels, Eigen::Vector3d* up);

// T with the roll and pitch that map `scan_up` (sensor frame) to `map_up` (the map's ground normal under
// the answer, RefineLayerView::ground_near, or its vertical); its yaw as verification reads it (atan2 of
// the rotation's first column in x, y) and its translation kept.
void level_answer(const Eigen::Vector3d& scan_up, const Eigen::Vector3d& map_up, Eigen::Isometry3d* T);

}  // namespace gsf
