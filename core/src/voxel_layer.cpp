#include "gsf/detail/voxel_layer.h"

#include <cmath>
#include <cstring>

#include "avx2_clone.h"
#include "fast_exp.h"

namespace gsf {
namespace {

constexpr int32_t kCoordLimit = VoxelLayer::kCellLimit;  // 21-bit packed voxel coordinates

// floor(v * inv_size) if it lies in (-2^20, 2^20 - 1), i.e. for a product in [1 - 2^20, 2^20 - 1);
// the floor truncates through an int32 (SSE2 has no rounding instruction; std::floor is a longer
// sequence).
bool cell_coord(float v, float inv_size, int32_t* out) {
  const float q = v * inv_size;
  if (!(q >= -float(kCoordLimit - 1) && q < float(kCoordLimit - 1))) return false;  // also NaN
  const int32_t t = static_cast<int32_t>(q);
  *out = static_cast<float>(t) > q ? t - 1 : t;
  return true;
}

uint64_t pack3(int32_t x, int32_t y, int32_t z) { return VoxelLayer::pack_cell(x, y, z); }

// The float's order as a signed integer (for finite values): lets the max over the logits vectorise.
inline int32_t ordered_bits(float v) {
  int32_t b;
  std::memcpy(&b, &v, sizeof b);
  return b ^ ((b >> 31) & 0x7FFFFFFF);
}

// One padding lane (exp of 0, never summed or stored): the exp loop then runs whole 4-wide vectors.
constexpr int kLanes = (kNumClasses + 3) / 4 * 4;

// The largest of one point's logits l into *mx; false when a logit is not finite. Max and finiteness
// without branches, on integers so that both loops vectorise (a float max does not without
// -ffast-math). -0 and +0 order differently here, which moves no l - max.
inline bool logits_max(const float* l, float* mx) {
  uint32_t non_finite = 0;
  int32_t max_bits = ordered_bits(l[0]);
  for (int k = 0; k < kNumClasses; ++k) {
    uint32_t bits;
    std::memcpy(&bits, &l[k], sizeof bits);
    non_finite |= static_cast<uint32_t>((bits & 0x7F800000u) == 0x7F800000u);
    const int32_t o = ordered_bits(l[k]);
    max_bits = o > max_bits ? o : max_bits;
  }
  const int32_t b = max_bits ^ ((max_bits >> 31) & 0x7FFFFFFF);
  std::memcpy(mx, &b, sizeof *mx);
  return non_finite == 0;
}

// Softmax of one point's finite logits l (mx: their largest) into prob (kLanes floats; `shifted` keeps
// its padding lane 0 between calls).
inline void softmax_logits(const float* l, float mx, float* prob, float* shifted) {
  for (int k = 0; k < kNumClasses; ++k) shifted[k] = l[k] - mx;
  for (int k = 0; k < kLanes; ++k) prob[k] = detail::exp_nonpositive(shifted[k]);
  float sum = 0.0f;
  for (int k = 0; k < kNumClasses; ++k) sum += prob[k];
  const float inv = 1.0f / sum;
  for (int k = 0; k < kNumClasses; ++k) prob[k] *= inv;
}

// Whether the point that finds n points already in its voxel adds its softmax (VoxelConfig::prob_samples
// = k > 0): the first k do, then every 2nd while n < 2k, every 4th while n < 4k, ...: the stride is
// 2^bit_width(n / k), so the samples spread over the whole sweep of the voxel and grow with log(n).
inline bool takes_sample(uint32_t n, uint32_t k) {
  if (n < k) return true;
  uint32_t q = n / k, width = 0;
  while (q) {
    ++width;
    q >>= 1;
  }
  return width >= 32 || (n & ((1u << width) - 1u)) == 0;
}

// The voxel of `key`: found, or inserted (zeroed) while fewer than max_voxels exist, with the same
// probe sequence as a BoundedHashMap of capacity max_voxels. UINT32_MAX when the layer is full.
inline uint32_t find_or_insert(uint64_t key, uint32_t* slots, uint64_t* keys, Voxel* voxels, uint32_t active,
                               uint32_t max_voxels, uint32_t* count) {
  const uint32_t mask = active - 1;
  for (uint32_t j = static_cast<uint32_t>(mix64(key)) & mask, n = 0; n < active; ++n, j = (j + 1) & mask) {
    const uint32_t sl = slots[j];
    if (sl == 0) {
      if (*count >= max_voxels) return UINT32_MAX;
      slots[j] = *count + 1;
      keys[*count] = key;
      const uint32_t id = (*count)++;
      Voxel& v = voxels[id];
      v.centroid[0] = v.centroid[1] = v.centroid[2] = 0.0f;
      v.count = 0;
      for (int k = 0; k < kNumClasses; ++k) v.prob[k] = 0.0f;
      v.label = 0;
      v.pad[0] = v.pad[1] = v.pad[2] = 0;
      return id;
    }
    if (keys[sl - 1] == key) return sl - 1;
  }
  return UINT32_MAX;
}

}  // namespace

size_t VoxelLayer::required_bytes(const VoxelConfig& config) { return counted_bytes<VoxelLayer>(config); }

Status VoxelLayer::bind(Arena& arena, const VoxelConfig& config) {
  bound_ = false;
  if (!(config.voxel_size > 0.0f) || !(config.column_size >= config.voxel_size) || config.max_voxels == 0 ||
      config.max_columns == 0 || !(config.min_range >= 0.0f) || !(config.max_range > config.min_range))
    return Status::InvalidArgument;
  config_ = config;
  voxels_ = arena.allocate<Voxel>(config.max_voxels);
  slot_count_ = BoundedHashMap<uint32_t>::slots_for(config.max_voxels);
  slots_ = arena.allocate<uint32_t>(slot_count_);
  keys_ = arena.allocate<uint64_t>(config.max_voxels);
  recent_keys_ = arena.allocate<uint64_t>(kRecent);
  recent_ids_ = arena.allocate<uint32_t>(kRecent);
  const bool ok_index = slots_ != nullptr && keys_ != nullptr && recent_keys_ != nullptr && recent_ids_ != nullptr;
  if (ok_index) std::memset(slots_, 0, sizeof(uint32_t) * slot_count_);
  active_slots_ = ok_index ? slot_count_ : 0;  // lookups on a counting or failed bind find nothing
  const bool ok_columns = columns_.bind(arena, config.max_columns);
  column_members_ = arena.allocate<uint32_t>(config.max_voxels);
  column_of_ = arena.allocate<uint32_t>(config.max_voxels);
  count_ = 0;
  if (arena.counting()) return Status::Ok;
  if (!voxels_ || !ok_index || !ok_columns || !column_members_ || !column_of_) return Status::BufferTooSmall;
  bound_ = true;
  return Status::Ok;
}

uint64_t VoxelLayer::key_of(const float p[3]) const {
  const float inv = 1.0f / config_.voxel_size;
  int32_t x, y, z;
  if (!cell_coord(p[0], inv, &x) || !cell_coord(p[1], inv, &y) || !cell_coord(p[2], inv, &z)) return UINT64_MAX;
  return pack3(x, y, z);
}

bool VoxelLayer::cell_of(const float p[3], int32_t out[3]) const {
  const float inv = 1.0f / config_.voxel_size;
  return cell_coord(p[0], inv, &out[0]) && cell_coord(p[1], inv, &out[1]) && cell_coord(p[2], inv, &out[2]);
}

uint32_t VoxelLayer::find(const float p[3]) const {
  const uint64_t k = key_of(p);
  if (k == UINT64_MAX) return UINT32_MAX;
  return index_find(k);
}

Status VoxelLayer::build(const ScanView& scan, VoxelStats* stats_out, bool gather_index) {
  VoxelStats stats;
  if (stats_out) *stats_out = stats;  // early returns report zeros, never a previous scan's numbers
  count_ = 0;
  column_lo_[0] = column_lo_[1] = 0;
  column_hi_[0] = column_hi_[1] = -1;
  if (!bound_) return Status::NotInitialized;
  reset_index(scan.count);
  if (scan.count == 0) return Status::InvalidInput;
  if (scan.points == nullptr || scan.labels == nullptr || scan.stride < 3) return Status::InvalidArgument;
  const bool use_logits = scan.logits != nullptr;
  if (use_logits && scan.logit_dim != static_cast<uint32_t>(kNumClasses)) return Status::InvalidArgument;
  count_ = accumulate_points(scan, use_logits, &stats);
  average_voxels(use_logits ? config_.prob_samples : 0);
  stats.unindexed_voxels = gather_index ? build_columns() : 0;
  stats.voxels = count_;
  if (stats_out) *stats_out = stats;
  if (count_ == 0) return Status::InvalidInput;
  return stats.dropped_points || stats.unindexed_voxels ? Status::CapacityExceeded : Status::Ok;
}

// An empty index. A scan of n points makes at most n voxels: the index only needs the slots for
// min(n, max_voxels).
void VoxelLayer::reset_index(uint32_t points) {
  if (active_slots_ > 0) std::memset(slots_, 0, sizeof(uint32_t) * active_slots_);
  const uint32_t want = BoundedHashMap<uint32_t>::slots_for(points < config_.max_voxels ? points : config_.max_voxels);
  active_slots_ = want < slot_count_ ? want : slot_count_;
  std::memset(recent_keys_, 0xFF, sizeof(uint64_t) * kRecent);  // UINT64_MAX: no packed key is all ones
  columns_.clear_for(0);
}

// The library class of a point, or -1 when it is dropped (and counted): not finite, out of range, or
// an unknown or ignored label.
int VoxelLayer::point_class(const float* p, uint32_t label, float min_r2, float max_r2, VoxelStats* stats) const {
  if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
    ++stats->non_finite;
    return -1;
  }
  const float r2 = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
  if (!(r2 >= min_r2 && r2 <= max_r2)) {
    ++stats->out_of_range;
    return -1;
  }
  const int c = classes_ ? classes_->library_class(label) : class_from_kitti(label);
  if (c == kUnknownClass) {
    ++stats->unknown_label;
    return -1;
  }
  if (c == kIgnoredClass) {
    ++stats->ignored;
    return -1;
  }
  return c;
}

