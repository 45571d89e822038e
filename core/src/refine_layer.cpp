#include "gsf/detail/refine_layer.h"

#include <cmath>

#include <Eigen/Dense>

#include "gsf/detail/semantic_grid.h"

namespace gsf {
namespace {

int32_t floor_div(int32_t a, int32_t b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

// Index of the first element of [0, n) for which less(i) is false (n when none), for a predicate that is
// true on a prefix. Branch-free halving (the same answer as the branching binary search without its
// unpredictable branches; semantic_grid.cpp's tile search does the same).
template <typename Less>
uint32_t lower_bound_index(uint32_t n, Less less) {
  if (n == 0) return 0;
  uint32_t base = 0;
  while (n > 1) {
    const uint32_t half = n / 2;
    base = less(base + half) ? base + half : base;
    n -= half;
  }
  return base + (less(base) ? 1u : 0u);
}

}  // namespace

bool refine_tile_of(const RefineCell& c, int32_t* tx, int32_t* ty, uint32_t* key) {
  const int32_t n = static_cast<int32_t>(kRefineTileCells);
  *tx = floor_div(c.x, n);
  *ty = floor_div(c.y, n);
  return semantic_tile_key(*tx, *ty, key);
}

uint8_t quantize_cell_offset(float f) {
  const float q = std::floor(f * 256.0f);
  return static_cast<uint8_t>(q < 0.0f ? 0.0f : (q > 255.0f ? 255.0f : q));
}

int8_t quantize_normal_component(float n) {
  const float q = std::round(n * 127.0f);
  return static_cast<int8_t>(q < -127.0f ? -127.0f : (q > 127.0f ? 127.0f : q));
}

uint32_t RefineLayerView::tile_with_key(uint32_t key) const {
  const uint32_t t = lower_bound_index(tile_count, [&](uint32_t k) { return tiles[k].key < key; });
  return t < tile_count && tiles[t].key == key ? t : tile_count;
}

uint32_t RefineLayerView::tile_of(uint32_t i) const {
  // The last tile whose first point is <= i.
  const uint32_t t = lower_bound_index(tile_count, [&](uint32_t k) { return tiles[k].first_point <= i; });
  return t == 0 ? 0 : t - 1;
}

void RefineLayerView::find(const RefineCell& c, uint32_t* begin, uint32_t* end, uint32_t* hint) const {
  *begin = *end = 0;
  int32_t tx, ty;
  uint32_t key;
  if (tile_count == 0 || !refine_tile_of(c, &tx, &ty, &key)) return;
  uint32_t t;
  if (hint && *hint < tile_count && tiles[*hint].key == key) {
    t = *hint;
  } else {
    t = tile_with_key(key);
    if (t == tile_count) return;
    if (hint) *hint = t;
  }
  const int64_t lz = int64_t(c.z) - tiles[t].z_base;
  if (lz < 0 || lz >= kRefineTileZCells) return;
  const int32_t n = static_cast<int32_t>(kRefineTileCells);
  const uint16_t local =
      static_cast<uint16_t>((uint32_t(lz) << 8) | (uint32_t(c.y - ty * n) << 4) | uint32_t(c.x - tx * n));
  const uint32_t first = tiles[t].first_point;
  const uint32_t last = t + 1 < tile_count ? tiles[t + 1].first_point : point_count;
  const MapRefinePoint* p = points + first;
  const uint32_t lo = lower_bound_index(last - first, [&](uint32_t k) { return p[k].cell < local; });
  uint32_t hi = lo;
  while (hi < last - first && p[hi].cell == local) ++hi;
  *begin = first + lo;
  *end = first + hi;
}

uint32_t RefineLayerView::ground_near(float x, float y, float radius, uint32_t min_points, float up[3]) const {
  if (tile_count == 0 || !(radius > 0.0f) || !(cell > 0.0f)) return 0;
  const float tile_m = cell * float(kRefineTileCells);
  const int32_t tx0 = int32_t(std::floor((x - radius) / tile_m)), tx1 = int32_t(std::floor((x + radius) / tile_m));
  const int32_t ty0 = int32_t(std::floor((y - radius) / tile_m)), ty1 = int32_t(std::floor((y + radius) / tile_m));
  // Bounded work: at most kGroundMaxTilesPerSide tiles a side (a 20 m radius at the default 1 m cell
  // spans 3-4 tiles of 16 m), looked up once for the four passes.
  if (int64_t(tx1) - tx0 + 1 > kGroundMaxTilesPerSide || int64_t(ty1) - ty0 + 1 > kGroundMaxTilesPerSide) return 0;
  uint32_t near[kGroundMaxTilesPerSide * kGroundMaxTilesPerSide];
  uint32_t near_count = 0;
  for (int32_t tx = tx0; tx <= tx1; ++tx)
    for (int32_t ty = ty0; ty <= ty1; ++ty) {
      uint32_t key;
      const uint32_t t = semantic_tile_key(tx, ty, &key) ? tile_with_key(key) : tile_count;
      if (t < tile_count) near[near_count++] = t;
    }
  const float r2 = radius * radius, cos_max = 0.906f;  // cos 25 deg
  Eigen::Vector3d plane = Eigen::Vector3d::Zero();     // z = a dx + b dy + c (dx, dy from x, y)
  uint32_t kept = 0;
  for (int pass = 0; pass < 4; ++pass) {
    const double band = pass == 1 ? 2.0 : (pass == 2 ? 0.5 : 0.25);  // pass 0: every level point, its mean
    Eigen::Matrix3d A = Eigen::Matrix3d::Zero();                     // normal equations of (dx, dy, 1)
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    uint32_t n = 0;
    for (uint32_t k = 0; k < near_count; ++k) {
      const uint32_t t = near[k];
      const uint32_t last = t + 1 < tile_count ? tiles[t + 1].first_point : point_count;
      for (uint32_t i = tiles[t].first_point; i < last; ++i) {
        float nrm[3], p[3];
        normal(points[i], nrm);
        if (!(std::fabs(nrm[2]) >= cos_max)) continue;
        position(t, i, p);
        const Eigen::Vector3d J(double(p[0]) - x, double(p[1]) - y, 1.0);
        if (J.x() * J.x() + J.y() * J.y() > r2) continue;
        if (pass > 0 && std::fabs(double(p[2]) - plane.dot(J)) > band) continue;
        A += J * J.transpose();
        b += double(p[2]) * J;
        ++n;
      }
    }
    if (n < min_points || n < 3) return 0;
    if (pass == 0) {
      plane = Eigen::Vector3d(0.0, 0.0, b.z() / double(n));  // a level start at the mean height
      continue;
    }
    if (!(std::fabs(A.determinant()) > 1e-9)) return 0;  // the points on a line: no plane
    plane = A.inverse() * b;                             // 3 x 3: the closed-form inverse
    kept = n;
  }
  const double len = std::sqrt(plane.x() * plane.x() + plane.y() * plane.y() + 1.0);
  up[0] = float(-plane.x() / len);
  up[1] = float(-plane.y() / len);
  up[2] = float(1.0 / len);
  return kept;
}

void RefineLayerView::position(uint32_t t, uint32_t i, float xyz[3]) const {
  const uint32_t key = tiles[t].key;
  const int32_t n = static_cast<int32_t>(kRefineTileCells);
  const MapRefinePoint& p = points[i];
  const int32_t cx = (int32_t(key >> 16) - 32768) * n + int32_t(p.cell & 0xF);
  const int32_t cy = (int32_t(key & 0xFFFF) - 32768) * n + int32_t((p.cell >> 4) & 0xF);
  const int32_t cz = tiles[t].z_base + int32_t(p.cell >> 8);
  position_in(RefineCell{cx, cy, cz}, p, xyz);
}

void RefineLayerView::position_in(const RefineCell& c, const MapRefinePoint& p, float xyz[3]) const {
  const float step = cell / 256.0f;
  xyz[0] = float(c.x) * cell + (float(p.offset[0]) + 0.5f) * step;
  xyz[1] = float(c.y) * cell + (float(p.offset[1]) + 0.5f) * step;
  xyz[2] = float(c.z) * cell + (float(p.offset[2]) + 0.5f) * step;
}

void RefineLayerView::normal(const MapRefinePoint& p, float n[3]) {
  const float x = p.normal[0], y = p.normal[1], z = p.normal[2];
  const float len2 = x * x + y * y + z * z;
  if (len2 == 0.0f) {
    n[0] = n[1] = n[2] = 0.0f;
    return;
  }
  const float inv = 1.0f / std::sqrt(len2);
  n[0] = x * inv;
  n[1] = y * inv;
  n[2] = z * inv;
}

Status RefineLayerView::validate() const {
  if (point_count == 0 && tile_count == 0) return Status::Ok;
  if (!tiles || !points || tile_count == 0) return Status::CorruptData;
  if (!(std::isfinite(cell) && cell > 0.0f)) return Status::CorruptData;
  if (tiles[0].first_point != 0) return Status::CorruptData;
  for (uint32_t t = 0; t < tile_count; ++t) {
    if (t > 0 && !(tiles[t - 1].key < tiles[t].key && tiles[t - 1].first_point <= tiles[t].first_point))
      return Status::CorruptData;
    if (tiles[t].first_point > point_count) return Status::CorruptData;
    // z_base keeps every cell index of the tile within int32 arithmetic (|z| < 2^30).
    if (tiles[t].z_base < -(1 << 30) || tiles[t].z_base > (1 << 30)) return Status::CorruptData;
    const uint32_t key = tiles[t].key;
    if ((key >> 16) == 0 || (key & 0xFFFF) == 0) return Status::CorruptData;  // semantic_tile_key's range
    const uint32_t last = t + 1 < tile_count ? tiles[t + 1].first_point : point_count;
    for (uint32_t i = tiles[t].first_point; i < last; ++i) {
      if (i > tiles[t].first_point && points[i - 1].cell > points[i].cell) return Status::CorruptData;
      const int32_t x = points[i].normal[0], y = points[i].normal[1], z = points[i].normal[2];
      const int32_t len2 = x * x + y * y + z * z;
      if (len2 != 0 && (len2 < 120 * 120 || len2 > 130 * 130)) return Status::CorruptData;
    }
  }
  return Status::Ok;
}

}  // namespace gsf
