// nuScenes-lidarseg scenes in the KITTI-like layout of ../shared/data/nuscenes-lidarseg-samples:
//   sequences/<scene>/velodyne/NNNNNN.bin (float32 x,y,z,intensity), lidarseg/NNNNNN.label (uint8 class
//   0-31), poses.txt (LiDAR poses in the global frame), calib.txt (identity Tr, not read).
// Labels are mapped to SemanticKITTI ids (the mapping in that folder's README), or kept as raw lidarseg
// ids with KittiReadOptions::raw_labels (for the nuScenes-lidarseg ClassTable); ego-vehicle returns
// (class 31) are dropped; a class > 31 makes the scan CorruptData. read() does not allocate; the
// buffer's capacity bounds the points kept after the ego points are dropped.
#pragma once
#include <string>
#include <vector>

#include "gsf/port/scan_source.h"
#include "gsf/port/semantic_kitti.h"  // KittiReadOptions

namespace gsf::port {

uint16_t nuscenes_to_kitti(uint8_t nuscenes_class);
// The lidarseg class nuScenes would give a point of this SemanticKITTI label (low 16 bits): poles,
// traffic signs, fences, other structure and buildings -> 28 static.manmade; trunks and vegetation ->
// 30 static.vegetation; other-object -> 29 static.other; unlabeled/outlier/unknown ids -> 0 noise. The
// simulator's nuScenes-style output (gsf simulate --label-set nuscenes) uses it.
uint8_t kitti_to_nuscenes(uint32_t kitti_label);

// Writes a scene in the layout NuScenesLidarsegSource reads: velodyne/NNNNNN.bin (x, y, z, intensity
// float32), lidarseg/NNNNNN.label (uint8 class per point), poses.txt and an identity calib.txt.
class NuScenesLidarsegWriter {
 public:
  // Creates the sequence's folders; frame files a sequence written there before left are removed (the
  // reader lists the frame files: a longer stale sequence would add frames without poses).
  Status open(const std::string& dataset_root, const std::string& sequence);
  Status write_scan(uint32_t frame, const float* xyzi, const uint8_t* lidarseg, uint32_t count);
  Status write_poses(const std::vector<Eigen::Isometry3d>& world_T_lidar);

 private:
  std::string dir_;
};

class NuScenesLidarsegSource final : public ScanSource {
 public:
  // options.require_labels: a missing lidarseg file is IoError (else the scan is read with label 0 and
  // nothing dropped); options.drop_non_finite as for SemanticKITTI; load_logits is unused (no logits).
  Status open(const std::string& dataset_root, const std::string& sequence, const KittiReadOptions& options = {});
  uint32_t size() const override { return static_cast<uint32_t>(frames_.size()); }
  uint32_t frame_id(uint32_t index) const override { return index < frames_.size() ? frames_[index] : 0; }
  Status read(uint32_t index, ScanBuffer& out) override;
  Status pose(uint32_t index, Eigen::Isometry3d* world_T_lidar) const override;

 private:
  std::string dir_;
  KittiReadOptions options_;
  std::vector<uint32_t> frames_;
  std::vector<Eigen::Isometry3d> poses_;
};

}  // namespace gsf::port