// Every kept point into its voxel: sums of position and class probabilities (the softmax of its logits,
// or 1 for its label) and the point count. Returns the number of voxels. An AVX2 clone on x86-64
// (avx2_clone.h): the softmax's exp runs 8 lanes a vector instead of 4, bitwise the same layer.
GSF_AVX2_CLONE uint32_t VoxelLayer::accumulate_points(const ScanView& scan, bool use_logits, VoxelStats* stats) {
  const float min_r2 = config_.min_range * config_.min_range;
  const float max_r2 = config_.max_range * config_.max_range;
  const float inv_size = 1.0f / config_.voxel_size;
  Voxel* const voxels = voxels_;
  uint32_t* const slots = slots_;
  uint64_t* const keys = keys_;
  uint64_t* const recent_keys = recent_keys_;
  uint32_t* const recent_ids = recent_ids_;
  const uint32_t active = active_slots_, max_voxels = config_.max_voxels;
  uint32_t count = 0;
  // Consecutive points of a scan line often share a voxel: the last key found skips the hash lookup.
  uint64_t last_key = UINT64_MAX;
  uint32_t last_voxel = 0;
  float prob[kLanes], shifted[kLanes] = {};
  const uint32_t samples = config_.prob_samples;
  stats->points_in = scan.count;
  for (uint32_t i = 0; i < scan.count; ++i) {
    const float* p = scan.points + static_cast<size_t>(i) * scan.stride;
    const int c = point_class(p, scan.labels[i], min_r2, max_r2, stats);
    if (c < 0) continue;
    const float* logits = use_logits ? scan.logits + static_cast<size_t>(i) * kNumClasses : nullptr;
    float mx = 0.0f;
    if (use_logits && !logits_max(logits, &mx)) {
      ++stats->non_finite;
      continue;
    }
    int32_t cx, cy, cz;
    if (!cell_coord(p[0], inv_size, &cx) || !cell_coord(p[1], inv_size, &cy) || !cell_coord(p[2], inv_size, &cz)) {
      ++stats->out_of_range;
      continue;
    }
    const uint64_t key = pack3(cx, cy, cz);
    uint32_t id = last_voxel;
    if (key != last_key) {
      // The recent table (direct-mapped, in L1) before the big index: the next scan column revisits
      // the voxels of the last few.
      const uint32_t r = static_cast<uint32_t>((key * 0x9E3779B97F4A7C15ULL) >> (64 - kRecentBits));
      if (recent_keys[r] == key) {
        id = recent_ids[r];
      } else {
        id = find_or_insert(key, slots, keys, voxels, active, max_voxels, &count);
        if (id == UINT32_MAX) {
          ++stats->dropped_points;
          continue;
        }
        recent_keys[r] = key;
        recent_ids[r] = id;
      }
      last_key = key;
      last_voxel = id;
    }
    Voxel& v = voxels[id];
    v.centroid[0] += p[0];
    v.centroid[1] += p[1];
    v.centroid[2] += p[2];
    const uint32_t before = v.count++;
    if (!use_logits) {
      v.prob[c] += 1.0f;
    } else if (samples == 0 || takes_sample(before, samples)) {
      softmax_logits(logits, mx, prob, shifted);
      for (int k = 0; k < kNumClasses; ++k) v.prob[k] += prob[k];
    } else {
      ++stats->unsampled_points;
    }
  }
  return count;
}

