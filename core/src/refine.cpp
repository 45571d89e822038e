#include "gsf/detail/refine.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>

#include "gsf/detail/angles.h"
#include "gsf/semantic_classes.h"

namespace gsf {

size_t Refiner::required_bytes(const RefineConfig& config) { return counted_bytes<Refiner>(config); }

Status Refiner::bind(Arena& arena, const RefineConfig& c) {
  bound_ = false;
  if (c.max_points == 0 || c.iterations == 0 || !(c.cell > 0) || !(c.radius_end > 0) ||
      !(c.radius_start >= c.radius_end) || c.radius_start > c.cell * 1.5f)
    return Status::InvalidArgument;
  config_ = c;
  query_ = arena.allocate<float>(size_t(c.max_points) * 3);
  query_cell_ = arena.allocate<uint64_t>(c.max_points);
  query_begin_ = arena.allocate<uint32_t>(size_t(c.max_points) * 27);
  query_end_ = arena.allocate<uint32_t>(size_t(c.max_points) * 27);
  query_pole_ = arena.allocate<uint8_t>(c.max_points);
  map_ = RefineLayerView();
  if (arena.counting()) return Status::Ok;
  if (!query_ || !query_cell_ || !query_begin_ || !query_end_ || !query_pole_) return Status::BufferTooSmall;
  bound_ = true;
  return Status::Ok;
}

namespace {
// The 27 neighbour cells j = 9 (dx + 1) + 3 (dy + 1) + dz + 1 nearest first: the own cell, the 6 faces,
// the 12 edges, the 8 corners (Refiner::refine, for a query point whose neighbours are not all the cells
// their offsets name).
constexpr uint8_t kVisitOrder[27] = {13, 4,  22, 10, 16, 12, 14, 1, 3, 5,  7,  9,  11, 15,
                                     17, 19, 21, 23, 25, 0,  2,  6, 8, 18, 20, 24, 26};
}  // namespace

Status Refiner::set_map(const RefineLayerView& layer) {
  if (!bound_) return Status::NotInitialized;
  if (layer.point_count > 0 && layer.cell != config_.cell) return Status::ConfigMismatch;
  map_ = layer;
  return Status::Ok;
}

Status Refiner::refine(const VoxelLayer& layer, const Eigen::Isometry3d& initial, Eigen::Isometry3d* out,
                       RefineStats* st_out) {
  RefineStats st;
  *out = initial;
  if (!bound_) return Status::NotInitialized;
  if (map_.empty()) return Status::Unsupported;
  const uint32_t q = pick_query_points(layer);
  st.query_points = q;
  uint32_t tile_hint = 0;
  for (uint32_t i = 0; i < q; ++i) query_cell_[i] = UINT64_MAX;
  Eigen::Isometry3d t = initial;
  // Gauss-Newton iterations with a correspondence radius shrinking from radius_start to radius_end.
  for (uint32_t it = 0; it < config_.iterations; ++it) {
    const float frac = config_.iterations > 1 ? float(it) / float(config_.iterations - 1) : 1.0f;
    const float radius = config_.radius_start + (config_.radius_end - config_.radius_start) * frac;
    const float r2 = radius * radius;
    Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> g = Eigen::Matrix<double, 6, 1>::Zero();
    double err = 0;
    const uint32_t inl = add_correspondence_rows(t, q, r2, &tile_hint, &H, &g, &err);
    ++st.iterations;  // iterations run (a settled refinement skips some)
    st.inliers = inl;
    st.rmse = inl ? std::sqrt(err / inl) : 0;
    bool settled = false;
    if (inl < 6 || !apply_update(H, g, &t, &settled)) break;
    // Settled at this radius: the remaining middle radii would find the same correspondences again, so
    // go straight to the last (tightest) one, which drops the far pairs.
    if (settled && it + 2 < config_.iterations) it = config_.iterations - 2;
  }
  st.accepted =
      st.inliers >= config_.min_inliers && (t.translation() - initial.translation()).norm() <= config_.max_correction;
  if (st.accepted) *out = t;
  if (st_out) *st_out = st;
  return Status::Ok;
}

Status Refiner::refine(const VoxelLayer& layer, const Eigen::Isometry3d& initial, Eigen::Isometry3d* out,
                       RefineStats* stats, uint32_t points, uint32_t iterations) {
  const RefineConfig bound = config_;
  if (points > 0 && points < config_.max_points) config_.max_points = points;
  if (iterations > 0 && iterations < config_.iterations) config_.iterations = iterations;
  const Status s = refine(layer, initial, out, stats);
  config_ = bound;
  return s;
}

// Query points: long-term voxels, deterministic stride subsample, into query_. Returns how many.
uint32_t Refiner::pick_query_points(const VoxelLayer& layer) {
  uint32_t eligible = 0;
  for (uint32_t i = 0; i < layer.size(); ++i) eligible += long_term(layer.voxel(i).label);
  const uint32_t stride = eligible > config_.max_points ? (eligible + config_.max_points - 1) / config_.max_points : 1;
  uint32_t q = 0, seen = 0;
  for (uint32_t i = 0; i < layer.size() && q < config_.max_points; ++i) {
    const Voxel& v = layer.voxel(i);
    if (!long_term(v.label)) continue;
    if (seen++ % stride) continue;
    for (int k = 0; k < 3; ++k) query_[3 * q + k] = v.centroid[k];
    query_pole_[q] = v.label == kPole || v.label == kTrunk;
    ++q;
  }
  return q;
}

// The normal equations at pose t: each query point with a map point within the radius (r2 squared)
// adds its residual's rows to H, g and err. Returns how many did.
//  - Point to plane along the map point's normal.
//  - A pole or trunk voxel whose map point has no normal (a column: nothing planar within a cell) adds
//    its horizontal offset from that point (an x and a y row). Without these rows a car park of columns
//    on flat ground gives ICP nothing to hold x, y and heading, and tracking there drifted 0.3-0.57 m
//    (docs/vehicle-modes.md, "Poles in ICP"). A column seen from opposite sides by the map and the query
//    is off by up to its diameter; rows of columns either side of an aisle cancel most of that.
// The small rotation turns about the sensor (t's origin), not the map's origin: its lever is the
// point's range, not a distance of kilometres across the map, so H stays well conditioned.
uint32_t Refiner::add_correspondence_rows(const Eigen::Isometry3d& t, uint32_t q, float r2, uint32_t* tile_hint,
                                          Eigen::Matrix<double, 6, 6>* H, Eigen::Matrix<double, 6, 1>* g, double* err) {
  auto add_row = [&](const Eigen::Vector3d& arm, const Eigen::Vector3d& n, double r) {
    Eigen::Matrix<double, 6, 1> J;
    J.head<3>() = arm.cross(n);  // d r / d (small rotation about the sensor)
    J.tail<3>() = n;             // d r / d translation
    *H += J * J.transpose();
    *g += J * r;
    *err += r * r;
  };
  uint32_t inl = 0;
  for (uint32_t i = 0; i < q; ++i) {
    const Eigen::Vector3d p = t * Eigen::Vector3d(query_[3 * i], query_[3 * i + 1], query_[3 * i + 2]);
    const float pf[3] = {float(p.x()), float(p.y()), float(p.z())};
    float nearest[3] = {0, 0, 0};
    const MapRefinePoint* nearest_point = find_nearest(i, pf, r2, tile_hint, nearest);
    if (nearest_point == nullptr) continue;
    float nearest_normal[3];
    RefineLayerView::normal(*nearest_point, nearest_normal);
    const Eigen::Vector3d nrm(nearest_normal[0], nearest_normal[1], nearest_normal[2]);
    const Eigen::Vector3d m(nearest[0], nearest[1], nearest[2]);
    const Eigen::Vector3d arm = p - t.translation();
    if (nrm.squaredNorm() >= 0.5) {
      add_row(arm, nrm, nrm.dot(p - m));  // point-to-plane residual
    } else if (query_pole_[i]) {
      add_row(arm, Eigen::Vector3d::UnitX(), p.x() - m.x());
      add_row(arm, Eigen::Vector3d::UnitY(), p.y() - m.y());
    } else {
      continue;
    }
    ++inl;
  }
  return inl;
}

// The 6x6 solve and the pose update (small rotation, then translation) applied to *t. False when the
// solution is not finite. *settled: the update moved the pose by less than kSettledM and turned it by
// less than kSettledRad, a thirtieth and a twentieth of what tracking calls precise (0.3 m, 1 deg), so
// more iterations at the same radius would not change the answer. (3 mm / 0.01 deg gave the same
// tracked precision on the suite's worlds for 3% more instructions a tracked scan.)
bool Refiner::apply_update(const Eigen::Matrix<double, 6, 6>& H, const Eigen::Matrix<double, 6, 1>& g,
                           Eigen::Isometry3d* t, bool* settled) {
  constexpr double kSettledM = 0.01, kSettledRad = 0.05 * kRadPerDeg;
  const Eigen::Matrix<double, 6, 1> dx = H.ldlt().solve(-g);
  if (!dx.allFinite()) return false;
  Eigen::Isometry3d update = Eigen::Isometry3d::Identity();
  const double angle = dx.head<3>().norm();
  *settled = dx.tail<3>().norm() < kSettledM && angle < kSettledRad;
  if (angle > 1e-12) update.linear() = Eigen::AngleAxisd(angle, dx.head<3>() / angle).toRotationMatrix();
  // Turned about the sensor c: x -> R (x - c) + c + v.
  const Eigen::Vector3d c = t->translation();
  update.translation() = c - update.linear() * c + dx.tail<3>();
  *t = update * *t;
  return true;
}

struct Refiner::NearestSearch {
  static constexpr uint32_t kNotLooked = UINT32_MAX;
  const RefineLayerView& map;
  uint32_t* tile_hint;
  float pf[3];            // the query point
  uint64_t part[3][3];    // [axis][d + 1]: the axis' field of the neighbour's key, in place
  int32_t coord[3][3];    // [axis][d + 1]: the cell coordinate the field decodes to (cell_of_key)
  bool regular;           // every axis' neighbours are own - 1 and own + 1, no field at its range's edge
  uint64_t own;           // the key of the point's own cell
  float gap2[3][3];       // [axis][offset + 1]: squared gap to the neighbour cell (0 for the own cell)
  uint32_t* known_begin;  // 27: point ranges of the cells around `own` (kNotLooked until looked up)
  uint32_t* known_end;
  float best;              // squared distance of the nearest so far (the radius first)
  uint32_t nearest_j = 0;  // its cell; 0 while none
  const MapRefinePoint* nearest_point = nullptr;
  float nearest[3] = {0, 0, 0};

