#include "gsf/detail/semantic_grid.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "gsf/detail/angles.h"
#include "gsf/detail/voxel_layer.h"

namespace gsf {

bool semantic_tile_key(int64_t tx, int64_t ty, uint32_t* key) {
  if (tx <= -32768 || tx >= 32768 || ty <= -32768 || ty >= 32768) return false;
  *key = (uint32_t(tx + 32768) << 16) | uint32_t(ty + 32768);
  return true;
}

namespace {

// Index of the first tile key >= key (tile_count when none), branch-free: the same answer as the
// branching binary search, without its unpredictable branches.
uint32_t tile_lower_bound(const uint32_t* keys, uint32_t n, uint32_t key) {
  if (n == 0) return 0;
  const uint32_t* base = keys;
  while (n > 1) {
    const uint32_t half = n / 2;
    base = base[half] < key ? base + half : base;
    n -= half;
  }
  return static_cast<uint32_t>(base - keys) + (*base < key ? 1u : 0u);
}

// Per-call cache of tile lookups for verify_pose: a hypothesis' voxels fall into a few dozen tiles, so
// most lookups skip the binary search. Entry value 0: empty, 1: tile absent, t + 2: tile t.
struct TileCache {
  static constexpr uint32_t kEntries = 64;
  uint32_t key[kEntries];
  uint32_t value[kEntries] = {};
};

// One axis of a map position in the semantic grid: tile coordinate and cell within the tile, as
// SemanticGridView::cell_at computes them (tile < 0 - 32767: outside every representable tile).
struct GridAxis {
  int32_t tile;
  int32_t cell;
};
constexpr int32_t kOutsideTiles = INT32_MIN;

struct GridConstants {
  float cell, tile;
  // 1 / cell and 1 / tile when both are powers of two (the default 1 m cells in 16 m tiles): then x *
  // (1 / d) is the same correctly rounded x / d, bit for bit, and a multiply instead of a division
  // takes the division's latency off the per-voxel chain (it was the hottest instruction of verify_pose).
  float inv_cell, inv_tile;
  bool exact_inverse;
  int32_t tile_cells;
  bool usable;
};

bool is_power_of_two(float d) {
  int e;
  return d > 0.0f && std::isfinite(d) && std::frexp(d, &e) == 0.5f;
}

GridConstants grid_constants(const SemanticGridView& g) {
  GridConstants k;
  k.usable = g.tile_count != 0 && g.cell > 0.0f;
  k.cell = g.cell;
  k.tile = g.cell * static_cast<float>(g.tile_cells);
  k.tile_cells = static_cast<int32_t>(g.tile_cells);
  k.exact_inverse = k.usable && is_power_of_two(k.cell) && is_power_of_two(k.tile) && std::isnormal(1.0f / k.cell) &&
                    std::isnormal(1.0f / k.tile);
  k.inv_cell = k.exact_inverse ? 1.0f / k.cell : 0.0f;
  k.inv_tile = k.exact_inverse ? 1.0f / k.tile : 0.0f;
  return k;
}

template <bool kExactInverse>
inline GridAxis grid_axis(const GridConstants& k, float x) {
  if (!k.usable) return {kOutsideTiles, 0};
  // cell_at's tile floor(x / tile) is valid within (-32768, 32768), i.e. for a quotient in
  // [-32767, 32768), where truncation through an int32 floors it (SSE2 has no rounding instruction).
  const float q = kExactInverse ? x * k.inv_tile : x / k.tile;
  if (!(q >= -32767.0f && q < 32768.0f)) return {kOutsideTiles, 0};  // also rejects NaN
  int32_t tile = static_cast<int32_t>(q);
  float f = static_cast<float>(tile);
  if (f > q) {
    tile -= 1;
    f -= 1.0f;
  }
  // The cell: (x - f tile) / cell truncated and clamped to [0, n - 1], as in cell_at.
  const float r = x - f * k.tile;
  int32_t c = static_cast<int32_t>(kExactInverse ? r * k.inv_cell : r / k.cell);
  c = c < 0 ? 0 : (c >= k.tile_cells ? k.tile_cells - 1 : c);  // float rounding at the tile's far edge
  return {tile, c};
}

// grid_axis over a block of positions at once: the same arithmetic without branches (a position outside
// the representable tiles, or NaN, computes on a finite stand-in and is then marked outside), so the
// compiler runs it a vector of positions at a time. tile[j], cell[j]: grid_axis(k, x[j]), bit for bit.
template <bool kExactInverse>
inline void grid_axes(const GridConstants& k, const float* __restrict x, uint32_t m, int32_t* __restrict tile,
                      int32_t* __restrict cell) {
  const float inv_tile = k.inv_tile, inv_cell = k.inv_cell, tile_m = k.tile, cell_m = k.cell;
  const int32_t last = k.tile_cells - 1;
#if defined(__aarch64__)
  const float x_limit = 32768.0f * tile_m;
#endif
  for (uint32_t j = 0; j < m; ++j) {
    const float q = kExactInverse ? x[j] * inv_tile : x[j] / tile_m;
    const bool inside = (q >= -32767.0f) & (q < 32768.0f);
    // Inside the tiles q and x themselves; outside (or NaN) finite values in range of the casts, whose
    // results the masks below discard. ARM64 clamps (fmaxnm / fminnm, one NEON instruction each: GCC 12
    // turns selects of floats into branches there under -fno-exceptions, and the loop would not
    // vectorise); x86-64 selects (its fmin / fmax are library calls).
#if defined(__aarch64__)
    const float qs = std::fmin(std::fmax(q, -32767.0f), 32768.0f);
    const float xs = std::fmin(std::fmax(x[j], -x_limit), x_limit);
#else
    const float qs = inside ? q : 0.0f, xs = inside ? x[j] : 0.0f;
#endif
    int32_t t = static_cast<int32_t>(qs);
    const bool below = static_cast<float>(t) > qs;
    t -= below ? 1 : 0;
    // |t| <= 32768: exact in float, so this is the float floor itself. (Taking 1.0f off the float, or
    // selecting the stores instead of masking them, also kept ARM64's loop scalar.)
    const float f = static_cast<float>(t);
    const float r = xs - f * tile_m;
    int32_t c = static_cast<int32_t>(kExactInverse ? r * inv_cell : r / cell_m);
    c = c < 0 ? 0 : c;
    c = c > last ? last : c;
    const int32_t keep = -static_cast<int32_t>(inside);  // all ones inside the tiles, else 0
    tile[j] = (t & keep) | (kOutsideTiles & ~keep);
    cell[j] = c & keep;
  }
}

// A block of samples' positions and cells, for the scoring loops: positions computed sample by sample,
// cells a vector at a time (grid_axes).
struct SampleBlock {
  static constexpr uint32_t kSize = 64;
  float x[kSize], y[kSize];
  int32_t tile_x[kSize], cell_x[kSize], tile_y[kSize], cell_y[kSize];
  uint8_t label[kSize];

