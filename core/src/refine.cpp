#include "gsf/detail/refine.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "gsf/semantic_classes.h"

namespace gsf {

size_t Refiner::required_bytes(const RefineConfig& config) { return counted_bytes<Refiner>(config); }

Status Refiner::bind(Arena& arena, const RefineConfig& c) {
  bound_ = false;
  if (c.max_points == 0 || c.max_map_points == 0 || c.iterations == 0 || !(c.cell > 0) || !(c.radius_end > 0) ||
      !(c.radius_start >= c.radius_end) || c.radius_start > c.cell * 1.5f)
    return Status::InvalidArgument;
  config_ = c;
  slot_count_ = BoundedHashMap<uint32_t>::slots_for(c.max_map_points);
  slots_ = arena.allocate<uint32_t>(slot_count_);
  cell_keys_ = arena.allocate<uint64_t>(c.max_map_points);
  begin_ = arena.allocate<uint32_t>(size_t(c.max_map_points) + 1);
  points_ = arena.allocate<float>(size_t(c.max_map_points) * 3);
  normals_ = arena.allocate<float>(size_t(c.max_map_points) * 3);
  query_ = arena.allocate<float>(size_t(c.max_points) * 3);
  query_cell_ = arena.allocate<uint64_t>(c.max_points);
  query_neighbours_ = arena.allocate<uint32_t>(size_t(c.max_points) * 27);
  n_ = 0;
  cells_ = 0;
  if (arena.counting()) return Status::Ok;
  if (!slots_ || !cell_keys_ || !begin_ || !points_ || !normals_ || !query_ || !query_cell_ || !query_neighbours_)
    return Status::BufferTooSmall;
  bound_ = true;
  return Status::Ok;
}

uint64_t Refiner::cell_key(float x, float y, float z) const {
  const float inv = 1.0f / config_.cell;
  const int64_t cx = static_cast<int64_t>(std::floor(x * inv)) + (1 << 20);
  const int64_t cy = static_cast<int64_t>(std::floor(y * inv)) + (1 << 20);
  const int64_t cz = static_cast<int64_t>(std::floor(z * inv)) + (1 << 20);
  return (uint64_t(cx & 0x1FFFFF) << 42) | (uint64_t(cy & 0x1FFFFF) << 21) | uint64_t(cz & 0x1FFFFF);
}

namespace {
// Slot hash of a cell key (x << 42 | y << 21 | z): mix64 of the column (x, y) plus z, so the cells of
// one column sit in neighbouring slots and the 3 z-neighbours a search visits share a cache line.
inline uint32_t cell_hash(uint64_t key) {
  return static_cast<uint32_t>(mix64(key >> 21)) + static_cast<uint32_t>(key & 0x1FFFFFu);
}
}  // namespace

uint32_t Refiner::find_cell(uint64_t key) const {
  const uint32_t mask = slot_count_ - 1;
  for (uint32_t i = cell_hash(key) & mask, n = 0; n < slot_count_; ++n, i = (i + 1) & mask) {
    const uint32_t s = slots_[i];
    if (s == 0) return UINT32_MAX;
    if (cell_keys_[s - 1] == key) return s - 1;
  }
  return UINT32_MAX;
}

Status Refiner::set_map(const float* pts, uint32_t n) {
  if (!bound_) return Status::NotInitialized;
  if (n > config_.max_map_points) return Status::InvalidArgument;
  n_ = 0;
  cells_ = 0;
  for (uint32_t i = 0; i < slot_count_; ++i) slots_[i] = 0;
  // Counting sort of the points by cell: cells in order of first appearance, points in map order
  // within a cell (the order the nearest-neighbour search visits them in; ties go to the first).
  // begin_ first counts per cell, then becomes the exclusive prefix sum.
  const uint32_t mask = slot_count_ - 1;
  uint32_t* cell_of = reinterpret_cast<uint32_t*>(normals_);  // scratch until the normals are computed
  for (uint32_t i = 0; i < n; ++i) {
    const uint64_t key = cell_key(pts[4 * i], pts[4 * i + 1], pts[4 * i + 2]);
    uint32_t c = find_cell(key);
    if (c == UINT32_MAX) {
      if (cells_ >= config_.max_map_points) return Status::CapacityExceeded;
      uint32_t j = cell_hash(key) & mask;
      while (slots_[j] != 0) j = (j + 1) & mask;  // load <= 0.5: an empty slot exists
      c = cells_++;
      slots_[j] = c + 1;
      cell_keys_[c] = key;
      begin_[c] = 0;
    }
    ++begin_[c];  // count for now
    cell_of[i] = c;
  }
  uint32_t run = 0;
  for (uint32_t c = 0; c < cells_; ++c) {
    const uint32_t count = begin_[c];
    begin_[c] = run;
    run += count;
  }
  begin_[cells_] = run;
  // Place each point at its cell's next free position: begin_[c] is advanced while filling, then
  // shifted back by one cell.
  for (uint32_t i = 0; i < n; ++i) {
    const uint32_t at = begin_[cell_of[i]]++;
    for (int k = 0; k < 3; ++k) points_[3 * at + k] = pts[4 * i + k];
  }
  for (uint32_t c = cells_; c > 0; --c) begin_[c] = begin_[c - 1];
  begin_[0] = 0;
  n_ = n;
  // Normals: PCA of the points in the 27 surrounding cells (smallest eigenvector), if planar enough.
  for (uint32_t i = 0; i < n; ++i) {
    const float* p = points_ + 3 * i;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    uint32_t m = 0;
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const uint32_t c =
              find_cell(cell_key(p[0] + dx * config_.cell, p[1] + dy * config_.cell, p[2] + dz * config_.cell));
          if (c == UINT32_MAX) continue;
          for (uint32_t k = begin_[c]; k < begin_[c + 1]; ++k) {
            const float* q = points_ + 3 * k;
            const Eigen::Vector3d v(q[0], q[1], q[2]);
            mean += v;
            cov += v * v.transpose();
            ++m;
          }
        }
    normals_[3 * i] = normals_[3 * i + 1] = normals_[3 * i + 2] = 0.0f;
    if (m < 5) continue;
    mean /= m;
    cov = cov / m - mean * mean.transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
    const Eigen::Vector3d ev = eig.eigenvalues();
    if (!(ev(0) < 0.3 * ev(1))) continue;  // not planar: no normal, not used
    const Eigen::Vector3d nrm = eig.eigenvectors().col(0);
    for (int k = 0; k < 3; ++k) normals_[3 * i + k] = static_cast<float>(nrm[k]);
  }
  return Status::Ok;
}