uint32_t VoxelLayer::samples_of(uint32_t n, uint32_t k) {
  if (k == 0 || n <= k) return n;
  // k, then per octave [lo, 2 lo) of the count (lo = k, 2k, 4k, ...) the multiples of its stride.
  uint64_t s = k, lo = k, stride = 2;
  while (lo < n) {
    const uint64_t hi = 2 * lo < n ? 2 * lo : n;
    s += (hi + stride - 1) / stride - (lo + stride - 1) / stride;
    lo *= 2;
    stride *= 2;
  }
  return static_cast<uint32_t>(s);
}

// Sums to means (probabilities over the points that added theirs: samples_of(count, prob_samples) with
// logits, every point without), and each voxel's label: its most probable class (the first of equals).
void VoxelLayer::average_voxels(uint32_t prob_samples) {
  for (uint32_t i = 0; i < count_; ++i) {
    Voxel& v = voxels_[i];
    const float inv = 1.0f / static_cast<float>(v.count);
    v.centroid[0] *= inv;
    v.centroid[1] *= inv;
    v.centroid[2] *= inv;
    const uint32_t sampled = samples_of(v.count, prob_samples);
    const float inv_prob = sampled == v.count ? inv : 1.0f / static_cast<float>(sampled);
    for (int k = 0; k < kNumClasses; ++k) v.prob[k] *= inv_prob;
    int best = 0;
    float best_prob = v.prob[0];
    for (int k = 1; k < kNumClasses; ++k)
      if (v.prob[k] > best_prob) {
        best_prob = v.prob[k];
        best = k;
      }
    v.label = static_cast<uint8_t>(best);
  }
}

