#include "gsf/port/nuscenes.h"

#include <cmath>
#include <cstring>

#include "scan_files.h"

namespace gsf::port {

uint16_t nuscenes_to_kitti(uint8_t c) {
  if (c == 0 || c == 1 || c == 31) return 0;
  if (c >= 2 && c <= 8) return 30;
  switch (c) {
    case 9: return 51;
    case 10: case 11: case 12: case 13: case 29: return 99;
    case 14: return 11;
    case 15: case 16: return 13;
    case 17: return 10;
    case 18: case 19: case 20: case 22: return 20;
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
  if (!detail::frame_path(path, dir_, "velodyne", frame, ".bin") || bin.open(path) != Status::Ok) return Status::IoError;
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
      out.labels[w] = nuscenes_to_kitti(lab[i]);
      ++w;
    }
    done += m;
  }
  out.count = w;
  return Status::Ok;
}

}  // namespace gsf::port
