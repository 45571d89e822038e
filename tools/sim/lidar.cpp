#include "sim/lidar.h"

#include <algorithm>
#include <cmath>

#include "gsf/detail/rng.h"

namespace gsf::sim {
namespace {

void prim_xy_bounds(const Primitive& p, float* lo, float* hi) {
  switch (p.shape) {
    case Shape::Box:
      lo[0] = p.a[0];
      lo[1] = p.a[1];
      hi[0] = p.b[0];
      hi[1] = p.b[1];
      break;
    case Shape::Cylinder:
    case Shape::Sphere:
      lo[0] = p.a[0] - p.b[0];
      lo[1] = p.a[1] - p.b[0];
      hi[0] = p.a[0] + p.b[0];
      hi[1] = p.a[1] + p.b[0];
      break;
  }
}

// Ray-primitive intersection: smallest t in (eps, best) or -1.
float intersect(const Primitive& p, const Eigen::Vector3f& o, const Eigen::Vector3f& d) {
  const float eps = 1e-4f;
  switch (p.shape) {
    case Shape::Box: {
      float t0 = -1e30f, t1 = 1e30f;
      for (int k = 0; k < 3; ++k) {
        if (std::fabs(d[k]) < 1e-12f) {
          if (o[k] < p.a[k] || o[k] > p.b[k]) return -1.0f;
          continue;
        }
        float ta = (p.a[k] - o[k]) / d[k], tb = (p.b[k] - o[k]) / d[k];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
      }
      if (t0 > t1 || t1 < eps) return -1.0f;
      return t0 > eps ? t0 : -1.0f;  // sensor inside a box: no return
    }
    case Shape::Cylinder: {
      const float r = p.b[0], h = p.b[1];
      const float ox = o.x() - p.a[0], oy = o.y() - p.a[1];
      const float A = d.x() * d.x() + d.y() * d.y();
      if (A < 1e-12f) return -1.0f;
      const float Bq = 2 * (ox * d.x() + oy * d.y()), Cq = ox * ox + oy * oy - r * r;
      const float disc = Bq * Bq - 4 * A * Cq;
      if (disc < 0) return -1.0f;
      const float t = (-Bq - std::sqrt(disc)) / (2 * A);
      if (t < eps) return -1.0f;
      const float z = o.z() + t * d.z();
      return (z >= p.a[2] && z <= p.a[2] + h) ? t : -1.0f;
    }
    case Shape::Sphere: {
      const Eigen::Vector3f oc = o - Eigen::Vector3f(p.a[0], p.a[1], p.a[2]);
      const float b = oc.dot(d), c = oc.squaredNorm() - p.b[0] * p.b[0];
      const float disc = b * b - c;
      if (disc < 0) return -1.0f;
      const float t = -b - std::sqrt(disc);
      return t > eps ? t : -1.0f;
    }
  }
  return -1.0f;
}

}  // namespace

Raycaster::Raycaster(const World& world, float cell) : world_(world), cell_(cell) {
  ox_ = world.min_xy[0];
  oy_ = world.min_xy[1];
  nx_ = std::max(1, static_cast<int>(std::ceil((world.max_xy[0] - ox_) / cell)));
  ny_ = std::max(1, static_cast<int>(std::ceil((world.max_xy[1] - oy_) / cell)));
  std::vector<uint32_t> counts(size_t(nx_) * ny_ + 1, 0);
  auto for_cells = [&](const Primitive& p, auto&& f) {
    float lo[2] = {0, 0}, hi[2] = {0, 0};
    prim_xy_bounds(p, lo, hi);
    const int x0 = std::clamp(static_cast<int>(std::floor((lo[0] - ox_) / cell)), 0, nx_ - 1);
    const int x1 = std::clamp(static_cast<int>(std::floor((hi[0] - ox_) / cell)), 0, nx_ - 1);
    const int y0 = std::clamp(static_cast<int>(std::floor((lo[1] - oy_) / cell)), 0, ny_ - 1);
    const int y1 = std::clamp(static_cast<int>(std::floor((hi[1] - oy_) / cell)), 0, ny_ - 1);
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) f(size_t(y) * nx_ + x);
  };
  for (const auto& p : world.prims) for_cells(p, [&](size_t c) { counts[c]++; });
  cell_start_.assign(counts.size() + 1, 0);
  for (size_t c = 0; c < counts.size(); ++c) cell_start_[c + 1] = cell_start_[c] + counts[c];
  cell_prims_.assign(cell_start_.back(), 0);
  std::vector<uint32_t> fill(cell_start_.begin(), cell_start_.end() - 1);
  for (uint32_t i = 0; i < world.prims.size(); ++i)
    for_cells(world.prims[i], [&](size_t c) { cell_prims_[fill[c]++] = i; });
}

