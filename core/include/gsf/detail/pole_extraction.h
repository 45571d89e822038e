// Internal (gsf/detail): a pipeline stage or building block, not part of the stable interface; it may
// change between versions. The stable interface is localizer.h, config.h, map_format.h, scan.h, status.h,
// platform.h, class_table.h, georeference.h, stage_configs.h, stage_results.h and the C API gsf.h.
// Geometric pole / trunk instances from host classes: for label sets that have no pole or trunk class
// (nuScenes-lidarseg keeps them inside static.manmade and static.vegetation), find thin, tall,
// vertical and isolated structures among the voxels of the "host" classes and return them as Instance
// records (instance_clustering.h) labelled kPole or kTrunk.
//
// Works on a VoxelLayer, so the same code serves a query (one scan in the sensor frame) and a map (the
// map builder's world-frame layer of many accumulated scans). Steps, in voxel cells of the layer:
//  1. Slices: per voxel level (z cell), 8-connected components of host voxels of one kind (pole hosts
//     or trunk hosts). A slice segment is *thin* when the bounding box of its voxel centroids has a
//     horizontal diagonal <= max_diameter[kind], and *isolated* when no host voxel (either kind) of the
//     same level lies outside it within ring_width of that box. A wall, a hedge or a canopy gives wide
//     segments; a wall fragment or a pole beside a wall is not isolated.
//  2. Chains: thin isolated segments of the same kind are linked upward when a voxel of one has a voxel
//     of the other up to max_gap higher (empty levels in between, as a sparse beam pattern leaves) and
//     within link_radius horizontally. Linked segments form a chain (union-find).
//  3. Acceptance per chain: >= min_levels distinct levels and a vertical extent (centroid span + one
//     voxel) >= min_height[kind]; an axis fitted by least squares of horizontal position on height
//     (x = a + b z, y = c + d z, every voxel weight 1) tilted <= max_tilt_deg from vertical; and the
//     residuals about that axis within a box of diagonal <= max_diameter[kind] (thickness, so a slightly
//     tilted tall pole is judged by its thickness, not by its drift).
//  4. Instances: centroid = point-weighted mean of the chain's voxel centroids, extent = axis-aligned
//     centroid box + one voxel, stability = config.stability[kind], as InstanceClustering does.
//     Quality score = vertical extent * cos(tilt) / (1 + mean ring voxels per segment): taller, more
//     vertical, more isolated first. At most max_instances are kept: on overflow the lowest score is
//     evicted (ties: fewer points, then later discovery), so the kept ones are the best max_instances
//     whatever the storage order, and build() returns Status::CapacityExceeded with
//     stats.dropped_capacity = the number of accepted chains not kept. The result is in discovery order
//     (first voxel index), deterministic for a given layer.
//  5. Beam-column rows (a layer in the sensor frame only, LayerFrame::Sensor): a flat surface seen at a
//     grazing angle (a facade or a fence far along the street) is hit by the sensor's azimuth columns one
//     by one, metres apart along the surface (range x azimuth step / sin(grazing angle)), so each column
//     is a thin, tall, isolated vertical line that passes 1-4. Such columns lie next to each other in
//     azimuth (one azimuth step, 0.1-0.4 deg, apart) at nearly the same range, where real poles of a
//     row are degrees apart. Accepted chains of one kind at most kColumnRowDeg apart in azimuth and at
//     most kColumnRowGap x range apart link into rows; every chain of a row of >= 3 is rejected
//     (stats.rejected_row). Up to 2 x max_instances chains are collected before this step, so
//     columns do not evict real poles first. Another drive sees the same surface from elsewhere, so
//     these lines never repeat: on the real nuScenes scans and the simulated nuScenes-labelled worlds
//     they were a large share of the scan's instances (docs/pole-extraction.md). The map builder's
//     accumulated world-frame layer (many viewpoints, LayerFrame::World) fills such surfaces in and
//     has no single sensor: there the step is off.
//
// Memory: bind() takes everything from the arena: 24 bytes per max_voxels plus two records per
// max_instances (2 x max_instances candidate records, 8 bytes per candidate for the row step); build()
// does not allocate. Cost: per host voxel 8 lookups (slices), per thin voxel
// (2 ceil(ring_width / voxel) + 3)^2 for the ring test and (2 ceil(link_radius / voxel) + 1)^2 *
// (1 + floor(max_gap / voxel)) for linking, plus a sort of each chain's voxels by level.
// Statuses: NotInitialized before a successful bind(); InvalidArgument from bind() for a bad config
// (non-positive capacities or sizes, overlapping host masks, tilt outside (0, 90) degrees) and from
// build() when the layer holds more than max_voxels voxels or when ring_width, link_radius or max_gap
// span more than 16 voxel cells of this layer. Ok with zero instances when nothing qualifies.
#pragma once
#include <cstdint>

