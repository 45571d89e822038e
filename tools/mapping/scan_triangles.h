// The triangles a query would form at each mapping scan's pose.
//
// A map triangle joins an apex to two of its K nearest *map* instances, and the map holds every instance
// the whole drive saw: on an open road an apex's nearest map instances include some on the far side of a
// building or 40 m along the road that no single scan sees together with it. A query builds its
// triangles among the instances it sees, so most of them had no twin in the map (held-out suite: open-road
// failures with 7-16 instances, 5-13 of them in the map, found 1-44 map triangle candidates for 35-357
// query triangles). Each mapping scan's detections (scan_detections.h: the query's own instance stages)
// say which map instances a query there sees; the map adds the triangles the query's TriangleBuilder
// (its K, its side limits) forms among those instances, at their map centroids. Host side.
#pragma once
#include <cstdint>
#include <vector>

#include "gsf/detail/triangle.h"
#include "gsf/status.h"
#include "mapping/scan_detections.h"

namespace gsf::mapping {

// For each detection, the nearest of the n instances (centroids n x 3, labels) with the detection's label
// within `radius` m in the bird's-eye view, ties to the lower id; UINT32_MAX when there is none.
std::vector<uint32_t> nearest_instances(const float* centroids, const uint8_t* labels, uint32_t n,
                                        const std::vector<ScanDetection>& detections, float radius);

struct ScanTriangleStats {
  uint32_t scans = 0;         // scans with at least three associated instances
  uint64_t formed = 0;        // triangles formed over all scans (before removing repeats)
  uint32_t added = 0;         // distinct triangles not already in `existing`
  uint32_t largest_scan = 0;  // most instances one scan saw
  uint32_t crowded = 0;       // not added: max_key_share map triangles already had their key
};

// Per scan s (its detections are [scan_begin[s], scan_begin[s + 1]) of `instance_of_detection`, which
// gives each detection's instance id in [0, n) or UINT32_MAX), the triangles `query` (the query's
// TriangleConfig: neighbours, side limits) forms among the distinct instances the scan saw, at their
// centroids. Appends to `triangles` those whose vertex set is not already there (ids are instance ids);
// deterministic (scans in order, each scan's instances in id order). With max_key_share > 0 a triangle
// whose index key (labels, quantised sides) max_key_share map triangles already have is not added: in a
// repetitive layout such a triangle is one more twin of many, which only crowds the true match out of
// the query's per-triangle cap.
Status add_scan_triangles(const float* centroids, const uint8_t* labels, uint32_t n,
                          const std::vector<uint32_t>& instance_of_detection, const std::vector<uint32_t>& scan_begin,
                          const TriangleConfig& query, uint32_t max_key_share, std::vector<Triangle>* triangles,
                          ScanTriangleStats* stats);

}  // namespace gsf::mapping
