#include "gsf/detail/pole_extraction.h"

#include <algorithm>
#include <cmath>

namespace gsf {
namespace {

constexpr uint32_t kNone = UINT32_MAX;          // not a host voxel / not visited
constexpr uint32_t kRejected = UINT32_MAX - 1;  // host voxel of a wide or crowded segment
constexpr uint32_t kCurrent = UINT32_MAX - 2;   // member of the segment being built
constexpr int32_t kMaxReachCells = 16;

bool is_segment(uint32_t s) { return s < kCurrent; }

// Horizontal distance from p to the box [lo, hi] (0 inside).
float box_distance(const float p[3], const float lo[2], const float hi[2]) {
  const float dx = p[0] < lo[0] ? lo[0] - p[0] : (p[0] > hi[0] ? p[0] - hi[0] : 0.0f);
  const float dy = p[1] < lo[1] ? lo[1] - p[1] : (p[1] > hi[1] ? p[1] - hi[1] : 0.0f);
  return std::sqrt(dx * dx + dy * dy);
}

bool finite_positive(float v) { return std::isfinite(v) && v > 0.0f; }

}  // namespace

size_t PoleExtraction::required_bytes(const PoleConfig& config, uint32_t max_voxels) {
  return counted_bytes<PoleExtraction>(config, max_voxels);
}

Status PoleExtraction::bind(Arena& arena, const PoleConfig& config, uint32_t max_voxels) {
  bound_ = false;
  count_ = 0;
  if (config.max_instances == 0 || max_voxels == 0 || max_voxels >= kCurrent) return Status::InvalidArgument;
  if ((config.pole_hosts & config.trunk_hosts) != 0) return Status::InvalidArgument;
  for (int k = 0; k < 2; ++k)
    if (!finite_positive(config.max_diameter[k]) || !(config.min_height[k] >= 0.0f) ||
        !std::isfinite(config.min_height[k]) || !(config.stability[k] >= 0.0f && config.stability[k] <= 1.0f))
      return Status::InvalidArgument;
  if (!(config.max_tilt_deg > 0.0f && config.max_tilt_deg < 90.0f) || !finite_positive(config.link_radius) ||
      !(config.ring_width >= 0.0f) || !std::isfinite(config.ring_width) || !(config.max_gap >= 0.0f) ||
      !std::isfinite(config.max_gap))
    return Status::InvalidArgument;
  config_ = config;
  max_voxels_ = max_voxels;
  instances_ = arena.allocate<Instance>(config.max_instances);
  info_ = arena.allocate<PoleInfo>(config.max_instances);
  voxel_seg_ = arena.allocate<uint32_t>(max_voxels);
  queue_ = arena.allocate<uint32_t>(max_voxels);
  offsets_ = arena.allocate<uint32_t>(size_t(max_voxels) + 1);
  segments_ = arena.allocate<Segment>(max_voxels);
  if (arena.counting()) return Status::Ok;
  if (!instances_ || !info_ || !voxel_seg_ || !queue_ || !offsets_ || !segments_) return Status::BufferTooSmall;
  bound_ = true;
  return Status::Ok;
}

uint32_t PoleExtraction::find_root(uint32_t s) {
  while (segments_[s].parent != s) {
    segments_[s].parent = segments_[segments_[s].parent].parent;  // path halving
    s = segments_[s].parent;
  }
  return s;
}

Status PoleExtraction::build(const VoxelLayer& layer, PoleStats* stats_out) {
  PoleStats stats;
  if (stats_out) *stats_out = stats;  // early returns report zeros
  count_ = 0;
  if (!bound_) return Status::NotInitialized;
  const uint32_t n = layer.size();
  if (n > max_voxels_) return Status::InvalidArgument;
  const Voxel* vox = layer.voxels();
  const float vs = layer.config().voxel_size;
  const int32_t ring_cells = static_cast<int32_t>(std::ceil(config_.ring_width / vs));
  const int32_t link_cells = static_cast<int32_t>(std::ceil(config_.link_radius / vs));
  const int32_t gap_levels = 1 + static_cast<int32_t>(std::floor(config_.max_gap / vs + 1e-4f));
  if (ring_cells > kMaxReachCells || link_cells > kMaxReachCells || gap_levels > kMaxReachCells)
    return Status::InvalidArgument;
  const ClassMask hosts = config_.pole_hosts | config_.trunk_hosts;
  auto kind_of = [&](uint32_t v) -> uint8_t {
    return (config_.pole_hosts & class_bit(vox[v].label)) ? uint8_t(kPoleKind) : uint8_t(kTrunkKind);
  };
  auto is_host = [&](uint32_t v) { return (hosts & class_bit(vox[v].label)) != 0; };
  auto cell = [&](uint32_t v, int32_t c[3]) { return layer.cell_of(vox[v].centroid, c); };

  // 1. Slice segments.
  for (uint32_t i = 0; i < n; ++i) voxel_seg_[i] = kNone;
  uint32_t segments = 0;
  for (uint32_t seed = 0; seed < n; ++seed) {
    if (voxel_seg_[seed] != kNone || !is_host(seed)) continue;
    int32_t sc[3];
    if (!cell(seed, sc)) {
      voxel_seg_[seed] = kRejected;
      continue;
    }
    const uint8_t kind = kind_of(seed);
    uint32_t head = 0, tail = 0;
    queue_[tail++] = seed;
    voxel_seg_[seed] = kCurrent;
    float lo[2] = {vox[seed].centroid[0], vox[seed].centroid[1]}, hi[2] = {lo[0], lo[1]};
    int32_t clo[2] = {sc[0], sc[1]}, chi[2] = {sc[0], sc[1]};
    while (head < tail) {
      const uint32_t v = queue_[head++];
      int32_t c[3];
      if (!cell(v, c)) continue;
      for (int k = 0; k < 2; ++k) {
        lo[k] = std::min(lo[k], vox[v].centroid[k]);
        hi[k] = std::max(hi[k], vox[v].centroid[k]);
        clo[k] = std::min(clo[k], c[k]);
        chi[k] = std::max(chi[k], c[k]);
      }
      for (int32_t dx = -1; dx <= 1; ++dx)
        for (int32_t dy = -1; dy <= 1; ++dy) {
          const uint32_t u = layer.find_cell(c[0] + dx, c[1] + dy, c[2]);
          if (u == UINT32_MAX || voxel_seg_[u] != kNone || !is_host(u) || kind_of(u) != kind) continue;
          voxel_seg_[u] = kCurrent;
          queue_[tail++] = u;  // each voxel enters once: tail <= n
        }
    }
    ++stats.segments;
    stats.host_voxels += tail;
    const float ex = hi[0] - lo[0], ey = hi[1] - lo[1];
    uint32_t mark = kRejected;
    if (std::sqrt(ex * ex + ey * ey) > config_.max_diameter[kind]) {
      ++stats.segments_wide;
    } else {
      // Isolation ring: host voxels of this level outside the segment within ring_width of its box.
      uint32_t ring = 0;
      if (config_.ring_width > 0.0f)
        for (int32_t x = clo[0] - ring_cells; x <= chi[0] + ring_cells; ++x)
          for (int32_t y = clo[1] - ring_cells; y <= chi[1] + ring_cells; ++y) {
            const uint32_t u = layer.find_cell(x, y, sc[2]);
            if (u == UINT32_MAX || voxel_seg_[u] == kCurrent || !is_host(u)) continue;
            ring += box_distance(vox[u].centroid, lo, hi) <= config_.ring_width;
          }
      if (ring > config_.max_ring_voxels) {
        ++stats.segments_crowded;
      } else {
        mark = segments;
        Segment& s = segments_[segments++];
        s.parent = mark;
        s.level = sc[2];
        s.ring = static_cast<uint16_t>(ring);
        s.kind = kind;
        s.pad = 0;
      }
    }
    for (uint32_t q = 0; q < tail; ++q) voxel_seg_[queue_[q]] = mark;
  }

  // 2. Link stacked thin segments (union by smaller id, so roots are deterministic).
  const float link2 = config_.link_radius * config_.link_radius;
  for (uint32_t v = 0; v < n; ++v) {
    const uint32_t sv = voxel_seg_[v];
    if (!is_segment(sv)) continue;
    int32_t c[3];
    if (!cell(v, c)) continue;
    for (int32_t g = 1; g <= gap_levels; ++g)
      for (int32_t dx = -link_cells; dx <= link_cells; ++dx)
        for (int32_t dy = -link_cells; dy <= link_cells; ++dy) {
          const uint32_t u = layer.find_cell(c[0] + dx, c[1] + dy, c[2] + g);
          if (u == UINT32_MAX || !is_segment(voxel_seg_[u])) continue;
          const uint32_t su = voxel_seg_[u];
          if (segments_[su].kind != segments_[sv].kind) continue;
          const float ddx = vox[u].centroid[0] - vox[v].centroid[0], ddy = vox[u].centroid[1] - vox[v].centroid[1];
          if (ddx * ddx + ddy * ddy > link2) continue;
          const uint32_t a = find_root(sv), b = find_root(su);
          if (a == b) continue;
          if (a < b) segments_[b].parent = a;
          else segments_[a].parent = b;
        }
  }

  // 3. Group the chains' voxels by root (stable counting sort: voxel order within a chain).
  for (uint32_t s = 0; s <= segments; ++s) offsets_[s] = 0;
  for (uint32_t v = 0; v < n; ++v)
    if (is_segment(voxel_seg_[v])) ++offsets_[find_root(voxel_seg_[v]) + 1];
  for (uint32_t s = 0; s < segments; ++s) offsets_[s + 1] += offsets_[s];
  for (uint32_t v = 0; v < n; ++v)
    if (is_segment(voxel_seg_[v])) queue_[offsets_[find_root(voxel_seg_[v])]++] = v;
  // Now the members of root r are queue_[r == 0 ? 0 : offsets_[r - 1], offsets_[r]).

  for (uint32_t r = 0; r < segments; ++r) {
    if (segments_[r].parent != r) continue;  // not a root
    const uint32_t begin = r == 0 ? 0 : offsets_[r - 1], end = offsets_[r];
    if (begin == end) continue;
    ++stats.chains;
    uint32_t* m = queue_ + begin;
    const uint32_t count = end - begin;
    // Levels: sort by (level, voxel id), count distinct ones, sum segment rings once per segment.
    std::sort(m, m + count, [&](uint32_t a, uint32_t b) {
      const int32_t la = segments_[voxel_seg_[a]].level, lb = segments_[voxel_seg_[b]].level;
      return la != lb ? la < lb : a < b;
    });
    uint32_t levels = 0, chain_segments = 0, ring_sum = 0;
    int32_t last_level = 0;
    double sw = 0, sx = 0, sy = 0, sz = 0, spx = 0, spy = 0, spz = 0;
    float lo[3], hi[3];
    uint32_t points = 0, first = UINT32_MAX;
    for (uint32_t q = 0; q < count; ++q) {
      const uint32_t v = m[q];
      const Segment& s = segments_[voxel_seg_[v]];
      if (q == 0 || s.level != last_level) ++levels;
      last_level = s.level;
      const float* p = vox[v].centroid;
      for (int k = 0; k < 3; ++k) {
        lo[k] = q == 0 ? p[k] : std::min(lo[k], p[k]);
        hi[k] = q == 0 ? p[k] : std::max(hi[k], p[k]);
      }
      sw += 1.0;
      sx += p[0];
      sy += p[1];
      sz += p[2];
      spx += double(p[0]) * vox[v].count;
      spy += double(p[1]) * vox[v].count;
      spz += double(p[2]) * vox[v].count;
      points += vox[v].count;
      first = std::min(first, v);
    }
    // Segments of the chain: each segment's voxels share one level, so count segment ids once via
    // the first voxel met of each (voxel ids ascend within a level).
    for (uint32_t q = 0; q < count; ++q) {
      const uint32_t s = voxel_seg_[m[q]];
      bool seen = false;
      for (uint32_t t = q; t-- > 0 && segments_[voxel_seg_[m[t]]].level == segments_[s].level;)
        if (voxel_seg_[m[t]] == s) {
          seen = true;
          break;
        }
      if (!seen) {
        ++chain_segments;
        ring_sum += segments_[s].ring;
      }
    }
    const uint8_t kind = segments_[r].kind;
    const float height = hi[2] - lo[2] + vs;
    if (levels < config_.min_levels || points < config_.min_points || height < config_.min_height[kind]) {
      ++stats.rejected_short;
      continue;
    }
    // Axis: least squares x = a + b z, y = c + d z about the voxel mean.
    const double mx = sx / sw, my = sy / sw, mz = sz / sw;
    double szz = 0, sxz = 0, syz = 0;
    for (uint32_t q = 0; q < count; ++q) {
      const float* p = vox[m[q]].centroid;
      const double dz = p[2] - mz;
      szz += dz * dz;
      sxz += (p[0] - mx) * dz;
      syz += (p[1] - my) * dz;
    }
    const double bx = szz > 0 ? sxz / szz : 0.0, by = szz > 0 ? syz / szz : 0.0;
    const double tilt = std::atan(std::sqrt(bx * bx + by * by)) * (180.0 / 3.14159265358979323846);
    if (!(tilt <= config_.max_tilt_deg)) {
      ++stats.rejected_tilt;
      continue;
    }
    double rlo[2] = {0, 0}, rhi[2] = {0, 0};
    for (uint32_t q = 0; q < count; ++q) {
      const float* p = vox[m[q]].centroid;
      const double dz = p[2] - mz;
      const double rx = p[0] - mx - bx * dz, ry = p[1] - my - by * dz;
      rlo[0] = q == 0 ? rx : std::min(rlo[0], rx);
      rhi[0] = q == 0 ? rx : std::max(rhi[0], rx);
      rlo[1] = q == 0 ? ry : std::min(rlo[1], ry);
      rhi[1] = q == 0 ? ry : std::max(rhi[1], ry);
    }
    const double thickness = std::sqrt((rhi[0] - rlo[0]) * (rhi[0] - rlo[0]) + (rhi[1] - rlo[1]) * (rhi[1] - rlo[1]));
    if (thickness > config_.max_diameter[kind]) {
      ++stats.rejected_thick;
      continue;
    }

    Instance in{};
    in.centroid[0] = static_cast<float>(spx / points);
    in.centroid[1] = static_cast<float>(spy / points);
    in.centroid[2] = static_cast<float>(spz / points);
    for (int k = 0; k < 3; ++k) in.extent[k] = hi[k] - lo[k] + vs;
    in.stability = config_.stability[kind];
    in.voxel_count = count;
    in.point_count = points;
    in.first_voxel = first;
    in.label = kind == kPoleKind ? uint8_t(kPole) : uint8_t(kTrunk);
    PoleInfo info{};
    info.height = height;
    info.tilt_deg = static_cast<float>(tilt);
    info.thickness = static_cast<float>(thickness);
    info.ring = chain_segments ? float(ring_sum) / float(chain_segments) : 0.0f;
    info.levels = levels;
    info.kind = kind;
    info.first_voxel = first;
    info.score = static_cast<float>(height * std::cos(tilt * (3.14159265358979323846 / 180.0)) / (1.0 + info.ring));

    // Keep the best max_instances by score; on overflow evict the worst.
    auto worse = [&](uint32_t a_slot, const PoleInfo& bi, const Instance& bn) {  // slot a worse than (bi, bn)?
      const PoleInfo& ai = info_[a_slot];
      const Instance& an = instances_[a_slot];
      if (ai.score != bi.score) return ai.score < bi.score;
      if (an.point_count != bn.point_count) return an.point_count < bn.point_count;
      return an.first_voxel > bn.first_voxel;
    };
    uint32_t slot = count_;
    if (count_ == config_.max_instances) {
      uint32_t w = 0;
      for (uint32_t k = 1; k < count_; ++k)
        if (worse(k, info_[w], instances_[w])) w = k;
      ++stats.dropped_capacity;
      if (worse(w, info, in) == false) continue;  // the new one is no better than the worst kept
      slot = w;
    } else {
      ++count_;
    }
    instances_[slot] = in;
    info_[slot] = info;
  }

  // Discovery order (first voxel; unique, so both arrays get the same permutation), then the
  // voxel -> instance map.
  std::sort(instances_, instances_ + count_,
            [](const Instance& a, const Instance& b) { return a.first_voxel < b.first_voxel; });
  std::sort(info_, info_ + count_, [](const PoleInfo& a, const PoleInfo& b) { return a.first_voxel < b.first_voxel; });
  for (uint32_t s = 0; s < segments; ++s) offsets_[s] = UINT32_MAX;  // root -> kept instance
  for (uint32_t k = 0; k < count_; ++k) offsets_[find_root(voxel_seg_[instances_[k].first_voxel])] = k;
  for (uint32_t v = 0; v < n; ++v) {
    const uint32_t s = voxel_seg_[v];
    voxel_seg_[v] = is_segment(s) ? offsets_[find_root(s)] : UINT32_MAX;
  }
  stats.instances = count_;
  if (stats_out) *stats_out = stats;
  return stats.dropped_capacity ? Status::CapacityExceeded : Status::Ok;
}

void PoleExtraction::order_by_score(uint32_t* order) const {
  for (uint32_t i = 0; i < count_; ++i) {  // insertion sort (count_ <= max_instances, small), stable
    uint32_t pos = i;
    while (pos > 0 && info_[order[pos - 1]].score < info_[i].score) {
      order[pos] = order[pos - 1];
      --pos;
    }
    order[pos] = i;
  }
}

}  // namespace gsf