#include "gsf/class_table.h"
#include "gsf/detail/arena.h"
#include "gsf/detail/instance_clustering.h"
#include "gsf/detail/voxel_layer.h"
#include "gsf/semantic_classes.h"
#include "gsf/stage_configs.h"
#include "gsf/status.h"

namespace gsf {

// Per kept instance: how it was judged.
struct PoleInfo {
  float score;
  float height;          // m, vertical extent
  float tilt_deg;        // axis from vertical
  float thickness;       // m, residual box diagonal about the axis
  float ring;            // mean ring voxels per segment
  uint32_t levels;       // distinct voxel levels
  uint32_t first_voxel;  // = instance(i).first_voxel
  uint8_t kind;          // PoleKind
  uint8_t pad[3];
};

struct PoleStats {
  uint32_t host_voxels = 0;
  uint32_t segments = 0;          // slice components of host voxels
  uint32_t segments_wide = 0;     // not thin
  uint32_t segments_crowded = 0;  // thin but not isolated
  uint32_t chains = 0;            // linked thin isolated segments
  uint32_t rejected_short = 0;    // too few levels, or too low
  uint32_t rejected_tilt = 0;
  uint32_t rejected_thick = 0;
  uint32_t rejected_row = 0;      // beam-column rows (step 5)
  uint32_t dropped_capacity = 0;  // accepted but not among the best max_instances
  uint32_t instances = 0;
};

// Where the layer's origin is: a single scan in its sensor frame (the sensor at the origin: step 5 runs),
// or a world-frame layer of many scans (step 5 is off).
enum class LayerFrame : uint8_t { World, Sensor };

class PoleExtraction {
 public:
  static size_t required_bytes(const PoleConfig& config, uint32_t max_voxels);
  Status bind(Arena& arena, const PoleConfig& config, uint32_t max_voxels);
  Status build(const VoxelLayer& voxels, PoleStats* stats, LayerFrame frame = LayerFrame::World);

  uint32_t size() const { return count_; }
  const Instance& instance(uint32_t i) const { return instances_[i]; }
  const Instance* instances() const { return instances_; }
  const PoleInfo& info(uint32_t i) const { return info_[i]; }
  // The kept poles' indices best score first (ties in index order) into order[0 .. size()): the rank by
  // which the localizer, and the map builder's per-scan detections, fill the instance slots left free.
  void order_by_score(uint32_t* order) const;
  // Instance id of each voxel after build (UINT32_MAX for voxels in no kept instance).
  const uint32_t* voxel_instance() const { return voxel_seg_; }
  const PoleConfig& config() const { return config_; }

 private:
  struct Segment {
    uint32_t parent;  // union-find
    int32_t level;    // z cell
    uint16_t ring;    // host voxels in its isolation ring (saturating)
    uint8_t kind;
    uint8_t pad;
  };
  uint32_t find_root(uint32_t s);
  struct Hosts;       // the layer's host voxels as the steps read them (pole_extraction.cpp)
  struct SliceBox;    // a slice segment's centroid box and cell box
  struct ChainShape;  // what a chain's voxels add up to
  // The steps of build(), in order.
  uint32_t find_slice_segments(const Hosts& h, int32_t ring_cells, PoleStats* stats);
  void link_segments(const Hosts& h, int32_t link_cells, int32_t gap_levels);
  void group_chains(uint32_t n, uint32_t segments);
  void judge_chain(const Hosts& h, uint32_t root, uint32_t* members, uint32_t count, PoleStats* stats);
  void order_by_discovery(uint32_t n, uint32_t segments);
  // Their parts.
  uint32_t grow_slice(const Hosts& h, uint32_t seed, uint8_t kind, const int32_t seed_cell[3], SliceBox* box);
  uint32_t ring_voxels(const Hosts& h, const SliceBox& box, int32_t level, int32_t ring_cells) const;
  void sum_chain(const Hosts& h, uint32_t* members, uint32_t count, ChainShape* shape) const;
  void keep_best(const Instance& in, const PoleInfo& info, PoleStats* stats);
  void reject_column_rows(PoleStats* stats);
  uint32_t worst_slot() const;
  void evict_worst(PoleStats* stats);

  PoleConfig config_{};
  Instance* instances_ = nullptr;
  PoleInfo* info_ = nullptr;
  uint32_t* voxel_seg_ = nullptr;  // during build: segment id or a marker; after: kept instance id
  uint32_t* queue_ = nullptr;      // slice BFS, then chain members grouped by root
  uint32_t* offsets_ = nullptr;    // per segment (+1): chain member ranges, then root -> instance
  Segment* segments_ = nullptr;
  uint32_t* row_order_ = nullptr;   // 2 x max_instances: candidates by azimuth (step 5)
  uint32_t* row_parent_ = nullptr;  // 2 x max_instances: row union-find, then row sizes
  uint32_t max_voxels_ = 0;
  uint32_t count_ = 0;
  uint32_t collect_ = 0;  // during build: chains kept before step 5 (max_instances, or twice that)
  bool bound_ = false;
};

}  // namespace gsf
