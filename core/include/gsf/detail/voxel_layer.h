// Internal (gsf/detail): a pipeline stage or building block, not part of the stable interface; it may
// change between versions. The stable interface is localizer.h, config.h, map_format.h, scan.h, status.h,
// platform.h, class_table.h, georeference.h, stage_configs.h, stage_results.h and the C API gsf.h.
// The metric-semantic layer (bottom of the scene graph): a scan voxelised into a bounded hash of voxels,
// each with its centroid, point count, mean class-probability vector and argmax label; plus a coarse
// 2-D column index for radius gathers (the neighbourhood each instance's field is trained on).
//
// Per point: non-finite -> counted and skipped; range outside [min_range, max_range] -> skipped;
// label -> library class through the label set's ClassTable (set_classes; without one,
// class_from_kitti, i.e. SemanticKITTI): ignored classes skipped, unknown ids counted and skipped; probability =
// softmax(logits) when the scan carries logits, else one-hot of the label. With logits, a voxel's mean
// probability is over a deterministic subset of its points (VoxelConfig::prob_samples: the first k, then
// every 2nd, 4th, ... as its count doubles; samples_of()); its centroid and count take every point.
// A dense sensor's near voxels (hundreds of points at 128 beams) then stop costing a softmax a point.
// Voxels are stored densely in order of first insertion (scan point order), so the layer is deterministic.
// Capacity: when max_voxels is reached, points that fall into existing voxels still accumulate and
// points needing a new voxel are dropped (counted). When the 2-D gather index runs out of columns
// (max_columns), the voxels of the missing columns stay in the layer but gather_within() cannot see them
// (counted as unindexed_voxels). In both cases the layer stays fully usable and build() returns
// Status::CapacityExceeded as a warning (the voxels are valid).
// Other statuses: NotInitialized before a successful bind(); InvalidArgument for a malformed view
// (null points/labels with count > 0, stride < 3, logit_dim != kNumClasses); InvalidInput for an empty
// scan or one without a single usable point. On every non-Ok status except CapacityExceeded the layer
// is empty (size() == 0), never stale from a previous scan.
#pragma once
#include <cstdint>

#include "gsf/class_table.h"
#include "gsf/detail/arena.h"
#include "gsf/detail/bounded_hash_map.h"
#include "gsf/scan.h"
#include "gsf/semantic_classes.h"
#include "gsf/stage_configs.h"
#include "gsf/status.h"

namespace gsf {

struct Voxel {  // 96 B; what verification, clustering and refinement read sits in the first 20
  // centroid and label share the first 16 bytes: with the arena's 16-byte alignment they never straddle
  // a cache line (verification reads just these two, ~180k sampled voxels a query)
  float centroid[3];
  uint8_t label;  // dense argmax class
  uint8_t pad[3];
  uint32_t count;
  float prob[kNumClasses];  // mean class probability
};

struct VoxelStats {
  uint32_t points_in = 0, non_finite = 0, out_of_range = 0, ignored = 0, unknown_label = 0;
  uint32_t voxels = 0, dropped_points = 0;
  uint32_t unindexed_voxels = 0;  // voxels left out of the gather index (column capacity)
  uint32_t unsampled_points = 0;  // kept points whose softmax was skipped (VoxelConfig::prob_samples)
};

class VoxelLayer {
 public:
  static size_t required_bytes(const VoxelConfig& config);
  Status bind(Arena& arena, const VoxelConfig& config);
  // gather_index = false leaves out the 2-D column index (gather_within() then matches nothing): a
  // tracked scan reads only the voxels, and the index was 3% of its instructions.
  Status build(const ScanView& scan, VoxelStats* stats, bool gather_index = true);
  // The label set of the scans' raw label ids (not copied: it must outlive the layer's use); nullptr
  // (the default) means SemanticKITTI ids through class_from_kitti().
  void set_classes(const ClassTable* table) { classes_ = table; }

  uint32_t size() const { return count_; }
  const Voxel& voxel(uint32_t i) const { return voxels_[i]; }
  const Voxel* voxels() const { return voxels_; }
  const VoxelConfig& config() const { return config_; }