  // Cells are floor(x * (1 / cell)) per axis (the map builder's convention), keyed as 3 x 21 bits. The
  // neighbour at offset d along axis k is the cell of pf[k] + d cell, so the 27 neighbour keys are
  // sums of 3 x 3 per-axis parts (9 floors).
  void key_parts(float cell) {
    const float inv = 1.0f / cell;
    regular = true;
    for (int k = 0; k < 3; ++k) {
      int64_t raw[3];
      for (int d = -1; d <= 1; ++d) {
        const int64_t c = static_cast<int64_t>(std::floor((pf[k] + d * cell) * inv)) + (1 << 20);
        raw[d + 1] = c;
        part[k][d + 1] = uint64_t(c & 0x1FFFFF) << (42 - 21 * k);
        coord[k][d + 1] = int32_t(c & 0x1FFFFF) - (1 << 20);
      }
      regular = regular && raw[0] + 1 == raw[1] && raw[2] - 1 == raw[1] && raw[0] > 0 && raw[2] < 0x1FFFFF;
    }
    own = part[0][1] | part[1][1] | part[2][1];
  }
  // Gaps from p to the lower and upper faces of its own cell, shrunk by 1 mm (and a relative 1e-5):
  // every point of the cell below (above) lies at least the lower (upper) gap away along that axis,
  // whatever the float rounding of its cell key and of d2. Squared here.
  void face_gaps(float cell) {
    for (int k = 0; k < 3; ++k) {
      const int64_t c = coord[k][1];
      const double lo = double(c) * cell, hi = double(c + 1) * cell, x = pf[k];
      const double slack = 1e-5 * (std::fabs(lo) + std::fabs(hi)) + 1e-3;
      const float gl = float(std::max(0.0, x - lo - slack)), gh = float(std::max(0.0, hi - x - slack));
      gap2[k][0] = gl * gl;
      gap2[k][1] = 0.0f;
      gap2[k][2] = gh * gh;
    }
  }
  // A named cell farther than the best distance so far (its gap g) cannot hold a point that beats it
  // (the margin covers float rounding): skipped without a lookup.
  bool beyond(float g) const { return g > best * (1.0f + 1e-4f) + 1e-6f; }
  // Cell j at offsets (ox, oy, oz) + 1; `named`: it is the neighbour the offsets name (float rounding
  // could make it another one), so its lookup is remembered per query point. A tie (equal d2) goes to
  // the lower j, which keeps the answer the j-order search's.
  void visit(uint32_t j, int ox, int oy, int oz, bool named) {
    const RefineCell cell{coord[0][ox], coord[1][oy], coord[2][oz]};
    uint32_t begin, end;
    if (named) {  // found before or looked up once now
      if (known_begin[j] == kNotLooked) map.find(cell, &known_begin[j], &known_end[j], tile_hint);
      begin = known_begin[j];
      end = known_end[j];
    } else {
      map.find(cell, &begin, &end, tile_hint);
    }
    if (begin == end) return;  // most of the 27 cells are empty
    // The cell's corner once; each point adds its offset (the same arithmetic as position_in).
    const float step = map.cell / 256.0f;  // RefineLayerView::position_in's
    const float corner[3] = {float(cell.x) * map.cell, float(cell.y) * map.cell, float(cell.z) * map.cell};
    for (uint32_t id = begin; id < end; ++id) {
      const MapRefinePoint& mp = map.points[id];
      const float m[3] = {corner[0] + (float(mp.offset[0]) + 0.5f) * step,
                          corner[1] + (float(mp.offset[1]) + 0.5f) * step,
                          corner[2] + (float(mp.offset[2]) + 0.5f) * step};
      const float ex = m[0] - pf[0], ey = m[1] - pf[1], ez = m[2] - pf[2];
      const float d2 = ex * ex + ey * ey + ez * ez;
      if (d2 < best || (d2 == best && j < nearest_j)) {
        best = d2;
        nearest_j = j;
        nearest_point = &mp;
        for (int k = 0; k < 3; ++k) nearest[k] = m[k];
      }
    }
  }
  // All 27 cells are named. Per axis the own cell, then the nearer neighbour, then the farther: the
  // gaps grow along each loop (float sums are monotone), so the first cell beyond the best ends it.
  void search_named_cells() {
    int order[3][3];
    for (int k = 0; k < 3; ++k) {
      const bool low_first = gap2[k][0] <= gap2[k][2];
      order[k][0] = 1;
      order[k][1] = low_first ? 0 : 2;
      order[k][2] = low_first ? 2 : 0;
    }
    for (int a = 0; a < 3; ++a) {
      const int ox = order[0][a];
      if (beyond(gap2[0][ox])) break;
      for (int b = 0; b < 3; ++b) {
        const int oy = order[1][b];
        const float gxy = gap2[0][ox] + gap2[1][oy];
        if (beyond(gxy)) break;
        for (int c = 0; c < 3; ++c) {
          const int oz = order[2][c];
          if (beyond(gxy + gap2[2][oz])) break;
          visit(uint32_t(ox * 9 + oy * 3 + oz), ox, oy, oz, true);
        }
      }
    }
  }
  // Some neighbours are not the cells their offsets name: the 27 in kVisitOrder, the named ones
  // beyond the best skipped.
  void search_all_cells() {
    for (const uint8_t j : kVisitOrder) {
      const int ox = j / 9, oy = (j / 3) % 3, oz = j % 3;  // offsets + 1
      const uint64_t key = part[0][ox] | part[1][oy] | part[2][oz];
      const bool named = key == own + (uint64_t(int64_t(ox - 1)) << 42) + (uint64_t(int64_t(oy - 1)) << 21) +
                                    uint64_t(int64_t(oz - 1));
      if (named && beyond(gap2[0][ox] + gap2[1][oy] + gap2[2][oz])) continue;
      visit(j, ox, oy, oz, named);
    }
  }
};

// The nearest map point to query point i (at pf) strictly within the radius (r2 squared), or nullptr;
// its position into nearest. The first strictly nearest in the order (dx, dy, dz) = (-1, -1, -1),
// (-1, -1, 0), ... (cell j = 9 (dx + 1) + 3 (dy + 1) + dz + 1, then point order); the cells are visited
// nearer first, so the cells farther than the best so far are skipped sooner.
const MapRefinePoint* Refiner::find_nearest(uint32_t i, const float pf[3], float r2, uint32_t* tile_hint,
                                            float nearest[3]) {
  NearestSearch s{map_, tile_hint, {pf[0], pf[1], pf[2]}, {}, {}, true, 0, {}, nullptr, nullptr, r2};
  s.key_parts(config_.cell);
  s.known_begin = query_begin_ + size_t(i) * 27;  // point ranges of the cells around `own`
  s.known_end = query_end_ + size_t(i) * 27;
  if (query_cell_[i] != s.own) {
    query_cell_[i] = s.own;
    for (int j = 0; j < 27; ++j) s.known_begin[j] = NearestSearch::kNotLooked;
  }
  s.face_gaps(config_.cell);
  if (s.regular) s.search_named_cells();
  else s.search_all_cells();
  for (int k = 0; k < 3; ++k) nearest[k] = s.nearest[k];
  return s.nearest_point;
}

}  // namespace gsf