uint32_t VoxelLayer::build_columns() {
  // Counting sort of voxels into 2-D columns: count, prefix-sum (slot order), fill in voxel order.
  // Voxel centroids lie inside representable cells and column_size >= voxel_size, so every centroid has
  // a column coordinate. column_of_ keeps each voxel's column slot (+1; 0: not indexed) for the fill.
  const float inv = 1.0f / config_.column_size;
  uint32_t unindexed = 0;
  columns_.clear_for(count_);  // at most one column per voxel
  for (uint32_t i = 0; i < count_; ++i) {
    const Voxel& v = voxels_[i];
    int32_t c[2];
    const bool coords = cell_coord(v.centroid[0], inv, &c[0]) && cell_coord(v.centroid[1], inv, &c[1]);
    ColumnCell* cell = columns_.find_or_insert(coords ? pack3(c[0], c[1], 0) : UINT64_MAX);
    if (cell) {
      cell->count += 1;
      if (coords) {
        const bool first = column_lo_[0] > column_hi_[0];
        for (int k = 0; k < 2; ++k) {
          column_lo_[k] = first || c[k] < column_lo_[k] ? c[k] : column_lo_[k];
          column_hi_[k] = first || c[k] > column_hi_[k] ? c[k] : column_hi_[k];
        }
      }
      column_of_[i] = columns_.slot_of(cell) + 1;
    } else {
      ++unindexed;
      column_of_[i] = 0;  // not indexed (column capacity exhausted)
    }
  }
  uint32_t running = 0;
  columns_.for_each([&](uint64_t, ColumnCell& c) {
    c.begin = running;
    running += c.count;
    c.count = 0;
  });
  for (uint32_t i = 0; i < count_; ++i) {
    if (!column_of_[i]) continue;
    ColumnCell& cell = columns_.at_slot(column_of_[i] - 1);
    column_members_[cell.begin + cell.count++] = i;
  }
  return unindexed;
}

