#include "gsf/detail/pole_extraction.h"

#include <algorithm>
#include <cmath>

#include "gsf/detail/angles.h"

namespace gsf {
namespace {

constexpr uint32_t kNone = UINT32_MAX;          // not a host voxel / not visited
constexpr uint32_t kRejected = UINT32_MAX - 1;  // host voxel of a wide or crowded segment
constexpr uint32_t kCurrent = UINT32_MAX - 2;   // member of the segment being built
constexpr int32_t kMaxReachCells = 16;
// Step 5 (beam-column rows): azimuth columns of one surface are one azimuth step apart (0.1-0.4 deg on
// common sensors; 1 deg also links across a column the extraction lost) and, along a surface seen at
// >= 5 deg, at most about range x step / sin(5 deg) < 0.1 x range apart; real poles of a row are degrees
// apart in azimuth. Three columns make a row: a pole with its sign or a second pole behind it makes two.
constexpr float kColumnRowDeg = 1.0f;
constexpr float kColumnRowGap = 0.15f;
constexpr uint32_t kColumnRowMin = 3;

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
  // Twice max_instances: the candidates step 5 thins (header).
  instances_ = arena.allocate<Instance>(2 * size_t(config.max_instances));
  info_ = arena.allocate<PoleInfo>(2 * size_t(config.max_instances));
  row_order_ = arena.allocate<uint32_t>(2 * size_t(config.max_instances));
  row_parent_ = arena.allocate<uint32_t>(2 * size_t(config.max_instances));
  voxel_seg_ = arena.allocate<uint32_t>(max_voxels);
  queue_ = arena.allocate<uint32_t>(max_voxels);
  offsets_ = arena.allocate<uint32_t>(size_t(max_voxels) + 1);
  segments_ = arena.allocate<Segment>(max_voxels);
  if (arena.counting()) return Status::Ok;
  if (!instances_ || !info_ || !voxel_seg_ || !queue_ || !offsets_ || !segments_ || !row_order_ || !row_parent_)
    return Status::BufferTooSmall;
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

struct PoleExtraction::Hosts {
  const VoxelLayer& layer;
  const Voxel* vox;
  ClassMask pole_hosts;
  ClassMask hosts;  // pole and trunk hosts