  // Indices of voxels whose centroid lies within `radius` of `center` (horizontal distance only when
  // horizontal_only), in a deterministic order (column by column, ascending within a column). Returns
  // the number written (<= max_out; the first max_out of that order); *total (if given) is the number
  // that matched, so a caller can tell it was truncated. Cost: the column cells of the query square,
  // clipped to the occupied columns' bounding box (so a huge radius stays bounded), plus their members.
  // A non-finite centre, a NaN radius or radius <= 0 matches nothing; radius = +inf matches every indexed voxel.
  uint32_t gather_within(const float center[3], float radius, bool horizontal_only, uint32_t* out, uint32_t max_out,
                         uint32_t* total = nullptr) const;
  // How many of a voxel's n points add their softmax when VoxelConfig::prob_samples is k (0: all n):
  // n up to k, then k + about k/2 per doubling of n (closed form of the rule in accumulate_points).
  static uint32_t samples_of(uint32_t n, uint32_t k);
  // Index of the voxel containing point p, or UINT32_MAX.
  uint32_t find(const float p[3]) const;
  uint64_t key_of(const float p[3]) const;
  // Integer voxel coordinates of p (false if outside the representable +-2^20 voxels).
  bool cell_of(const float p[3], int32_t out[3]) const;
  // Voxel index at integer voxel coordinates, or UINT32_MAX. Inline: clustering calls it for every
  // neighbour cell of every instance voxel (~130k times a scan).
  uint32_t find_cell(int32_t x, int32_t y, int32_t z) const;

  // Voxel keys: coordinates within +-kCellLimit packed into 21 bits each.
  static constexpr int32_t kCellLimit = 1 << 20;
  static uint64_t pack_cell(int32_t x, int32_t y, int32_t z) {
    return (uint64_t(uint32_t(x + kCellLimit)) << 42) | (uint64_t(uint32_t(y + kCellLimit)) << 21) |
           uint64_t(uint32_t(z + kCellLimit));
  }

 private:
  struct ColumnCell {
    uint32_t begin, count;
  };
  // The steps of build(), in order.
  void reset_index(uint32_t points);
  uint32_t accumulate_points(const ScanView& scan, bool use_logits, VoxelStats* stats);
  void average_voxels(uint32_t prob_samples);
  uint32_t build_columns();  // returns the number of voxels left unindexed
  int point_class(const float* p, uint32_t label, float min_r2, float max_r2, VoxelStats* stats) const;

  VoxelConfig config_{};
  const ClassTable* classes_ = nullptr;
  Voxel* voxels_ = nullptr;
  // Voxel key -> voxel index: open addressing (mix64, linear probing, load <= 0.5) over slots that hold
  // index + 1 (0 = empty); the keys live densely per voxel in keys_, so a probe reads 4 bytes of slot
  // and then the key of a voxel the scan is about to touch anyway. Only the first active_slots_ slots
  // (a power of two >= 2 min(points, max_voxels)) are used per scan.
  uint32_t index_find(uint64_t key) const;
  uint32_t* slots_ = nullptr;
  uint64_t* keys_ = nullptr;
  // Recently found voxels, direct-mapped by key hash (12 KB: stays in L1): a scan's next column mostly
  // hits the voxels of the last few, and the big index's slots and keys miss the caches at 100k points.
  static constexpr uint32_t kRecentBits = 10, kRecent = 1u << kRecentBits;
  uint64_t* recent_keys_ = nullptr;
  uint32_t* recent_ids_ = nullptr;
  uint32_t slot_count_ = 0, active_slots_ = 0;
  BoundedHashMap<ColumnCell> columns_;  // column key -> range in column_members_
  uint32_t* column_members_ = nullptr;  // voxel ids grouped by column
  uint32_t* column_of_ = nullptr;       // scratch: per voxel its column slot order
  uint32_t count_ = 0;
  int32_t column_lo_[2] = {0, 0}, column_hi_[2] = {-1, -1};  // occupied column bbox (empty: lo > hi)
  bool bound_ = false;
};

inline uint32_t VoxelLayer::index_find(uint64_t key) const {
  if (active_slots_ == 0) return UINT32_MAX;
  const uint32_t mask = active_slots_ - 1;
  for (uint32_t i = static_cast<uint32_t>(mix64(key)) & mask, n = 0; n < active_slots_; ++n, i = (i + 1) & mask) {
    const uint32_t s = slots_[i];
    if (s == 0) return UINT32_MAX;
    if (keys_[s - 1] == key) return s - 1;
  }
  return UINT32_MAX;
}

inline uint32_t VoxelLayer::find_cell(int32_t x, int32_t y, int32_t z) const {
  if (x <= -kCellLimit || x >= kCellLimit - 1 || y <= -kCellLimit || y >= kCellLimit - 1 || z <= -kCellLimit ||
      z >= kCellLimit - 1)
    return UINT32_MAX;
  return index_find(pack_cell(x, y, z));
}

}  // namespace gsf
