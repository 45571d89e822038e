#include "mapping/scan_detections.h"

#include <algorithm>
#include <cmath>

#include "gsf/detail/arena.h"

namespace gsf::mapping {

Status ScanDetector::init(const LocalizerConfig& stages, uint32_t max_voxels) {
  ClusterConfig cluster = stages.cluster;
  cluster.instance_classes = stages.classes ? stages.classes->instance_classes() : stages.cluster.instance_classes;
  const PoleConfig poles = effective_pole_config(stages);
  poles_on_ = (poles.pole_hosts | poles.trunk_hosts) != 0;
  max_instances_ = stages.cluster.max_instances;
  size_t bytes = InstanceClustering::required_bytes(cluster, max_voxels) + 256;
  if (poles_on_) bytes += PoleExtraction::required_bytes(poles, max_voxels) + 256;
  memory_.assign(bytes / 8 + 4, 0);
  void* base = reinterpret_cast<void*>((reinterpret_cast<uintptr_t>(memory_.data()) + 15) & ~uintptr_t(15));
  Arena arena(base, memory_.size() * 8 - 16);
  if (clusters_.bind(arena, cluster, max_voxels) != Status::Ok) return Status::InvalidArgument;
  clusters_.set_classes(stages.classes);
  if (poles_on_) {
    if (poles_.bind(arena, poles, max_voxels) != Status::Ok) return Status::InvalidArgument;
    pole_order_.resize(poles.max_instances);
  }
  return Status::Ok;
}

Status ScanDetector::detect(const VoxelLayer& voxels, const Eigen::Isometry3d& map_T_lidar,
                            std::vector<ScanDetection>* out) {
  auto push = [&](const Instance& in) {
    const Eigen::Vector3d p = map_T_lidar * Eigen::Vector3d(in.centroid[0], in.centroid[1], in.centroid[2]);
    ScanDetection d{};
    for (int k = 0; k < 3; ++k) d.xyz[k] = static_cast<float>(p[k]);
    d.label = in.label;
    out->push_back(d);
  };
  // As Localizer::find_instances: clustered instances, then geometric poles best score first into the
  // slots clustering left free.
  Status s = clusters_.build(voxels, nullptr);
  if (s != Status::Ok && s != Status::CapacityExceeded) return s;
  uint32_t n = clusters_.size();
  for (uint32_t i = 0; i < n; ++i) push(clusters_.instance(i));
  if (!poles_on_) return Status::Ok;
  s = poles_.build(voxels, nullptr);
  if (s != Status::Ok && s != Status::CapacityExceeded) return s;
  const uint32_t np = poles_.size();  // <= poles.max_instances = pole_order_.size()
  poles_.order_by_score(pole_order_.data());
  for (uint32_t k = 0; k < np && n < max_instances_; ++k, ++n) push(poles_.instance(pole_order_[k]));
  return Status::Ok;
}

std::vector<uint32_t> count_detections(const float* centroids, const uint8_t* labels, uint32_t n,
                                       const std::vector<ScanDetection>& detections, float radius) {
  std::vector<uint32_t> count(n, 0);
  if (detections.empty() || !(radius > 0.0f)) return count;
  // Detections sorted by (cell x, cell y) of `radius` cells; an instance looks in its 3 x 3 cells.
  auto cell = [radius](float v) { return static_cast<int64_t>(std::floor(v / radius)); };
  auto key = [](int64_t cx, int64_t cy) {
    return (uint64_t(cx + (int64_t(1) << 31)) << 32) | uint32_t(cy + (1u << 31));
  };
  std::vector<std::pair<uint64_t, uint32_t>> idx(detections.size());
  for (size_t i = 0; i < detections.size(); ++i)
    idx[i] = {key(cell(detections[i].xyz[0]), cell(detections[i].xyz[1])), static_cast<uint32_t>(i)};
  std::sort(idx.begin(), idx.end());
  const float r2 = radius * radius;
  for (uint32_t i = 0; i < n; ++i) {
    const float* c = centroids + 3 * size_t(i);
    const int64_t cx = cell(c[0]), cy = cell(c[1]);
    for (int64_t dx = -1; dx <= 1; ++dx)
      for (int64_t dy = -1; dy <= 1; ++dy) {
        const uint64_t k = key(cx + dx, cy + dy);
        auto it = std::lower_bound(idx.begin(), idx.end(), std::make_pair(k, uint32_t(0)));
        for (; it != idx.end() && it->first == k; ++it) {
          const ScanDetection& d = detections[it->second];
          const float ex = d.xyz[0] - c[0], ey = d.xyz[1] - c[1];
          if ((d.label == kAnyLabel || d.label == labels[i]) && ex * ex + ey * ey <= r2) ++count[i];
        }
      }
  }
  return count;
}

std::vector<uint32_t> triangle_vertices(const std::vector<uint32_t>& detections,
                                        const std::vector<uint32_t>& opportunities, uint32_t min_detections) {
  std::vector<uint32_t> ids;
  for (uint32_t i = 0; i < detections.size(); ++i)
    if (detections[i] >= std::min(min_detections, opportunities[i])) ids.push_back(i);
  return ids;
}

}  // namespace gsf::mapping