  uint8_t kind(uint32_t v) const {
    return (pole_hosts & class_bit(vox[v].label)) ? uint8_t(kPoleKind) : uint8_t(kTrunkKind);
  }
  bool host(uint32_t v) const { return (hosts & class_bit(vox[v].label)) != 0; }
  bool cell(uint32_t v, int32_t c[3]) const { return layer.cell_of(vox[v].centroid, c); }
};

struct PoleExtraction::SliceBox {
  float lo[2], hi[2];      // of the voxel centroids
  int32_t clo[2], chi[2];  // of the voxel cells
};

struct PoleExtraction::ChainShape {
  uint32_t levels = 0, segments = 0, ring_sum = 0;  // distinct levels, segments and their rings' sum
  float lo[3], hi[3];                               // centroid box
  double sw = 0, sx = 0, sy = 0, sz = 0;            // voxel-weighted sums (the axis fit)
  double spx = 0, spy = 0, spz = 0;                 // point-weighted sums (the centroid)
  uint32_t points = 0, first = UINT32_MAX;
};

Status PoleExtraction::build(const VoxelLayer& layer, PoleStats* stats_out, LayerFrame frame) {
  PoleStats stats;
  if (stats_out) *stats_out = stats;  // early returns report zeros
  count_ = 0;
  if (!bound_) return Status::NotInitialized;
  const uint32_t n = layer.size();
  if (n > max_voxels_) return Status::InvalidArgument;
  const float vs = layer.config().voxel_size;
  const int32_t ring_cells = static_cast<int32_t>(std::ceil(config_.ring_width / vs));
  const int32_t link_cells = static_cast<int32_t>(std::ceil(config_.link_radius / vs));
  const int32_t gap_levels = 1 + static_cast<int32_t>(std::floor(config_.max_gap / vs + 1e-4f));
  if (ring_cells > kMaxReachCells || link_cells > kMaxReachCells || gap_levels > kMaxReachCells)
    return Status::InvalidArgument;
  const Hosts h{layer, layer.voxels(), config_.pole_hosts, config_.pole_hosts | config_.trunk_hosts};

  // 1. Slice segments.
  const uint32_t segments = find_slice_segments(h, ring_cells, &stats);
  // 2. Link stacked thin segments (union by smaller id, so roots are deterministic).
  link_segments(h, link_cells, gap_levels);
  // 3. Group the chains' voxels by root; the members of root r are queue_[r == 0 ? 0 : offsets_[r - 1],
  // offsets_[r]). 4. Judge each chain; the best collect_ are kept (max_instances, twice that before step 5).
  group_chains(n, segments);
  collect_ = frame == LayerFrame::Sensor ? 2 * config_.max_instances : config_.max_instances;
  for (uint32_t r = 0; r < segments; ++r) {
    if (segments_[r].parent != r) continue;  // not a root
    const uint32_t begin = r == 0 ? 0 : offsets_[r - 1], end = offsets_[r];
    if (begin == end) continue;
    ++stats.chains;
    judge_chain(h, r, queue_ + begin, end - begin, &stats);
  }
  // 5. Beam-column rows, then the best max_instances of what is left.
  if (frame == LayerFrame::Sensor) reject_column_rows(&stats);
  while (count_ > config_.max_instances) evict_worst(&stats);
  order_by_discovery(n, segments);
  stats.instances = count_;
  if (stats_out) *stats_out = stats;
  return stats.dropped_capacity ? Status::CapacityExceeded : Status::Ok;
}

// 1. Per level, the 8-connected components of host voxels of one kind; thin and isolated ones become
// segments (voxel_seg_ = the segment id), the others mark their voxels kRejected. Returns the count.
uint32_t PoleExtraction::find_slice_segments(const Hosts& h, int32_t ring_cells, PoleStats* stats) {
  const uint32_t n = h.layer.size();
  for (uint32_t i = 0; i < n; ++i) voxel_seg_[i] = kNone;
  uint32_t segments = 0;
  for (uint32_t seed = 0; seed < n; ++seed) {
    if (voxel_seg_[seed] != kNone || !h.host(seed)) continue;
    int32_t sc[3];
    if (!h.cell(seed, sc)) {
      voxel_seg_[seed] = kRejected;
      continue;
    }
    const uint8_t kind = h.kind(seed);
    SliceBox box;
    const uint32_t tail = grow_slice(h, seed, kind, sc, &box);
    ++stats->segments;
    stats->host_voxels += tail;
    const float ex = box.hi[0] - box.lo[0], ey = box.hi[1] - box.lo[1];
    uint32_t mark = kRejected;
    if (std::sqrt(ex * ex + ey * ey) > config_.max_diameter[kind]) {
      ++stats->segments_wide;
    } else {
      const uint32_t ring = ring_voxels(h, box, sc[2], ring_cells);
      if (ring > 0) {  // not isolated
        ++stats->segments_crowded;
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
  return segments;
}

// Breadth-first over the 8-connected host voxels of `kind` on the seed's level: the members (marked
// kCurrent) into queue_[0, returned count), their boxes into *box.
uint32_t PoleExtraction::grow_slice(const Hosts& h, uint32_t seed, uint8_t kind, const int32_t sc[3], SliceBox* box) {
  const Voxel* vox = h.vox;
  uint32_t head = 0, tail = 0;
  queue_[tail++] = seed;
  voxel_seg_[seed] = kCurrent;
  float* lo = box->lo;
  float* hi = box->hi;
  int32_t* clo = box->clo;
  int32_t* chi = box->chi;
  lo[0] = vox[seed].centroid[0];
  lo[1] = vox[seed].centroid[1];
  hi[0] = lo[0];
  hi[1] = lo[1];
  clo[0] = chi[0] = sc[0];
  clo[1] = chi[1] = sc[1];
  while (head < tail) {
    const uint32_t v = queue_[head++];
    int32_t c[3];
    if (!h.cell(v, c)) continue;
    for (int k = 0; k < 2; ++k) {
      lo[k] = std::min(lo[k], vox[v].centroid[k]);
      hi[k] = std::max(hi[k], vox[v].centroid[k]);
      clo[k] = std::min(clo[k], c[k]);
      chi[k] = std::max(chi[k], c[k]);
    }
    for (int32_t dx = -1; dx <= 1; ++dx)
      for (int32_t dy = -1; dy <= 1; ++dy) {
        const uint32_t u = h.layer.find_cell(c[0] + dx, c[1] + dy, c[2]);
        if (u == UINT32_MAX || voxel_seg_[u] != kNone || !h.host(u) || h.kind(u) != kind) continue;
        voxel_seg_[u] = kCurrent;
        queue_[tail++] = u;  // each voxel enters once: tail <= n
      }
  }
  return tail;
}

// Isolation ring: host voxels of this level outside the segment (kCurrent) within ring_width of its box.
uint32_t PoleExtraction::ring_voxels(const Hosts& h, const SliceBox& box, int32_t level, int32_t ring_cells) const {
  uint32_t ring = 0;
  if (config_.ring_width > 0.0f)
    for (int32_t x = box.clo[0] - ring_cells; x <= box.chi[0] + ring_cells; ++x)
      for (int32_t y = box.clo[1] - ring_cells; y <= box.chi[1] + ring_cells; ++y) {
        const uint32_t u = h.layer.find_cell(x, y, level);
        if (u == UINT32_MAX || voxel_seg_[u] == kCurrent || !h.host(u)) continue;
        ring += box_distance(h.vox[u].centroid, box.lo, box.hi) <= config_.ring_width;
      }
  return ring;
}

// 2. A segment voxel links to one of the same kind up to gap_levels higher and within link_radius.
void PoleExtraction::link_segments(const Hosts& h, int32_t link_cells, int32_t gap_levels) {
  const Voxel* vox = h.vox;
  const uint32_t n = h.layer.size();
  const float link2 = config_.link_radius * config_.link_radius;
  for (uint32_t v = 0; v < n; ++v) {
    const uint32_t sv = voxel_seg_[v];
    if (!is_segment(sv)) continue;
    int32_t c[3];
    if (!h.cell(v, c)) continue;
    for (int32_t g = 1; g <= gap_levels; ++g)
      for (int32_t dx = -link_cells; dx <= link_cells; ++dx)
        for (int32_t dy = -link_cells; dy <= link_cells; ++dy) {
          const uint32_t u = h.layer.find_cell(c[0] + dx, c[1] + dy, c[2] + g);
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
}

// 3. The chains' voxels grouped by root into queue_ (stable counting sort: voxel order within a chain);
// offsets_[r] ends root r's members.
void PoleExtraction::group_chains(uint32_t n, uint32_t segments) {
  for (uint32_t s = 0; s <= segments; ++s) offsets_[s] = 0;
  for (uint32_t v = 0; v < n; ++v)
    if (is_segment(voxel_seg_[v])) ++offsets_[find_root(voxel_seg_[v]) + 1];
  for (uint32_t s = 0; s < segments; ++s) offsets_[s + 1] += offsets_[s];
  for (uint32_t v = 0; v < n; ++v)
    if (is_segment(voxel_seg_[v])) queue_[offsets_[find_root(voxel_seg_[v])]++] = v;
}

// 4. One chain (its members, sorted here by level): accepted when tall enough, upright and thin about
// its axis, then kept among the best max_instances by score.
void PoleExtraction::judge_chain(const Hosts& h, uint32_t root, uint32_t* m, uint32_t count, PoleStats* stats) {
  const Voxel* vox = h.vox;
  const float vs = h.layer.config().voxel_size;
  ChainShape shape;
  sum_chain(h, m, count, &shape);
  const uint8_t kind = segments_[root].kind;
  const float height = shape.hi[2] - shape.lo[2] + vs;
  if (shape.levels < config_.min_levels || height < config_.min_height[kind]) {
    ++stats->rejected_short;
    return;
  }
  // Axis: least squares x = a + b z, y = c + d z about the voxel mean.
  const double mx = shape.sx / shape.sw, my = shape.sy / shape.sw, mz = shape.sz / shape.sw;
  double szz = 0, sxz = 0, syz = 0;
  for (uint32_t q = 0; q < count; ++q) {
    const float* p = vox[m[q]].centroid;
    const double dz = p[2] - mz;
    szz += dz * dz;
    sxz += (p[0] - mx) * dz;
    syz += (p[1] - my) * dz;
  }
  const double bx = szz > 0 ? sxz / szz : 0.0, by = szz > 0 ? syz / szz : 0.0;
  const double tilt = std::atan(std::sqrt(bx * bx + by * by)) * kDegPerRad;
  if (!(tilt <= config_.max_tilt_deg)) {
    ++stats->rejected_tilt;
    return;
  }
  // Thickness: the box of the residuals about the axis.
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
    ++stats->rejected_thick;
    return;
  }
  Instance in{};
  in.centroid[0] = static_cast<float>(shape.spx / shape.points);
  in.centroid[1] = static_cast<float>(shape.spy / shape.points);
  in.centroid[2] = static_cast<float>(shape.spz / shape.points);
  for (int k = 0; k < 3; ++k) in.extent[k] = shape.hi[k] - shape.lo[k] + vs;
  in.stability = config_.stability[kind];
  in.voxel_count = count;
  in.point_count = shape.points;
  in.first_voxel = shape.first;
  in.label = kind == kPoleKind ? uint8_t(kPole) : uint8_t(kTrunk);
  PoleInfo info{};
  info.height = height;
  info.tilt_deg = static_cast<float>(tilt);
  info.thickness = static_cast<float>(thickness);
  info.ring = shape.segments ? float(shape.ring_sum) / float(shape.segments) : 0.0f;
  info.levels = shape.levels;
  info.kind = kind;
  info.first_voxel = shape.first;
  info.score = static_cast<float>(height * std::cos(tilt * kRadPerDeg) / (1.0 + info.ring));
  keep_best(in, info, stats);
}

// A chain's levels, box and sums: members sorted by (level, voxel id); distinct levels counted, each
// segment's ring summed once.
void PoleExtraction::sum_chain(const Hosts& h, uint32_t* m, uint32_t count, ChainShape* shape) const {
  const Voxel* vox = h.vox;
  std::sort(m, m + count, [&](uint32_t a, uint32_t b) {
    const int32_t la = segments_[voxel_seg_[a]].level, lb = segments_[voxel_seg_[b]].level;
    return la != lb ? la < lb : a < b;
  });
  ChainShape& c = *shape;
  int32_t last_level = 0;
  for (uint32_t q = 0; q < count; ++q) {
    const uint32_t v = m[q];
    const Segment& s = segments_[voxel_seg_[v]];
    if (q == 0 || s.level != last_level) ++c.levels;
    last_level = s.level;
    const float* p = vox[v].centroid;
    for (int k = 0; k < 3; ++k) {
      c.lo[k] = q == 0 ? p[k] : std::min(c.lo[k], p[k]);
      c.hi[k] = q == 0 ? p[k] : std::max(c.hi[k], p[k]);
    }
    c.sw += 1.0;
    c.sx += p[0];
    c.sy += p[1];
    c.sz += p[2];
    c.spx += double(p[0]) * vox[v].count;
    c.spy += double(p[1]) * vox[v].count;
    c.spz += double(p[2]) * vox[v].count;
    c.points += vox[v].count;
    c.first = std::min(c.first, v);
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
      ++c.segments;
      c.ring_sum += segments_[s].ring;
    }
  }
}

// Keep the best collect_ by score; on overflow evict the worst (ties: fewer points, then later
// discovery), unless the new one is no better than it.
namespace {
bool worse_candidate(const PoleInfo& ai, const Instance& an, const PoleInfo& bi, const Instance& bn) {
  if (ai.score != bi.score) return ai.score < bi.score;
  if (an.point_count != bn.point_count) return an.point_count < bn.point_count;
  return an.first_voxel > bn.first_voxel;
}
}  // namespace

void PoleExtraction::keep_best(const Instance& in, const PoleInfo& info, PoleStats* stats) {
  uint32_t slot = count_;
  if (count_ == collect_) {
    const uint32_t w = worst_slot();
    ++stats->dropped_capacity;
    if (!worse_candidate(info_[w], instances_[w], info, in)) return;  // the new one is no better than the worst kept
    slot = w;
  } else {
    ++count_;
  }
  instances_[slot] = in;
  info_[slot] = info;
}

// The kept candidate worse than every other (count_ > 0).
uint32_t PoleExtraction::worst_slot() const {
  uint32_t w = 0;
  for (uint32_t k = 1; k < count_; ++k)
    if (worse_candidate(info_[k], instances_[k], info_[w], instances_[w])) w = k;
  return w;
}

// Drops the worst kept candidate (the last one moves into its slot; discovery order is restored later).
void PoleExtraction::evict_worst(PoleStats* stats) {
  const uint32_t w = worst_slot();
  --count_;
  instances_[w] = instances_[count_];
  info_[w] = info_[count_];
  ++stats->dropped_capacity;
}

// 5. Rows of beam columns (header): candidates sorted by azimuth about the sensor (the origin); each
// one links to those of its kind within kColumnRowDeg after it (cyclically) and within kColumnRowGap x
// the nearer range; the members of a row of >= kColumnRowMin are removed.
void PoleExtraction::reject_column_rows(PoleStats* stats) {
  const uint32_t n = count_;
  if (n < kColumnRowMin) return;
  auto azimuth = [&](uint32_t i) { return std::atan2(instances_[i].centroid[1], instances_[i].centroid[0]); };
  auto range = [&](uint32_t i) { return std::hypot(instances_[i].centroid[0], instances_[i].centroid[1]); };
  for (uint32_t i = 0; i < n; ++i) row_order_[i] = row_parent_[i] = i;
  std::sort(row_order_, row_order_ + n, [&](uint32_t a, uint32_t b) {
    const float za = azimuth(a), zb = azimuth(b);
    return za != zb ? za < zb : a < b;
  });
  auto root = [&](uint32_t i) {
    while (row_parent_[i] != i) i = row_parent_[i] = row_parent_[row_parent_[i]];
    return i;
  };
  const float window = kColumnRowDeg * kRadPerDeg;
  for (uint32_t a = 0; a < n; ++a) {
    const uint32_t i = row_order_[a];
    for (uint32_t step = 1; step < n; ++step) {
      const uint32_t j = row_order_[(a + step) % n];
      float d = azimuth(j) - azimuth(i);
      if (d < 0.0f) d += 2.0f * float(kPi);  // past +-180 deg
      if (!(d <= window)) break;
      if (info_[i].kind != info_[j].kind) continue;
      const float dx = instances_[i].centroid[0] - instances_[j].centroid[0];
      const float dy = instances_[i].centroid[1] - instances_[j].centroid[1];
      if (std::hypot(dx, dy) > kColumnRowGap * std::min(range(i), range(j))) continue;
      const uint32_t ri = root(i), rj = root(j);
      if (ri != rj) row_parent_[std::max(ri, rj)] = std::min(ri, rj);
    }
  }
  // Row sizes at the roots (row_order_ is free again), then compaction of the survivors.
  for (uint32_t i = 0; i < n; ++i) row_order_[i] = 0;
  for (uint32_t i = 0; i < n; ++i) ++row_order_[root(i)];
  uint32_t kept = 0;
  for (uint32_t i = 0; i < n; ++i) {
    if (row_order_[root(i)] >= kColumnRowMin) {
      ++stats->rejected_row;
      continue;
    }
    instances_[kept] = instances_[i];
    info_[kept] = info_[i];
    ++kept;
  }
  count_ = kept;
}

// Discovery order (first voxel; unique, so both arrays get the same permutation), then the
// voxel -> instance map.
void PoleExtraction::order_by_discovery(uint32_t n, uint32_t segments) {
  std::sort(instances_, instances_ + count_,
            [](const Instance& a, const Instance& b) { return a.first_voxel < b.first_voxel; });
  std::sort(info_, info_ + count_, [](const PoleInfo& a, const PoleInfo& b) { return a.first_voxel < b.first_voxel; });
  for (uint32_t s = 0; s < segments; ++s) offsets_[s] = UINT32_MAX;  // root -> kept instance
  for (uint32_t k = 0; k < count_; ++k) offsets_[find_root(voxel_seg_[instances_[k].first_voxel])] = k;
  for (uint32_t v = 0; v < n; ++v) {
    const uint32_t s = voxel_seg_[v];
    voxel_seg_[v] = is_segment(s) ? offsets_[find_root(s)] : UINT32_MAX;
  }
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
