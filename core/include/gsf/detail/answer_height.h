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

}  // namespace gsf
