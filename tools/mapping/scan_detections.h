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
#include <cstdint>
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