uint32_t VoxelLayer::gather_within(const float center[3], float radius, bool horizontal_only, uint32_t* out,
                                   uint32_t max_out, uint32_t* total) const {
  uint32_t written = 0, matched = 0;
  if (bound_ && count_ > 0 && radius > 0.0f && std::isfinite(center[0]) && std::isfinite(center[1]) &&
      std::isfinite(center[2]) && column_lo_[0] <= column_hi_[0]) {
    const float inv = 1.0f / config_.column_size;
    const float r2 = radius * radius;
    // The query square in column coordinates, clipped to the occupied columns' bounding box (in float,
    // so a radius beyond the representable range clips instead of overflowing).
    const float fx0 = std::floor((center[0] - radius) * inv), fx1 = std::floor((center[0] + radius) * inv);
    const float fy0 = std::floor((center[1] - radius) * inv), fy1 = std::floor((center[1] + radius) * inv);
    if (fx1 >= float(column_lo_[0]) && fx0 <= float(column_hi_[0]) && fy1 >= float(column_lo_[1]) &&
        fy0 <= float(column_hi_[1])) {
      const int32_t x0 = fx0 <= float(column_lo_[0]) ? column_lo_[0] : static_cast<int32_t>(fx0);
      const int32_t x1 = fx1 >= float(column_hi_[0]) ? column_hi_[0] : static_cast<int32_t>(fx1);
      const int32_t y0 = fy0 <= float(column_lo_[1]) ? column_lo_[1] : static_cast<int32_t>(fy0);
      const int32_t y1 = fy1 >= float(column_hi_[1]) ? column_hi_[1] : static_cast<int32_t>(fy1);
      for (int32_t cx = x0; cx <= x1; ++cx)
        for (int32_t cy = y0; cy <= y1; ++cy) {
          const ColumnCell* cell = columns_.find(pack3(cx, cy, 0));
          if (!cell) continue;
          for (uint32_t m = 0; m < cell->count; ++m) {
            const uint32_t id = column_members_[cell->begin + m];
            const float* c = voxels_[id].centroid;
            const float dx = c[0] - center[0], dy = c[1] - center[1], dz = horizontal_only ? 0.0f : c[2] - center[2];
            if (dx * dx + dy * dy + dz * dz > r2) continue;
            ++matched;
            if (written < max_out) out[written++] = id;
          }
        }
    }
  }
  if (total) *total = matched;
  return written;
}

}  // namespace gsf