  // One axis of the first m positions (grid_axis of each, outside every tile when k is not usable).
  template <bool kExactInverse>
  static void axis_of(const GridConstants& k, uint32_t m, const float* pos, int32_t* tile, int32_t* cell) {
    if (k.usable) {
      grid_axes<kExactInverse>(k, pos, m, tile, cell);
      return;
    }
    std::fill(tile, tile + m, kOutsideTiles);
    std::fill(cell, cell + m, 0);
  }
  // Both axes of the first m positions (x, y).
  template <bool kExactInverse>
  void cells_of(const GridConstants& k, uint32_t m) {
    axis_of<kExactInverse>(k, m, x, tile_x, cell_x);
    axis_of<kExactInverse>(k, m, y, tile_y, cell_y);
  }
};

// Index into g.palette (and g.neighbours) of the cell at the two axes, the tile found through `cache`
// (the cell cell_at finds); kNoCell outside the stored tiles.
constexpr uint32_t kNoCell = UINT32_MAX;
inline uint32_t palette_index_at_axes(const SemanticGridView& g, const GridConstants& k, GridAxis ax, GridAxis ay,
                                      TileCache& cache) {
  if (!k.usable || ax.tile == kOutsideTiles || ay.tile == kOutsideTiles) return kNoCell;
  const uint32_t key = (uint32_t(ax.tile + 32768) << 16) | uint32_t(ay.tile + 32768);
  const uint32_t e = static_cast<uint32_t>((key * 0x9E3779B1u) >> 26);  // 64 entries
  uint32_t t;
  if (cache.value[e] != 0 && cache.key[e] == key) {
    if (cache.value[e] == 1) return kNoCell;
    t = cache.value[e] - 2;
  } else {
    const uint32_t lo = tile_lower_bound(g.tile_keys, g.tile_count, key);
    const bool found = lo < g.tile_count && g.tile_keys[lo] == key;
    cache.key[e] = key;
    cache.value[e] = found ? lo + 2 : 1;
    if (!found) return kNoCell;
    t = lo;
  }
  const size_t n = g.tile_cells;
  return g.palette_offsets[t] + g.cells[size_t(t) * n * n + size_t(ay.cell) * n + size_t(ax.cell)];
}

// Index into g.palette of the cell at (x, y) (cell_at's plain arithmetic); kNoCell outside the tiles.
uint32_t palette_index_at(const SemanticGridView& g, float x, float y, uint32_t* hint) {
  if (g.tile_count == 0 || !(g.cell > 0.0f)) return kNoCell;
  const float tile = g.cell * static_cast<float>(g.tile_cells);
  const float fx = std::floor(x / tile), fy = std::floor(y / tile);
  if (!(std::fabs(fx) < 32768.0f && std::fabs(fy) < 32768.0f)) return kNoCell;  // also rejects NaN
  uint32_t key;
  if (!semantic_tile_key(static_cast<int64_t>(fx), static_cast<int64_t>(fy), &key)) return kNoCell;
  uint32_t t;
  if (hint && *hint < g.tile_count && g.tile_keys[*hint] == key) {
    t = *hint;
  } else {
    const uint32_t lo = tile_lower_bound(g.tile_keys, g.tile_count, key);
    if (lo >= g.tile_count || g.tile_keys[lo] != key) return kNoCell;
    t = lo;
    if (hint) *hint = t;
  }
  int32_t cx = static_cast<int32_t>((x - fx * tile) / g.cell), cy = static_cast<int32_t>((y - fy * tile) / g.cell);
  const int32_t n = static_cast<int32_t>(g.tile_cells);
  cx = cx < 0 ? 0 : (cx >= n ? n - 1 : cx);  // float rounding at the tile's far edge
  cy = cy < 0 ? 0 : (cy >= n ? n - 1 : cy);
  return g.palette_offsets[t] +
         g.cells[size_t(t) * g.tile_cells * g.tile_cells + size_t(cy) * g.tile_cells + size_t(cx)];
}

}  // namespace

uint32_t SemanticGridView::cell_at(float x, float y, uint32_t* hint) const {
  const uint32_t i = palette_index_at(*this, x, y, hint);
  return i == kNoCell ? 0u : palette[i];
}

uint32_t SemanticGridView::neighbours_at(float x, float y) const {
  const uint32_t i = palette_index_at(*this, x, y, nullptr);
  return i == kNoCell || neighbours == nullptr ? 0u : neighbours[i];
}

uint32_t count_observed(const SemanticGridView& grid, const Eigen::Isometry3d& map_T_scan, const float* xyz,
                        uint32_t n) {
  uint32_t observed = 0, hint = 0;
  for (uint32_t i = 0; i < n; ++i) {
    const Eigen::Vector3d p = map_T_scan * Eigen::Vector3d(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
    const float x = float(p.x()), y = float(p.y());
    if ((grid.cell_at(x, y, &hint) | grid.neighbours_at(x, y)) & kCellObserved) ++observed;
  }
  return observed;
}

Status SemanticGridView::validate(uint32_t num_classes) const {
  if (tile_count == 0) return Status::Ok;
  if (!tile_keys || !cells || !palette_offsets || !palette || !neighbours) return Status::CorruptData;
  if (!(cell > 0.0f) || !std::isfinite(cell) || tile_cells == 0 || tile_cells > kMaxSemanticTileCells)
    return Status::CorruptData;
  const uint32_t allowed = kCellObserved | (num_classes >= 31 ? 0x7FFFFFFFu : ((1u << num_classes) - 1));
  for (uint32_t i = 1; i < tile_count; ++i)
    if (tile_keys[i - 1] >= tile_keys[i]) return Status::CorruptData;
  if (palette_offsets[0] != 0 || palette_offsets[tile_count] != palette_count) return Status::CorruptData;
  const uint32_t per_tile = tile_cells * tile_cells;
  for (uint32_t t = 0; t < tile_count; ++t) {
    const uint32_t lo = palette_offsets[t], hi = palette_offsets[t + 1];
    if (hi <= lo || hi - lo > 256) return Status::CorruptData;
    for (uint32_t c = 0; c < per_tile; ++c)
      if (cells[size_t(t) * per_tile + c] >= hi - lo) return Status::CorruptData;
  }
  for (uint32_t i = 0; i < palette_count; ++i)
    if ((palette[i] | neighbours[i]) & ~allowed) return Status::CorruptData;
  return Status::Ok;
}

namespace {

// The two sources verification reads: the voxel layer itself, or its compact bird's-eye copy.
struct VoxelSource {
  static constexpr bool kRecords = false;  // the pattern search keeps no SearchMemo over it
  const VoxelLayer& voxels;
  uint32_t size() const { return voxels.size(); }
  // Bird's-eye position under the upright rotation R (its third column is exactly zero: a z rotation,
  // see verify_pose) plus t; the z term would add an exact zero, so R * (x, y, z) + t is this, bit for bit.
  Eigen::Vector2f at(uint32_t i, const Eigen::Matrix3f& R, const Eigen::Vector3f& t, uint8_t* label) const {
    const Voxel& vx = voxels.voxel(i);
    *label = vx.label;
    const Eigen::Vector3f p = R * Eigen::Vector3f(vx.centroid[0], vx.centroid[1], vx.centroid[2]) + t;
    return p.head<2>();
  }
};

struct PointSource {
  static constexpr bool kRecords = true;
  const VerifyPoint* points;
  uint32_t n;
  uint32_t size() const { return n; }
  Eigen::Vector2f at(uint32_t i, const Eigen::Matrix3f& R, const Eigen::Vector3f& t, uint8_t* label) const {
    const VerifyPoint& q = points[i];
    *label = static_cast<uint8_t>(q.label);
    return Eigen::Vector2f(R(0, 0) * q.x + R(0, 1) * q.y + t.x(), R(1, 0) * q.x + R(1, 1) * q.y + t.y());
  }
};

enum class Verdict { kUnknown, kAgree, kOtherClass, kContradicted };

// Above-ground class bits: a cell holding any of them was seen occupied.
constexpr uint32_t kAboveGroundClasses = ~(kGroundClasses | kCellObserved);

// One sampled voxel (class bit `bit`) against the cell at palette index `at` (kNoCell: outside).
inline Verdict verdict_of(const SemanticGridView& grid, uint32_t at, uint32_t bit) {
  const uint32_t mask = at == kNoCell ? 0u : grid.palette[at];
  const bool ground = (bit & kGroundClasses) != 0;
  if (ground ? !(mask & kGroundClasses) : !(mask & kCellObserved)) return Verdict::kUnknown;
  // A hypothesis pose is good to about a cell: the class in a 4-neighbour cell still agrees (a lattice
  // shift moves cues by metres, far beyond this tolerance). The cell is in a stored tile here, so its
  // palette entry's neighbour mask is there.
  if (mask & bit) return Verdict::kAgree;
  const uint32_t near = mask | grid.neighbours[at];
  if (near & bit) return Verdict::kAgree;
  return !ground && (near & kAboveGroundClasses) ? Verdict::kOtherClass : Verdict::kContradicted;
}

// A pose's score, summed sample by sample in sample order (every scoring path the same sums, bit for bit).
struct Tally {
  PoseVerification v;
  float contradicted = 0.0f, other_class = 0.0f;
  // Adds one sample (class weight w); returns its signed evidence (verify_pose_evidence).
  float add(Verdict verdict, float w, DisagreeWeights disagree) {
    switch (verdict) {
      case Verdict::kUnknown: ++v.unknown; return 0.0f;
      case Verdict::kAgree: v.agree += w; return w;
      case Verdict::kOtherClass: other_class += w; return -disagree.other_class * w;
      case Verdict::kContradicted: contradicted += w; return -disagree.contradicted * w;
    }
    return 0.0f;
  }
  PoseVerification result(uint32_t samples, DisagreeWeights disagree) {
    v.scored = samples - v.unknown;
    v.disagree = contradicted + other_class;
    v.score = v.agree - disagree.contradicted * contradicted - disagree.other_class * other_class;
    return v;
  }
};

// The scoring loop, with the grid's reciprocal test hoisted out of it (kExactInverse: k.exact_inverse).
template <bool kExactInverse, class Source>
PoseVerification score_samples(const Source& src, const SemanticGridView& grid, const GridConstants& k,
                               const Eigen::Isometry3d& T, uint32_t stride, const float* weights,
                               DisagreeWeights disagree, float* evidence = nullptr) {
  const uint32_t n = src.size();
  // Bird's-eye comparison under the upright prior: only the hypothesis' heading and position matter. A
  // clique of mid-height centroids constrains roll and pitch poorly, and a few degrees of tilt would
  // move every tall structure's voxels across cells.
  const float yaw = static_cast<float>(std::atan2(T.linear()(1, 0), T.linear()(0, 0)));
  const Eigen::Matrix3f R = Eigen::AngleAxisf(yaw, Eigen::Vector3f::UnitZ()).toRotationMatrix();
  const Eigen::Vector3f t = T.translation().cast<float>();
  TileCache cache;
  Tally tally;
  SampleBlock b;
  for (uint32_t i = 0; i < n;) {
    uint32_t m = 0;
    for (; m < SampleBlock::kSize && i < n; ++m, i += stride) {
      const Eigen::Vector2f p = src.at(i, R, t, &b.label[m]);
      b.x[m] = p.x();
      b.y[m] = p.y();
    }
    b.cells_of<kExactInverse>(k, m);
    for (uint32_t j = 0; j < m; ++j) {
      const GridAxis ax{b.tile_x[j], b.cell_x[j]}, ay{b.tile_y[j], b.cell_y[j]};
      const uint8_t label = b.label[j];
      const Verdict verdict = verdict_of(grid, palette_index_at_axes(grid, k, ax, ay, cache), class_bit(label));
      const float e = tally.add(verdict, weights[label], disagree);
      if (evidence) *evidence++ = e;
    }
  }
  return tally.result((n + stride - 1) / stride, disagree);
}

template <class Source>
PoseVerification score_pose(const Source& src, const SemanticGridView& grid, const Eigen::Isometry3d& T,
                            uint32_t max_points, const float* weights, DisagreeWeights disagree) {
  const uint32_t n = src.size();
  if (n == 0 || max_points == 0 || grid.empty() || grid.neighbours == nullptr) return PoseVerification();
  const uint32_t stride = (n + max_points - 1) / max_points;
  const GridConstants k = grid_constants(grid);
  return k.exact_inverse ? score_samples<true>(src, grid, k, T, stride, weights, disagree)
                         : score_samples<false>(src, grid, k, T, stride, weights, disagree);
}

// The evidence variant: score_samples with each sample's signed weight written out (k = i / stride).
template <class Source>
PoseVerification score_pose_evidence(const Source& src, const SemanticGridView& grid, const Eigen::Isometry3d& T,
                                     uint32_t max_points, const float* weights, DisagreeWeights disagree,
                                     float* evidence) {
  const uint32_t n = src.size();
  if (n == 0 || max_points == 0 || grid.empty() || grid.neighbours == nullptr) return PoseVerification();
  const uint32_t stride = (n + max_points - 1) / max_points;
  const GridConstants k = grid_constants(grid);
  return k.exact_inverse ? score_samples<true>(src, grid, k, T, stride, weights, disagree, evidence)
                         : score_samples<false>(src, grid, k, T, stride, weights, disagree, evidence);
}

// SearchMemo's cell encoding: a GridAxis as one integer, unique per cell, and back.
static_assert(kMaxSemanticTileCells == 16, "packed cells hold the cell in their low 4 bits");
inline int32_t packed_cell(GridAxis a) { return a.tile == kOutsideTiles ? INT32_MIN : a.tile * 16 + a.cell; }
inline GridAxis unpacked_cell(int32_t c) {
  if (c == INT32_MIN) return {kOutsideTiles, 0};
  const int32_t cell = c & 15;  // two's complement: tile * 16 has its low 4 bits clear
  return {(c - cell) / 16, cell};
}

// Scores T on the sample and records it into `to` (rotated positions, cells, verdicts) when kTurn is
// false; when true, T is the pose recorded in `from` turned about the sensor, and a sample whose cells
// along both axes did not change keeps its verdict without a map lookup (a verdict depends on the cell
// and the label only; a small turn moves only the far samples across cells). Either way score_samples'
// sums, bit for bit (rotated + t is PointSource::at's sum in its order).
template <bool kExactInverse, bool kTurn>
PoseVerification record_pose(const PointSource& src, const SemanticGridView& grid, const GridConstants& k,
                             const Eigen::Isometry3d& T, uint32_t stride, const float* weights,
                             DisagreeWeights disagree, const SearchMemo::Sample* __restrict from,
                             SearchMemo::Sample* __restrict to) {
  const float yaw = static_cast<float>(std::atan2(T.linear()(1, 0), T.linear()(0, 0)));
  const Eigen::Matrix3f R = Eigen::AngleAxisf(yaw, Eigen::Vector3f::UnitZ()).toRotationMatrix();
  const float r00 = R(0, 0), r01 = R(0, 1), r10 = R(1, 0), r11 = R(1, 1);
  const float tx = static_cast<float>(T.translation().x()), ty = static_cast<float>(T.translation().y());
  // Local copies: the stores below could alias the originals, which would be reloaded every sample.
  const GridConstants kc = k;
  const SemanticGridView g = grid;
  const VerifyPoint* const points = src.points;
  const uint32_t n = src.n;
  TileCache cache;
  Tally tally;
  SampleBlock b;
  uint32_t s = 0;
  for (uint32_t i = 0; i < n;) {
    uint32_t m = 0;
    for (; m < SampleBlock::kSize && i < n; ++m, i += stride) {
      const VerifyPoint q = points[i];
      SearchMemo::Sample& r = to[s + m];
      r.rotated[0] = r00 * q.x + r01 * q.y;
      r.rotated[1] = r10 * q.x + r11 * q.y;
      b.x[m] = r.rotated[0] + tx;
      b.y[m] = r.rotated[1] + ty;
      b.label[m] = static_cast<uint8_t>(q.label);
    }
    b.cells_of<kExactInverse>(kc, m);
    for (uint32_t j = 0; j < m; ++j, ++s) {
      const GridAxis ax{b.tile_x[j], b.cell_x[j]}, ay{b.tile_y[j], b.cell_y[j]};
      const uint8_t label = b.label[j];
      SearchMemo::Sample& r = to[s];
      r.cell[0] = packed_cell(ax);
      r.cell[1] = packed_cell(ay);
      r.verdict =
          kTurn && r.cell[0] == from[s].cell[0] && r.cell[1] == from[s].cell[1]
              ? from[s].verdict
              : static_cast<uint32_t>(verdict_of(g, palette_index_at_axes(g, kc, ax, ay, cache), class_bit(label)));
      tally.add(static_cast<Verdict>(r.verdict), weights[label], disagree);
    }
  }
  return tally.result(s, disagree);
}

// Scores T, the pose recorded in `from` moved along kAxis (0: x, 1: y) and not turned, recording it into
// `to`: a sample whose cell along kAxis did not change keeps its verdict without a map lookup.
template <bool kExactInverse, int kAxis>
PoseVerification probe_shift(const PointSource& src, const SemanticGridView& grid, const GridConstants& k,
                             const Eigen::Isometry3d& T, uint32_t stride, const float* weights,
                             DisagreeWeights disagree, const SearchMemo::Sample* __restrict from,
                             SearchMemo::Sample* __restrict to) {
  const float shift = static_cast<float>(T.translation()(kAxis));
  const GridConstants kc = k;  // local copies, as in record_pose
  const SemanticGridView g = grid;
  const VerifyPoint* const points = src.points;
  const uint32_t n = src.n;
  const uint32_t count = n == 0 ? 0 : (n + stride - 1) / stride;
  TileCache cache;
  Tally tally;
  SampleBlock b;
  for (uint32_t s0 = 0; s0 < count; s0 += SampleBlock::kSize) {
    const uint32_t m = std::min(SampleBlock::kSize, count - s0);
    for (uint32_t j = 0; j < m; ++j) b.x[j] = from[s0 + j].rotated[kAxis] + shift;
    b.axis_of<kExactInverse>(kc, m, b.x, b.tile_x, b.cell_x);
    for (uint32_t j = 0; j < m; ++j) {
      const uint32_t s = s0 + j;
      SearchMemo::Sample r = from[s];
      const uint8_t label = static_cast<uint8_t>(points[size_t(s) * stride].label);
      const GridAxis moved{b.tile_x[j], b.cell_x[j]};
      const int32_t cell = packed_cell(moved);
      if (cell != r.cell[kAxis]) {
        const GridAxis kept = unpacked_cell(r.cell[1 - kAxis]);
        const uint32_t at = kAxis == 0 ? palette_index_at_axes(g, kc, moved, kept, cache)
                                       : palette_index_at_axes(g, kc, kept, moved, cache);
        r.cell[kAxis] = cell;
        r.verdict = static_cast<uint32_t>(verdict_of(g, at, class_bit(label)));
      }
      to[s] = r;
      tally.add(static_cast<Verdict>(r.verdict), weights[label], disagree);
    }
  }
  return tally.result(count, disagree);
}

// The pattern search's score of T on max_points through the memo: from the record in `from` when T moves
// it along shift_axis (0: x, 1: y), from it turned about the sensor (shift_axis 2), else (shift_axis -1)
// from scratch; recorded into `to`.
PoseVerification memo_score(const PointSource& src, const SemanticGridView& grid, const Eigen::Isometry3d& T,
                            uint32_t max_points, const float* weights, DisagreeWeights disagree,
                            const SearchMemo::Sample* from, SearchMemo::Sample* to, int shift_axis) {
  const uint32_t n = src.size();
  if (n == 0 || max_points == 0 || grid.empty() || grid.neighbours == nullptr) return PoseVerification();
  const uint32_t stride = (n + max_points - 1) / max_points;
  const GridConstants k = grid_constants(grid);
  const bool e = k.exact_inverse;
  if (shift_axis == 0)
    return e ? probe_shift<true, 0>(src, grid, k, T, stride, weights, disagree, from, to)
             : probe_shift<false, 0>(src, grid, k, T, stride, weights, disagree, from, to);
  if (shift_axis == 1)
    return e ? probe_shift<true, 1>(src, grid, k, T, stride, weights, disagree, from, to)
             : probe_shift<false, 1>(src, grid, k, T, stride, weights, disagree, from, to);
  if (shift_axis == 2)
    return e ? record_pose<true, true>(src, grid, k, T, stride, weights, disagree, from, to)
             : record_pose<false, true>(src, grid, k, T, stride, weights, disagree, from, to);
  return e ? record_pose<true, false>(src, grid, k, T, stride, weights, disagree, nullptr, to)
           : record_pose<false, false>(src, grid, k, T, stride, weights, disagree, nullptr, to);
}

// Samples score_pose takes of n on max_points.
uint32_t sample_count(uint32_t n, uint32_t max_points) {
  if (n == 0 || max_points == 0) return 0;
  const uint32_t stride = (n + max_points - 1) / max_points;
  return (n + stride - 1) / stride;
}

template <class Source>
PoseVerification search_pose(const Source& src, const SemanticGridView& grid, const Eigen::Isometry3d& T,
                             uint32_t max_points, const float* weights, uint32_t rounds, float step_m, float step_deg,
                             Eigen::Isometry3d* refined, uint32_t search_divisor, uint32_t polish_divisor,
                             const PoseVerification* at_start, DisagreeWeights disagree, SearchMemo* memo) {
  Eigen::Isometry3d best = T;
  auto sample = [max_points](uint32_t divisor) {
    const uint32_t d = divisor > 0 ? divisor : 1;
    return max_points / d > 0 ? max_points / d : 1;
  };
  const uint32_t coarse = sample(search_divisor), polish = sample(polish_divisor);
  const bool memo_fits = Source::kRecords && memo != nullptr &&
                         memo->capacity >= std::max(sample_count(src.size(), coarse), sample_count(src.size(), polish));
  int best_slot = 0;  // the memo slot holding the best pose's record (the other: the probe's)
  // Probe k of a pass (-1: the best pose itself, recorded again), scored through the memo when it fits.
  auto score_probe = [&](const Eigen::Isometry3d& c, uint32_t points, int k) -> float {
    if constexpr (Source::kRecords) {
      if (memo_fits) {
        SearchMemo::Sample* to = memo->slot[k < 0 ? best_slot : best_slot ^ 1];
        return memo_score(src, grid, c, points, weights, disagree, memo->slot[best_slot], to,
                          k < 0 ? -1 : (k < 4 ? k / 2 : 2))
            .score;
      }
    }
    return score_pose(src, grid, c, points, weights, disagree).score;
  };
  bool any_move = false;
  uint32_t points = rounds > 1 ? coarse : polish;
  float best_score = score_probe(best, points, -1);
  double step = step_m, turn = deg_to_rad(double(step_deg));
  for (uint32_t r = 0; r < rounds; ++r, step *= 0.5, turn *= 0.5) {
    if (r + 1 == rounds && points != polish) {  // the last, finest round on its own sample
      points = polish;
      best_score = score_probe(best, points, -1);
    }
    bool moved = true;
    int last_move = -1;  // the probe opposite the last move returns to the pose it left, known worse
    for (uint32_t pass = 0; pass < kPatternSearchPassesPerRound && moved; ++pass) {
      moved = false;
      for (int k = 0; k < 6; ++k) {
        if (last_move >= 0 && k == (last_move ^ 1)) continue;
        Eigen::Isometry3d c = best;
        if (k < 4) {
          c.translation().x() += (k == 0 ? step : k == 1 ? -step : 0.0);
          c.translation().y() += (k == 2 ? step : k == 3 ? -step : 0.0);
        } else {
          // Turn about the sensor: map_T_scan * Rz keeps the scan origin where it is.
          c.linear() =
              c.linear() * Eigen::AngleAxisd(k == 4 ? turn : -turn, Eigen::Vector3d::UnitZ()).toRotationMatrix();
        }
        const float sc = score_probe(c, points, k);
        if (sc > best_score) {
          best_score = sc;
          best = c;
          best_slot ^= 1;  // the probe's record is the best's now (unused without the memo)
          moved = any_move = true;
          last_move = k;
        }
      }
    }
  }
  if (refined) *refined = best;
  // Not moved: the full score at the start pose is the caller's, when it has it (the same call).
  if (!any_move && at_start) return *at_start;
  return score_pose(src, grid, best, max_points, weights, disagree);
}

}  // namespace

void fill_verify_points(const VoxelLayer& voxels, VerifyPoint* out) {
  for (uint32_t i = 0; i < voxels.size(); ++i) {
    const Voxel& vx = voxels.voxel(i);
    out[i] = VerifyPoint{vx.centroid[0], vx.centroid[1], vx.label};
  }
}

PoseVerification verify_pose(const VoxelLayer& voxels, const SemanticGridView& grid, const Eigen::Isometry3d& T,
                             uint32_t max_points, const float* weights, DisagreeWeights disagree) {
  return score_pose(VoxelSource{voxels}, grid, T, max_points, weights, disagree);
}

PoseVerification verify_pose(const VerifyPoint* points, uint32_t n, const SemanticGridView& grid,
                             const Eigen::Isometry3d& T, uint32_t max_points, const float* weights,
                             DisagreeWeights disagree) {
  return score_pose(PointSource{points, n}, grid, T, max_points, weights, disagree);
}

PoseVerification verify_pose_evidence(const VerifyPoint* points, uint32_t n, const SemanticGridView& grid,
                                      const Eigen::Isometry3d& T, uint32_t max_points, const float* weights,
                                      DisagreeWeights disagree, float* evidence) {
  return score_pose_evidence(PointSource{points, n}, grid, T, max_points, weights, disagree, evidence);
}

PoseVerification verify_pose_refined(const VoxelLayer& voxels, const SemanticGridView& grid, const Eigen::Isometry3d& T,
                                     uint32_t max_points, const float* weights, uint32_t rounds, float step_m,
                                     float step_deg, Eigen::Isometry3d* refined, uint32_t search_divisor,
                                     uint32_t polish_divisor, const PoseVerification* at_start,
                                     DisagreeWeights disagree) {
  return search_pose(VoxelSource{voxels}, grid, T, max_points, weights, rounds, step_m, step_deg, refined,
                     search_divisor, polish_divisor, at_start, disagree, nullptr);
}

PoseVerification verify_pose_refined(const VerifyPoint* points, uint32_t n, const SemanticGridView& grid,
                                     const Eigen::Isometry3d& T, uint32_t max_points, const float* weights,
                                     uint32_t rounds, float step_m, float step_deg, Eigen::Isometry3d* refined,
                                     uint32_t search_divisor, uint32_t polish_divisor, const PoseVerification* at_start,
                                     DisagreeWeights disagree, SearchMemo* memo) {
  return search_pose(PointSource{points, n}, grid, T, max_points, weights, rounds, step_m, step_deg, refined,
                     search_divisor, polish_divisor, at_start, disagree, memo);
}

VerdictCounts count_verdicts(const VerifyPoint* points, uint32_t n, const SemanticGridView& grid,
                             const Eigen::Isometry3d& T, uint32_t max_points) {
  VerdictCounts c;
  if (n == 0 || max_points == 0 || grid.empty() || grid.neighbours == nullptr) return c;
  const uint32_t stride = (n + max_points - 1) / max_points;
  const GridConstants k = grid_constants(grid);
  const PointSource src{points, n};
  const float yaw = static_cast<float>(std::atan2(T.linear()(1, 0), T.linear()(0, 0)));
  const Eigen::Matrix3f R = Eigen::AngleAxisf(yaw, Eigen::Vector3f::UnitZ()).toRotationMatrix();
  const Eigen::Vector3f t = T.translation().cast<float>();
  TileCache cache;
  for (uint32_t i = 0; i < n; i += stride) {
    uint8_t label;
    const Eigen::Vector2f p = src.at(i, R, t, &label);
    const uint32_t bit = class_bit(label);
    if (bit & kGroundClasses) continue;
    const uint32_t at = palette_index_at_axes(grid, k, grid_axis<false>(k, p.x()), grid_axis<false>(k, p.y()), cache);
    switch (verdict_of(grid, at, bit)) {
      case Verdict::kUnknown: break;
      case Verdict::kAgree: ++c.agree; break;
      case Verdict::kOtherClass: ++c.other_class; break;
      case Verdict::kContradicted: ++c.contradicted; break;
    }
  }
  return c;
}

}  // namespace gsf
