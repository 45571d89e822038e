#include "gsf/port/nuscenes.h"

#include <cmath>
#include <cstring>
#include <filesystem>

#include "scan_files.h"

namespace gsf::port {

uint16_t nuscenes_to_kitti(uint8_t c) {
  if (c == 0 || c == 1 || c == 31) return 0;
  if (c >= 2 && c <= 8) return 30;
  switch (c) {
    case 9: return 51;
    case 10:
    case 11:
    case 12:
    case 13:
    case 29: return 99;
    case 14: return 11;
    case 15:
    case 16: return 13;
    case 17: return 10;
    case 18:
    case 19:
    case 20:
    case 22: return 20;
    case 21: return 15;
    case 23: return 18;
    case 24: return 40;
    case 25: return 49;
    case 26: return 48;
    case 27: return 72;
    case 28: return 50;
    case 30: return 70;
    default: return 0;
  }
}

uint8_t kitti_to_nuscenes(uint32_t label) {
  switch (label & 0xFFFFu) {
    case 10:
    case 252: return 17;
    case 11: return 14;
    case 13: return 16;
    case 15: return 21;
    case 16:
    case 20:
    case 256:
    case 257:
    case 259: return 18;
    case 18:
    case 258: return 23;
    case 30:
    case 31:
    case 32:
    case 253:
    case 254:
    case 255: return 2;
    case 40:
    case 60: return 24;
    case 44:
    case 49: return 25;
    case 48: return 26;
    case 50:
    case 51:
    case 52:
    case 80:
    case 81: return 28;
    case 70:
    case 71: return 30;
    case 72: return 27;
    case 99: return 29;
    default: return 0;
  }
}

Status NuScenesLidarsegWriter::open(const std::string& root, const std::string& seq) {
  return detail::make_sequence_dirs(root, seq, "lidarseg", &dir_);
}

Status NuScenesLidarsegWriter::write_scan(uint32_t frame, const float* xyzi, const uint8_t* lidarseg, uint32_t count) {
  if (dir_.empty()) return Status::NotInitialized;
  if (frame > 999999) return Status::InvalidInput;
  if (count > 0 && (xyzi == nullptr || lidarseg == nullptr)) return Status::InvalidInput;
  for (uint32_t i = 0; i < count; ++i)
    if (lidarseg[i] > 31) return Status::InvalidInput;
  char path[detail::kMaxPathBytes];
  if (!detail::frame_path(path, dir_, "velodyne", frame, ".bin") ||
      !detail::write_file(path, {{xyzi, size_t(count) * 16}}))
    return Status::IoError;
  if (!detail::frame_path(path, dir_, "lidarseg", frame, ".label") ||
      !detail::write_file(path, {{lidarseg, size_t(count)}}))
    return Status::IoError;
  return Status::Ok;
}

Status NuScenesLidarsegWriter::write_poses(const std::vector<Eigen::Isometry3d>& poses) {
  if (dir_.empty()) return Status::NotInitialized;
  return detail::write_pose_files(dir_, poses);
}

Status NuScenesLidarsegSource::open(const std::string& root, const std::string& seq, const KittiReadOptions& options) {
  frames_.clear();
  poses_.clear();
  options_ = options;
  dir_ = root + "/sequences/" + seq;
  std::vector<uint32_t> frames, labelled;
  Status s = detail::list_frames(dir_, "velodyne", ".bin", &frames);
  if (s != Status::Ok) return s;
  if (options.require_labels && detail::list_frames(dir_, "lidarseg", ".label", &labelled) != Status::Ok)
    return Status::IoError;
  // poses.txt holds LiDAR poses already (calib is the identity); optional, but must parse.
  std::vector<Eigen::Isometry3d> poses;
  std::string text;
  s = detail::read_text(dir_ + "/poses.txt", &text);
  if (s == Status::IoError) return s;
  if (s == Status::Ok) {
    s = parse_poses(text, Eigen::Isometry3d::Identity(), &poses);
    if (s != Status::Ok) return s;
  }
  frames_.swap(frames);
  poses_.swap(poses);
  return Status::Ok;
}

Status NuScenesLidarsegSource::pose(uint32_t index, Eigen::Isometry3d* out) const {
  if (index >= frames_.size() || frames_[index] >= poses_.size()) return Status::NotFound;
  *out = poses_[frames_[index]];
  return Status::Ok;
}

// No heap: the files are streamed through a fixed stack chunk and compacted into `out` (ego points
// dropped), so out.count is only published once the whole scan has passed every check.
Status NuScenesLidarsegSource::read(uint32_t index, ScanBuffer& out) {
  out.count = 0;
  out.has_logits = false;
  if (index >= frames_.size()) return Status::NotFound;
  const uint32_t frame = frames_[index];
  char path[detail::kMaxPathBytes];
  detail::InputFile bin, labels;
  if (!detail::frame_path(path, dir_, "velodyne", frame, ".bin") || bin.open(path) != Status::Ok)
    return Status::IoError;
  if (!detail::frame_path(path, dir_, "lidarseg", frame, ".label")) return Status::IoError;
  const Status ls = labels.open(path);
  if (ls == Status::IoError || (ls == Status::NotFound && options_.require_labels)) return Status::IoError;
  if (bin.size() % 16 != 0) return Status::CorruptData;
  const uint64_t n = bin.size() / 16;
  if (labels.is_open() && labels.size() != n) return Status::CorruptData;
  constexpr uint32_t kChunk = 256;
  float pts[kChunk * 4];
  uint8_t lab[kChunk] = {};  // stays 0 (noise -> unlabeled) when there is no label file
  uint32_t w = 0;
  for (uint64_t done = 0; done < n;) {
    const uint32_t m = static_cast<uint32_t>(n - done < kChunk ? n - done : kChunk);
    if (bin.read_exact(pts, size_t(m) * 16) != Status::Ok) return Status::IoError;
    if (labels.is_open() && labels.read_exact(lab, m) != Status::Ok) return Status::IoError;
    for (uint32_t i = 0; i < m; ++i) {
      if (lab[i] > 31) return Status::CorruptData;
      if (lab[i] == 31) continue;  // ego vehicle
      const float* p = pts + 4 * i;
      if (!(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]) && std::isfinite(p[3]))) {
        if (!options_.drop_non_finite) return Status::InvalidInput;
        continue;
      }
      if (w >= out.capacity) return Status::CapacityExceeded;
      std::memcpy(out.points + 4 * size_t(w), p, 16);
      out.labels[w] = options_.raw_labels ? lab[i] : nuscenes_to_kitti(lab[i]);
      ++w;
    }
    done += m;
  }
  out.count = w;
  return Status::Ok;
}

}  // namespace gsf::port
