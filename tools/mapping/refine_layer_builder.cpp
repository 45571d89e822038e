#include "mapping/refine_layer_builder.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>

namespace gsf::mapping {
namespace {

struct Placed {
  uint32_t key;    // tile key
  int32_t cz;      // z cell
  uint16_t local;  // y << 4 | x within the tile (z added once the tile's base is known)
  uint8_t offset[3];
  uint32_t input;  // input order, the tie-break inside a cell
};

// Point i of the layer at map-local xyz; false for a non-finite point or one beyond the tile key range.
bool place(const float* xyz, float inv, uint32_t i, Placed* p) {
  int32_t c[3];
  for (int k = 0; k < 3; ++k) {
    const float s = xyz[k] * inv;
    if (!std::isfinite(s) || std::fabs(s) >= float(1 << 19)) return false;
    const float f = std::floor(s);
    c[k] = static_cast<int32_t>(f);
    p->offset[k] = quantize_cell_offset(s - f);
  }
  int32_t tx, ty;
  if (!refine_tile_of(RefineCell{c[0], c[1], c[2]}, &tx, &ty, &p->key)) return false;
  const int32_t t = static_cast<int32_t>(kRefineTileCells);
  p->cz = c[2];
  p->local = static_cast<uint16_t>((uint32_t(c[1] - ty * t) << 4) | uint32_t(c[0] - tx * t));
  p->input = i;
  return true;
}

// Appends the placed points, sorted (tile, z cell, cell, input order), to the layer's tiles and points;
// *placed is emptied. The tiles must come after every tile already in the layer.
Status append_placed(std::vector<Placed>* placed, std::vector<MapRefineTile>* tiles,
                     std::vector<MapRefinePoint>* points) {
  std::sort(placed->begin(), placed->end(), [](const Placed& a, const Placed& b) {
    if (a.key != b.key) return a.key < b.key;
    if (a.cz != b.cz) return a.cz < b.cz;
    if (a.local != b.local) return a.local < b.local;
    return a.input < b.input;
  });
  const std::vector<Placed>& p = *placed;
  const uint32_t n = static_cast<uint32_t>(p.size()), base = static_cast<uint32_t>(points->size());
  points->resize(size_t(base) + n);
  // Tiles: z base = the lowest z cell of the tile (points are sorted by z within a tile).
  for (uint32_t i = 0; i < n;) {
    uint32_t j = i;
    while (j < n && p[j].key == p[i].key) ++j;
    const int32_t z_base = p[i].cz;
    if (p[j - 1].cz - z_base >= kRefineTileZCells) return Status::InvalidInput;
    tiles->push_back(MapRefineTile{p[i].key, base + i, z_base});
    for (uint32_t k = i; k < j; ++k) {
      MapRefinePoint& out = (*points)[base + k];
      out.cell = static_cast<uint16_t>((uint32_t(p[k].cz - z_base) << 8) | p[k].local);
      for (int a = 0; a < 3; ++a) {
        out.offset[a] = p[k].offset[a];
        out.normal[a] = 0;
      }
    }
    i = j;
  }
  std::vector<Placed>().swap(*placed);
  return Status::Ok;
}

// Normals: PCA of the quantised points in the 27 cells around each point's cell (smallest eigenvector)
// when the neighbourhood is planar enough; otherwise none (zero).
void add_normals(float cell, const std::vector<MapRefineTile>& tiles_in, std::vector<MapRefinePoint>* points) {
  const std::vector<MapRefineTile>* tiles = &tiles_in;
  const uint32_t n = static_cast<uint32_t>(points->size());
  RefineLayerView view;
  view.cell = cell;
  view.tile_count = static_cast<uint32_t>(tiles->size());
  view.point_count = n;
  view.tiles = tiles->data();
  view.points = points->data();
  uint32_t hint = 0;
  for (uint32_t t = 0; t < view.tile_count; ++t) {
    const uint32_t last = t + 1 < view.tile_count ? (*tiles)[t + 1].first_point : n;
    const int32_t tn = static_cast<int32_t>(kRefineTileCells);
    const uint32_t key = (*tiles)[t].key;
    for (uint32_t i = (*tiles)[t].first_point; i < last; ++i) {
      const MapRefinePoint& p = (*points)[i];
      const RefineCell own{(int32_t(key >> 16) - 32768) * tn + int32_t(p.cell & 0xF),
                           (int32_t(key & 0xFFFF) - 32768) * tn + int32_t((p.cell >> 4) & 0xF),
                           (*tiles)[t].z_base + int32_t(p.cell >> 8)};
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
      uint32_t m = 0;
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dz = -1; dz <= 1; ++dz) {
            const RefineCell c{own.x + dx, own.y + dy, own.z + dz};
            uint32_t b, e;
            view.find(c, &b, &e, &hint);
            for (uint32_t k = b; k < e; ++k) {
              float q[3];
              view.position_in(c, (*points)[k], q);
              const Eigen::Vector3d v(q[0], q[1], q[2]);
              mean += v;
              cov += v * v.transpose();
              ++m;
            }
          }
      if (m < 5) continue;
      mean /= m;
      cov = cov / m - mean * mean.transpose();
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
      const Eigen::Vector3d ev = eig.eigenvalues();
      if (!(ev(0) < 0.3 * ev(1))) continue;  // not planar: no normal, not used
      const Eigen::Vector3d nrm = eig.eigenvectors().col(0);
      // In place: the neighbourhoods read positions only (cell and offset), never normals.
      for (int k = 0; k < 3; ++k) (*points)[i].normal[k] = quantize_normal_component(float(nrm[k]));
    }
  }
}

// The layer from the placed points (consumed: freed before the normals, 20 bytes a point).
Status build_from_placed(std::vector<Placed>* placed, float cell, std::vector<MapRefineTile>* tiles,
                         std::vector<MapRefinePoint>* points) {
  const Status s = append_placed(placed, tiles, points);
  if (s == Status::Ok) add_normals(cell, *tiles, points);
  return s;
}

// Whether the chunks' points are all placeable and their refinement tile columns never decrease in input
// order (the builder's points come in cell-key order, x-major: so they do when the grid's cell is the
// builder's refine_voxel); *n: their count.
Status scan_chunks(const std::vector<std::vector<float>>& chunks, float inv, size_t* n, bool* monotone) {
  *n = 0;
  *monotone = true;
  uint32_t column = 0;
  Placed p;
  for (const std::vector<float>& c : chunks)
    for (size_t j = 0; j + 3 <= c.size(); j += 3, ++*n) {
      if (!place(c.data() + j, inv, 0, &p)) return Status::InvalidInput;
      const uint32_t tx = p.key >> 16;
      if (*n > 0 && tx < column) *monotone = false;
      column = tx;
    }
  return Status::Ok;
}

}  // namespace

