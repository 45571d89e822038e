#include "mapping/scan_detections.h"

#include <algorithm>
#include <cmath>

#include "gsf/detail/arena.h"
#include "mapping/workspace.h"

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
  Arena arena = aligned_arena(memory_.data(), memory_.size() * 8);
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
  s = poles_.build(voxels, nullptr, LayerFrame::Sensor);  // one scan, sensor frame
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
  const CellIndex cells(detections.size(), radius,
                        [&](size_t i) { return std::make_pair(detections[i].xyz[0], detections[i].xyz[1]); });
  const float r2 = radius * radius;
  for (uint32_t i = 0; i < n; ++i) {
    const float* c = centroids + 3 * size_t(i);
    cells.for_each_near(c[0], c[1], [&](uint32_t k) {
      const ScanDetection& d = detections[k];
      const float ex = d.xyz[0] - c[0], ey = d.xyz[1] - c[1];
      if ((d.label == kAnyLabel || d.label == labels[i]) && ex * ex + ey * ey <= r2) ++count[i];
    });
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
