#include "gsf/detail/instance_clustering.h"

#include <algorithm>
#include <cmath>

namespace gsf {

size_t InstanceClustering::required_bytes(const ClusterConfig& config, uint32_t max_voxels) {
  return counted_bytes<InstanceClustering>(config, max_voxels);
}

Status InstanceClustering::bind(Arena& arena, const ClusterConfig& config, uint32_t max_voxels) {
  bound_ = false;
  if (config.max_instances == 0 || max_voxels == 0) return Status::InvalidArgument;
  for (int c = 0; c < kNumClasses; ++c)
    if (!(config.tolerance[c] > 0.0f && config.tolerance[c] < 10.0f) || !(config.max_extent[c] > 0.0f) ||
        !(config.vertical_tolerance[c] >= 0.0f && config.vertical_tolerance[c] < 10.0f))
      return Status::InvalidArgument;
  config_ = config;
  max_voxels_ = max_voxels;
  max_components_ = max_voxels;
  instances_ = arena.allocate<Instance>(config.max_instances);
  queue_ = arena.allocate<uint32_t>(max_voxels);
  voxel_instance_ = arena.allocate<uint32_t>(max_voxels);
  component_to_instance_ = arena.allocate<uint32_t>(max_components_);
  count_ = 0;
  if (arena.counting()) return Status::Ok;
  if (!instances_ || !queue_ || !voxel_instance_ || !component_to_instance_) return Status::BufferTooSmall;
  bound_ = true;
  return Status::Ok;
}

struct InstanceClustering::Reach {
  uint8_t label;
  float tol, tol2;  // connection distance (across, or in 3-D), and its square
  float vtol;       // vertical tolerance
  bool cylinder;    // vtol above tol: a cylinder (tol across, vtol up and down) instead of the sphere
  int32_t reach;    // cells within tol
  int32_t reach_z;  // cells within the vertical reach
};

Status InstanceClustering::build(const VoxelLayer& layer, ClusterStats* stats_out) {
  ClusterStats stats;
  if (stats_out) *stats_out = stats;  // early returns report zeros
  count_ = 0;
  if (!bound_) return Status::NotInitialized;
  const uint32_t n = layer.size();
  if (n > max_voxels_) return Status::InvalidArgument;
  const Voxel* vox = layer.voxels();
  for (uint32_t i = 0; i < n; ++i) voxel_instance_[i] = UINT32_MAX;
  uint32_t components = 0;
  for (uint32_t seed = 0; seed < n; ++seed) {
    const uint8_t label = vox[seed].label;
    if (!(config_.instance_classes & class_bit(label)) || voxel_instance_[seed] != UINT32_MAX) continue;
    const uint32_t comp = components++;
    const uint32_t size = grow_component(layer, seed, comp);
    component_to_instance_[comp] = UINT32_MAX;
    const Instance in = describe_component(layer, seed, size);
    ++stats.components;
    if (size < config_.min_voxels[label]) {
      ++stats.rejected_small;
      continue;
    }
    if (std::sqrt(in.extent[0] * in.extent[0] + in.extent[1] * in.extent[1]) > config_.max_extent[label]) {
      ++stats.rejected_extent;
      continue;
    }
    keep_largest(in, comp, &stats);
  }
  order_by_discovery(n);
  stats.instances = count_;
  if (stats_out) *stats_out = stats;
  return stats.dropped_capacity ? Status::CapacityExceeded : Status::Ok;
}

// The seed's component: breadth-first over voxels of its label within the label's tolerance, marked
// `comp` in voxel_instance_, into queue_[0, returned size).
uint32_t InstanceClustering::grow_component(const VoxelLayer& layer, uint32_t seed, uint32_t comp) {
  const float vs = layer.config().voxel_size;
  Reach r;
  r.label = layer.voxels()[seed].label;
  r.tol = config_.tolerance[r.label];
  r.tol2 = r.tol * r.tol;
  r.reach = static_cast<int32_t>(std::ceil(r.tol / vs));
  r.vtol = config_.vertical_tolerance[r.label];
  r.cylinder = r.vtol > r.tol;
  r.reach_z = r.cylinder ? static_cast<int32_t>(std::ceil(r.vtol / vs)) : r.reach;
  uint32_t head = 0, tail = 0;
  queue_[tail++] = seed;
  voxel_instance_[seed] = comp;
  while (head < tail) add_neighbours(layer, queue_[head++], comp, r, &tail);
  return tail;
}

// Voxel v's unvisited neighbours of the component's label within reach join it (at queue_[*tail]).
void InstanceClustering::add_neighbours(const VoxelLayer& layer, uint32_t v, uint32_t comp, const Reach& r,
                                        uint32_t* tail) {
  const Voxel* vox = layer.voxels();
  const float vs = layer.config().voxel_size;
  int32_t c[3];
  const float* p = vox[v].centroid;
  if (!layer.cell_of(p, c)) return;
  // Only the cells a centroid within the tolerance can lie in: [p - tol, p + tol] per axis (a 1 mm
  // margin for the rounding of a centroid at its cell's edge), inside the fixed reach, and of those
  // across only the ones whose nearest point is within tol. A centroid lies in its voxel's cell, so
  // the skipped cells hold no neighbour and the components are the same: 4 x 4 (less the corners)
  // x 4 lookups a voxel instead of 5 x 5 x 5 at the defaults.
  const float margin = 1e-3f;
  auto lo = [&](int axis, float rad, int32_t rc) {
    const int32_t k = static_cast<int32_t>(std::floor((p[axis] - rad - margin) / vs)) - c[axis];
    return k > -rc ? k : -rc;
  };
  auto hi = [&](int axis, float rad, int32_t rc) {
    const int32_t k = static_cast<int32_t>(std::floor((p[axis] + rad + margin) / vs)) - c[axis];
    return k < rc ? k : rc;
  };
  const float tol = r.tol, vtol = r.vtol;
  const float rz = r.cylinder ? vtol : tol;
  const int32_t x0 = lo(0, tol, r.reach), x1 = hi(0, tol, r.reach), y0 = lo(1, tol, r.reach), y1 = hi(1, tol, r.reach);
  const int32_t z0 = lo(2, rz, r.reach_z), z1 = hi(2, rz, r.reach_z);
  const float reach2 = (tol + margin) * (tol + margin);
  for (int32_t dx = x0; dx <= x1; ++dx)
    for (int32_t dy = y0; dy <= y1; ++dy) {
      // Distance from p to the cell (c + (dx, dy)) across: beyond tol, none of its voxels can connect.
      const float cx0 = float(c[0] + dx) * vs, cy0 = float(c[1] + dy) * vs;
      const float gx = p[0] < cx0 ? cx0 - p[0] : (p[0] > cx0 + vs ? p[0] - cx0 - vs : 0.0f);
      const float gy = p[1] < cy0 ? cy0 - p[1] : (p[1] > cy0 + vs ? p[1] - cy0 - vs : 0.0f);
      if (gx * gx + gy * gy > reach2) continue;
      for (int32_t dz = z0; dz <= z1; ++dz) {
        const uint32_t u = layer.find_cell(c[0] + dx, c[1] + dy, c[2] + dz);
        if (u == UINT32_MAX || voxel_instance_[u] != UINT32_MAX || vox[u].label != r.label) continue;
        const float ex = vox[u].centroid[0] - p[0];
        const float ey = vox[u].centroid[1] - p[1];
        const float ez = vox[u].centroid[2] - p[2];
        if (r.cylinder ? (ex * ex + ey * ey > r.tol2 || std::fabs(ez) > vtol) : (ex * ex + ey * ey + ez * ez > r.tol2))
          continue;
        voxel_instance_[u] = comp;
        queue_[(*tail)++] = u;  // each voxel enters once: tail <= n
      }
    }
}

// The component in queue_[0, size) as an Instance: point-weighted centroid, centroid box + one voxel.
Instance InstanceClustering::describe_component(const VoxelLayer& layer, uint32_t seed, uint32_t size) const {
  const Voxel* vox = layer.voxels();
  const float vs = layer.config().voxel_size;
  const uint8_t label = vox[seed].label;
  Instance in{};
  double sum[3] = {0, 0, 0};
  float lo[3] = {vox[seed].centroid[0], vox[seed].centroid[1], vox[seed].centroid[2]};
  float hi[3] = {lo[0], lo[1], lo[2]};
  uint32_t points = 0;
  for (uint32_t q = 0; q < size; ++q) {
    const Voxel& v = vox[queue_[q]];
    for (int k = 0; k < 3; ++k) {
      sum[k] += double(v.centroid[k]) * v.count;
      lo[k] = std::min(lo[k], v.centroid[k]);
      hi[k] = std::max(hi[k], v.centroid[k]);
    }
    points += v.count;
  }
  for (int k = 0; k < 3; ++k) {
    in.centroid[k] = static_cast<float>(sum[k] / points);
    in.extent[k] = hi[k] - lo[k] + vs;
  }
  in.voxel_count = size;
  in.point_count = points;
  in.first_voxel = seed;
  in.label = label;
  in.stability = classes_ ? classes_->stability(label) : stability_weight(label);
  return in;
}

// Keep the largest max_instances; on overflow evict the smallest (latest discovered among equals).
void InstanceClustering::keep_largest(const Instance& in, uint32_t comp, ClusterStats* stats) {
  uint32_t slot = count_;
  if (count_ == config_.max_instances) {
    uint32_t worst = 0;
    for (uint32_t k = 1; k < count_; ++k) {
      const Instance& a = instances_[k];
      const Instance& b = instances_[worst];
      if (a.point_count < b.point_count || (a.point_count == b.point_count && a.first_voxel > b.first_voxel)) worst = k;
    }
    ++stats->dropped_capacity;
    if (in.point_count <= instances_[worst].point_count) return;
    component_to_instance_[voxel_instance_[instances_[worst].first_voxel]] = UINT32_MAX;
    slot = worst;
  } else {
    ++count_;
  }
  instances_[slot] = in;
  component_to_instance_[comp] = slot;
}

// Discovery order, then map voxels to their kept instance's final index.
void InstanceClustering::order_by_discovery(uint32_t n) {
  std::sort(instances_, instances_ + count_,
            [](const Instance& a, const Instance& b) { return a.first_voxel < b.first_voxel; });
  for (uint32_t k = 0; k < count_; ++k) component_to_instance_[voxel_instance_[instances_[k].first_voxel]] = k;
  for (uint32_t i = 0; i < n; ++i)
    if (voxel_instance_[i] != UINT32_MAX) {
      const uint32_t comp = voxel_instance_[i];
      voxel_instance_[i] = component_to_instance_[comp];
    }
}

}  // namespace gsf