Status build_refine_layer(const float* xyz, uint32_t n, float cell, std::vector<MapRefineTile>* tiles,
                          std::vector<MapRefinePoint>* points) {
  tiles->clear();
  points->clear();
  if (!(cell > 0.0f) || !std::isfinite(cell)) return Status::InvalidArgument;
  const float inv = 1.0f / cell;  // the refiner's cell of a point: floor(x * inv) (Refiner::refine)
  std::vector<Placed> placed(n);
  for (uint32_t i = 0; i < n; ++i)
    if (!place(xyz + 3 * size_t(i), inv, i, &placed[i])) return Status::InvalidInput;
  return build_from_placed(&placed, cell, tiles, points);
}

Status build_refine_layer(std::vector<std::vector<float>>* chunks, float cell, std::vector<MapRefineTile>* tiles,
                          std::vector<MapRefinePoint>* points) {
  tiles->clear();
  points->clear();
  if (!(cell > 0.0f) || !std::isfinite(cell)) return Status::InvalidArgument;
  const float inv = 1.0f / cell;
  size_t n = 0;
  bool monotone = true;
  Status s = scan_chunks(*chunks, inv, &n, &monotone);
  if (s != Status::Ok) return s;
  if (n > UINT32_MAX) return Status::InvalidInput;
  // Tile column by tile column when the columns come in order (a column's tiles sort alone and follow
  // the previous column's): only one column is placed at a time, 20 bytes a point, while the chunks
  // are freed as they are read and the layer grows. Else every point placed at once.
  std::vector<Placed> placed;
  if (!monotone) placed.reserve(n);
  points->reserve(n);
  uint32_t i = 0;
  for (std::vector<float>& c : *chunks) {
    for (size_t j = 0; j + 3 <= c.size(); j += 3, ++i) {
      Placed p;
      place(c.data() + j, inv, i, &p);
      if (monotone && !placed.empty() && (p.key >> 16) != (placed.back().key >> 16)) {
        s = append_placed(&placed, tiles, points);
        if (s != Status::Ok) return s;
      }
      placed.push_back(p);
    }
    std::vector<float>().swap(c);
  }
  chunks->clear();
  s = append_placed(&placed, tiles, points);
  if (s == Status::Ok) add_normals(cell, *tiles, points);
  return s;
}

}  // namespace gsf::mapping