float Raycaster::cast(const Eigen::Vector3f& o, const Eigen::Vector3f& d, float max_t, uint32_t* label) const {
  float best = max_t;
  int best_prim = -1;
  bool ground = false;
  if (d.z() < -1e-6f) {
    const float tg = -o.z() / d.z();
    if (tg > 0 && tg < best) {
      best = tg;
      ground = true;
    }
  }
  // 2-D DDA over cells, stopping once the next cell starts beyond the best hit.
  const float dxy = std::sqrt(d.x() * d.x() + d.y() * d.y());
  int cx = static_cast<int>(std::floor((o.x() - ox_) / cell_));
  int cy = static_cast<int>(std::floor((o.y() - oy_) / cell_));
  const int sx = d.x() > 0 ? 1 : -1, sy = d.y() > 0 ? 1 : -1;
  const float inv_x = std::fabs(d.x()) > 1e-9f ? 1.0f / d.x() : 1e30f;
  const float inv_y = std::fabs(d.y()) > 1e-9f ? 1.0f / d.y() : 1e30f;
  float tmx = std::fabs(d.x()) > 1e-9f ? ((ox_ + (cx + (sx > 0)) * cell_) - o.x()) * inv_x : 1e30f;
  float tmy = std::fabs(d.y()) > 1e-9f ? ((oy_ + (cy + (sy > 0)) * cell_) - o.y()) * inv_y : 1e30f;
  const float tdx = std::fabs(cell_ * inv_x), tdy = std::fabs(cell_ * inv_y);
  float t_enter = 0.0f;
  for (int steps = 0; steps < 4 * (nx_ + ny_) && t_enter < best; ++steps) {
    if (cx >= 0 && cy >= 0 && cx < nx_ && cy < ny_) {
      const size_t c = size_t(cy) * nx_ + cx;
      for (uint32_t k = cell_start_[c]; k < cell_start_[c + 1]; ++k) {
        const float t = intersect(world_.prims[cell_prims_[k]], o, d);
        if (t > 0 && t < best) {
          best = t;
          best_prim = static_cast<int>(cell_prims_[k]);
          ground = false;
        }
      }
    }
    if (dxy < 1e-9f) break;
    if (tmx < tmy) {
      t_enter = tmx;
      tmx += tdx;
      cx += sx;
    } else {
      t_enter = tmy;
      tmy += tdy;
      cy += sy;
    }
  }
  if (best_prim >= 0) {
    const Primitive& p = world_.prims[best_prim];
    *label = uint32_t(p.semantic) | (p.instance << 16);
    return best;
  }
  if (ground) {
    const Eigen::Vector3f hit = o + best * d;
    *label = world_.ground_class(hit.x(), hit.y());
    return best;
  }
  return -1.0f;
}

void Raycaster::scan(const Eigen::Isometry3d& pose, const LidarParams& L, uint64_t seed, SimScan* out) const {
  out->xyzi.clear();
  out->labels.clear();
  gsf::Rng rng(seed);
  const Eigen::Matrix3f R = pose.rotation().cast<float>();
  const Eigen::Vector3f o = pose.translation().cast<float>();
  const int cols = static_cast<int>(std::lround(360.0f / L.azimuth_step_deg));
  const float deg = 3.14159265358979f / 180.0f;
  for (int c = 0; c < cols; ++c) {
    const float az = c * L.azimuth_step_deg * deg;
    for (int b = 0; b < L.beams; ++b) {
      const float el =
          (L.elevation_min_deg + (L.elevation_max_deg - L.elevation_min_deg) * b / std::max(1, L.beams - 1)) * deg;
      const Eigen::Vector3f ds(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el));
      uint32_t label = 0;
      float t = cast(o, R * ds, L.max_range, &label);
      // Noise draws happen for every ray so the stream does not depend on what was hit.
      const float u1 = std::max(rng.uniform01(), 1e-7f), u2 = rng.uniform01(), drop = rng.uniform01();
      if (t < L.min_range || drop < L.dropout) continue;
      t += L.range_noise * std::sqrt(-2.0f * std::log(u1)) * std::cos(6.2831853f * u2);
      const Eigen::Vector3f p = t * ds;
      const uint16_t sem = label & 0xFFFF;
      const float intensity = sem == 40 ? 0.15f : sem == 81 ? 0.9f : sem == 70 ? 0.35f : 0.5f;
      out->xyzi.insert(out->xyzi.end(), {p.x(), p.y(), p.z(), intensity});
      out->labels.push_back(label);
    }
  }
}

}  // namespace gsf::sim
