// nuScenes-lidarseg scenes in the KITTI-like layout of ../shared/data/nuscenes-lidarseg-samples:
//   sequences/<scene>/velodyne/NNNNNN.bin (float32 x,y,z,intensity), lidarseg/NNNNNN.label (uint8 class
//   0-31), poses.txt (LiDAR poses in the global frame), calib.txt (identity Tr).
// Labels are mapped to SemanticKITTI ids (the mapping in that folder's README); ego-vehicle returns
// (class 31) are dropped; a class > 31 makes the scan CorruptData.
#pragma once
#include <string>
#include <vector>

#include "gsf/port/scan_source.h"

namespace gsf::port {

uint16_t nuscenes_to_kitti(uint8_t nuscenes_class);

class NuScenesLidarsegSource final : public ScanSource {
 public:
  Status open(const std::string& dataset_root, const std::string& sequence);
  uint32_t size() const override { return static_cast<uint32_t>(frames_.size()); }
  uint32_t frame_id(uint32_t index) const override { return index < frames_.size() ? frames_[index] : 0; }
  Status read(uint32_t index, ScanBuffer& out) override;
  Status pose(uint32_t index, Eigen::Isometry3d* world_T_lidar) const override;

 private:
  std::string dir_;
  std::vector<uint32_t> frames_;
  std::vector<Eigen::Isometry3d> poses_;
};

}  // namespace gsf::port
