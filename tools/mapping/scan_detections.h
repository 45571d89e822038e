// Which map instances a single scan finds: the query's own instance stages run on every mapping scan.
//
// A map accumulates every scan of the drive, so it holds instances no single scan detects (a thin pole
// 40 m off the road, a trunk seen edge-on from each pass): on nuScenes-lidarseg's 32 beams the map of a
// street has several times the instances one of its scans finds there. Triangles over all of them make a
// map apex's K nearest neighbours instances that a query never sees, and the query's triangles then find
// no map twin. Running the localizer's clustering and geometric poles (same code, same settings) on each
// mapping scan tells which map instances a query can be expected to find; the builder forms triangles
// among those (MapBuildConfig::triangle_min_detections). Host side; memory grows with the drive's
// detections (about 40 per scan, 16 bytes each).
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "gsf/config.h"
#include "gsf/detail/instance_clustering.h"
#include "gsf/detail/pole_extraction.h"
#include "gsf/detail/voxel_layer.h"
#include "gsf/status.h"

namespace gsf::mapping {

struct ScanDetection {
  float xyz[3];  // map-local frame
  uint8_t label;
  uint8_t pad[3];
};

class ScanDetector {
 public:
  // `stages`: the localizer's configuration (label set resolved); `max_voxels`: the mapping scans' voxel
  // layer capacity.
  Status init(const LocalizerConfig& stages, uint32_t max_voxels);
  // Appends the instances the query pipeline finds in `voxels` (one scan, lidar frame), in the map frame.
  Status detect(const VoxelLayer& voxels, const Eigen::Isometry3d& map_T_lidar, std::vector<ScanDetection>* out);

 private:
  std::vector<uint64_t> memory_;
  InstanceClustering clusters_;
  PoleExtraction poles_;
  bool poles_on_ = false;
  uint32_t max_instances_ = 0;
  std::vector<uint32_t> pole_order_;
};

// Label of a ScanDetection that stands for a mapping scan's position (count_detections matches any).
constexpr uint8_t kAnyLabel = 0xFF;

// Points in square bird's-eye cells of `cell` m, sorted by cell: a point within `cell` m of (x, y) is in
// the 3 x 3 cells around it. `xy(i)` gives point i's (x, y).
class CellIndex {
 public:
  template <class XY>
  CellIndex(size_t n, float cell, XY xy) : cell_(cell), idx_(n) {
    for (size_t i = 0; i < n; ++i) {
      const std::pair<float, float> p = xy(i);
      idx_[i] = {key(coord(p.first), coord(p.second)), static_cast<uint32_t>(i)};
    }
    std::sort(idx_.begin(), idx_.end());
  }
  // f(i) for every point i in the 3 x 3 cells around (x, y).
  template <class F>
  void for_each_near(float x, float y, F&& f) const {
    const int64_t cx = coord(x), cy = coord(y);
    for (int64_t dx = -1; dx <= 1; ++dx)
      for (int64_t dy = -1; dy <= 1; ++dy) {
        const uint64_t k = key(cx + dx, cy + dy);
        for (auto it = std::lower_bound(idx_.begin(), idx_.end(), std::make_pair(k, uint32_t(0)));
             it != idx_.end() && it->first == k; ++it)
          f(it->second);
      }
  }

 private:
  int64_t coord(float v) const { return static_cast<int64_t>(std::floor(v / cell_)); }
  static uint64_t key(int64_t cx, int64_t cy) {
    return (uint64_t(cx + (int64_t(1) << 31)) << 32) | uint32_t(cy + (1u << 31));
  }
  float cell_;
  std::vector<std::pair<uint64_t, uint32_t>> idx_;
};

// Per map instance (centroids xyz, labels), the number of detections within `radius` m (bird's-eye) of
// its label (or of any label: kAnyLabel detections). Deterministic; O((instances + detections) log)
// through a sorted cell index.
std::vector<uint32_t> count_detections(const float* centroids, const uint8_t* labels, uint32_t n,
                                       const std::vector<ScanDetection>& detections, float radius);

// The triangle vertices of MapBuildConfig::triangle_min_detections: instance i qualifies when its
// detections reach min(min_detections, opportunities[i]), the opportunities being the mapping scans
// within the detection range. An instance no scan came near, or a map of one scan, is no evidence
// against an instance, so a short drive keeps what it has. Returns the qualifying ids in id order.
std::vector<uint32_t> triangle_vertices(const std::vector<uint32_t>& detections,
                                        const std::vector<uint32_t>& opportunities, uint32_t min_detections);

}  // namespace gsf::mapping