Status Refiner::refine(const VoxelLayer& layer, const Eigen::Isometry3d& initial, Eigen::Isometry3d* out,
                       RefineStats* st_out) {
  RefineStats st;
  *out = initial;
  if (!bound_) return Status::NotInitialized;
  if (n_ == 0) return Status::Unsupported;
  // Query points: long-term voxels, deterministic stride subsample.
  uint32_t eligible = 0;
  for (uint32_t i = 0; i < layer.size(); ++i) eligible += long_term(layer.voxel(i).label);
  const uint32_t stride = eligible > config_.max_points ? (eligible + config_.max_points - 1) / config_.max_points : 1;
  uint32_t q = 0, seen = 0;
  for (uint32_t i = 0; i < layer.size() && q < config_.max_points; ++i) {
    const Voxel& v = layer.voxel(i);
    if (!long_term(v.label)) continue;
    if (seen++ % stride) continue;
    for (int k = 0; k < 3; ++k) query_[3 * q + k] = v.centroid[k];
    ++q;
  }
  st.query_points = q;
  constexpr uint32_t kNotLooked = UINT32_MAX - 1;
  for (uint32_t i = 0; i < q; ++i) query_cell_[i] = UINT64_MAX;
  Eigen::Isometry3d t = initial;
  for (uint32_t it = 0; it < config_.iterations; ++it) {
    const float frac = config_.iterations > 1 ? float(it) / float(config_.iterations - 1) : 1.0f;
    const float radius = config_.radius_start + (config_.radius_end - config_.radius_start) * frac;
    const float r2 = radius * radius;
    Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
    Eigen::Matrix<double, 6, 1> g = Eigen::Matrix<double, 6, 1>::Zero();
    uint32_t inl = 0;
    double err = 0;
    for (uint32_t i = 0; i < q; ++i) {
      const Eigen::Vector3d p = t * Eigen::Vector3d(query_[3 * i], query_[3 * i + 1], query_[3 * i + 2]);
      float best = r2;
      int32_t nn = -1;
      const float pf[3] = {float(p.x()), float(p.y()), float(p.z())};
      // Gaps from p to the lower and upper faces of its own cell, shrunk by 1 mm (and a relative 1e-5):
      // every point of the cell below (above) lies at least the lower (upper) gap away along that axis,
      // whatever the float rounding of its cell key and of d2.
      const uint64_t own = cell_key(pf[0], pf[1], pf[2]);
      uint32_t* known = query_neighbours_ + size_t(i) * 27;  // cells around `own`, by offset
      if (query_cell_[i] != own) {
        query_cell_[i] = own;
        for (int j = 0; j < 27; ++j) known[j] = kNotLooked;
      }
      float gap[3][3];  // [axis][offset + 1]: 0 for the own cell
      for (int k = 0; k < 3; ++k) {
        const int64_t c = int64_t((own >> (42 - 21 * k)) & 0x1FFFFF) - (1 << 20);
        const double lo = double(c) * config_.cell, hi = double(c + 1) * config_.cell, x = pf[k];
        const double slack = 1e-5 * (std::fabs(lo) + std::fabs(hi)) + 1e-3;
        gap[k][0] = float(std::max(0.0, x - lo - slack));
        gap[k][1] = 0.0f;
        gap[k][2] = float(std::max(0.0, hi - x - slack));
      }
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dz = -1; dz <= 1; ++dz) {
            const uint64_t key =
                cell_key(pf[0] + dx * config_.cell, pf[1] + dy * config_.cell, pf[2] + dz * config_.cell);
            // A cell farther than the best distance so far cannot hold a point that beats it (the search
            // keeps the first strictly nearer point): skip its lookup. Only when the visited cell is the
            // neighbour the offsets name (float rounding could make it another one).
            const float g =
                gap[0][dx + 1] * gap[0][dx + 1] + gap[1][dy + 1] * gap[1][dy + 1] + gap[2][dz + 1] * gap[2][dz + 1];
            const bool named =
                key == own + (uint64_t(int64_t(dx)) << 42) + (uint64_t(int64_t(dy)) << 21) + uint64_t(int64_t(dz));
            if (named && g > best * (1.0f + 1e-4f) + 1e-6f) continue;
            uint32_t c;
            if (named) {  // the cell at this offset from `own`: found before or looked up once now
              uint32_t& slot = known[(dx + 1) * 9 + (dy + 1) * 3 + (dz + 1)];
              if (slot == kNotLooked) slot = find_cell(key);
              c = slot;
            } else {
              c = find_cell(key);
            }
            if (c == UINT32_MAX) continue;
            for (uint32_t id = begin_[c]; id < begin_[c + 1]; ++id) {
              const float ex = points_[3 * id] - float(p.x()), ey = points_[3 * id + 1] - float(p.y()),
                          ez = points_[3 * id + 2] - float(p.z());
              const float d2 = ex * ex + ey * ey + ez * ez;
              if (d2 < best) {
                best = d2;
                nn = static_cast<int32_t>(id);
              }
            }
          }
      if (nn < 0) continue;
      const Eigen::Vector3d nrm(normals_[3 * nn], normals_[3 * nn + 1], normals_[3 * nn + 2]);
      if (nrm.squaredNorm() < 0.5) continue;
      const Eigen::Vector3d m(points_[3 * nn], points_[3 * nn + 1], points_[3 * nn + 2]);
      const double r = nrm.dot(p - m);  // point-to-plane residual
      Eigen::Matrix<double, 6, 1> J;
      J.head<3>() = p.cross(nrm);  // d r / d (small rotation)
      J.tail<3>() = nrm;           // d r / d translation
      H += J * J.transpose();
      g += J * r;
      err += r * r;
      ++inl;
    }
    st.iterations = it + 1;
    st.inliers = inl;
    st.rmse = inl ? std::sqrt(err / inl) : 0;
    if (inl < 6) break;
    const Eigen::Matrix<double, 6, 1> dx = H.ldlt().solve(-g);
    if (!dx.allFinite()) break;
    Eigen::Isometry3d step = Eigen::Isometry3d::Identity();
    const double angle = dx.head<3>().norm();
    if (angle > 1e-12) step.linear() = Eigen::AngleAxisd(angle, dx.head<3>() / angle).toRotationMatrix();
    step.translation() = dx.tail<3>();
    t = step * t;
  }
  st.accepted =
      st.inliers >= config_.min_inliers && (t.translation() - initial.translation()).norm() <= config_.max_correction;
  if (st.accepted) *out = t;
  if (st_out) *st_out = st;
  return Status::Ok;
}

}  // namespace gsf
