// SemanticKITTI layout reader and writer:
//   <root>/sequences/<seq>/velodyne/NNNNNN.bin   float32 x, y, z, intensity per point
//   <root>/sequences/<seq>/labels/NNNNNN.label   uint32 per point: semantic id (low 16) | instance (high 16)
//   <root>/sequences/<seq>/logits/NNNNNN.bin     optional, format in docs/data-formats.md
//   <root>/sequences/<seq>/poses.txt             3x4 row-major per frame (camera frame); 13 numbers = time first
//   <root>/sequences/<seq>/calib.txt             Tr: velodyne -> camera (identity if absent)
// LiDAR pose in the world: Tr^-1 * P_i * Tr (KITTI / SemanticKITTI convention).
#pragma once
#include <string>
#include <vector>

#include "gsf/port/scan_source.h"

namespace gsf::port {

struct KittiReadOptions {
  bool require_labels = true;
  bool load_logits = true;       // when logits/ exists
  bool drop_non_finite = false;  // false: a NaN/Inf point rejects the scan with InvalidInput
  // nuScenes-lidarseg only: keep the raw lidarseg class (0..30) as the label instead of mapping it to
  // a SemanticKITTI id; use with nuscenes_lidarseg_class_table() (or a user table of lidarseg ids).
  bool raw_labels = false;
};

// Parses one scan from memory (what read() does after loading the files): .bin bytes, .label bytes
// (nullptr when absent), logits file bytes (nullptr when absent). Same statuses as read().
Status parse_scan(const void* bin, size_t bin_bytes, const void* labels, size_t label_bytes, const void* logits,
                  size_t logit_bytes, const KittiReadOptions& options, ScanBuffer& out);

// Parses poses.txt text (12 or 13 numbers per line) into LiDAR poses with calibration Tr.
Status parse_poses(const std::string& text, const Eigen::Isometry3d& tr, std::vector<Eigen::Isometry3d>* poses);

// open() reads the folder listing, calib.txt and poses.txt (allocates); read() does not allocate.
// A missing poses.txt is allowed (pose() -> NotFound); a malformed one fails open() with CorruptData.
// With logits/ present, a frame without its logits file is read without logits (has_logits false).
class SemanticKittiSource final : public ScanSource {
 public:
  Status open(const std::string& dataset_root, const std::string& sequence, const KittiReadOptions& options = {});
  uint32_t size() const override { return static_cast<uint32_t>(frames_.size()); }
  uint32_t frame_id(uint32_t index) const override { return index < frames_.size() ? frames_[index] : 0; }
  Status read(uint32_t index, ScanBuffer& out) override;
  Status pose(uint32_t index, Eigen::Isometry3d* world_T_lidar) const override;
  bool has_logits() const { return has_logits_; }
  const std::string& directory() const { return dir_; }

 private:
  std::string dir_;
  KittiReadOptions options_;
  std::vector<uint32_t> frames_;
  std::vector<Eigen::Isometry3d> poses_;  // by frame number (poses.txt line i = frame i)
  bool has_logits_ = false;
};

class SemanticKittiWriter {
 public:
  // Creates the sequence's folders; frame files a sequence written there before left are removed (the
  // reader lists the frame files: a longer stale sequence would add frames without poses).
  Status open(const std::string& dataset_root, const std::string& sequence);
  Status write_scan(uint32_t frame, const float* xyzi, const uint32_t* labels, const float* logits_or_null,
                    uint32_t count);
  // Writes poses.txt (LiDAR poses, line i = frame i) and calib.txt with an identity Tr.
  Status write_poses(const std::vector<Eigen::Isometry3d>& world_T_lidar);

 private:
  std::string dir_;
};

// Logits file: "GSFL", u16 version = 1, u16 D, u32 count, then count x D float32 (little-endian).
constexpr char kLogitsMagic[4] = {'G', 'S', 'F', 'L'};

}  // namespace gsf::port
