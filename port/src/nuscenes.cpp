#include "gsf/port/nuscenes.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;

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

Status NuScenesLidarsegSource::open(const std::string& root, const std::string& seq) {
  frames_.clear();
  poses_.clear();
  dir_ = (fs::path(root) / "sequences" / seq).string();
  std::error_code ec;
  if (!fs::is_directory(fs::path(dir_) / "velodyne", ec) || !fs::is_directory(fs::path(dir_) / "lidarseg", ec))
    return Status::IoError;
  for (const auto& e : fs::directory_iterator(fs::path(dir_) / "velodyne", ec)) {
    const std::string name = e.path().filename().string();
    if (e.path().extension() != ".bin" || name.size() != 10) continue;
    frames_.push_back(static_cast<uint32_t>(std::strtoul(name.c_str(), nullptr, 10)));
  }
  std::sort(frames_.begin(), frames_.end());
  std::ifstream poses(fs::path(dir_) / "poses.txt");
  std::string line;
  while (poses && std::getline(poses, line)) {
    std::istringstream s(line);
    double m[12];
    int k = 0;
    while (k < 12 && (s >> m[k])) ++k;
    if (k == 0) continue;
    if (k != 12) return Status::CorruptData;
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) t.matrix()(r, c) = m[4 * r + c];
    poses_.push_back(t);
  }
  return Status::Ok;
}

Status NuScenesLidarsegSource::pose(uint32_t index, Eigen::Isometry3d* out) const {
  if (index >= frames_.size() || frames_[index] >= poses_.size()) return Status::NotFound;
  *out = poses_[frames_[index]];
  return Status::Ok;
}

Status NuScenesLidarsegSource::read(uint32_t index, ScanBuffer& out) {
  out.count = 0;
  out.has_logits = false;
  if (index >= frames_.size()) return Status::NotFound;
  char name[32];
  std::snprintf(name, sizeof(name), "%06u", frames_[index]);
  std::ifstream fb(fs::path(dir_) / "velodyne" / (std::string(name) + ".bin"), std::ios::binary | std::ios::ate);
  std::ifstream fl(fs::path(dir_) / "lidarseg" / (std::string(name) + ".label"), std::ios::binary | std::ios::ate);
  if (!fb || !fl) return Status::IoError;
  const std::streamoff nb = fb.tellg(), nl = fl.tellg();
  if (nb < 0 || nl < 0 || nb % 16 != 0) return Status::CorruptData;
  const uint64_t n = uint64_t(nb) / 16;
  if (uint64_t(nl) != n) return Status::CorruptData;
  std::vector<float> pts(n * 4);
  std::vector<uint8_t> lab(n);
  fb.seekg(0);
  fl.seekg(0);
  if ((n && !fb.read(reinterpret_cast<char*>(pts.data()), nb)) || (n && !fl.read(reinterpret_cast<char*>(lab.data()), nl)))
    return Status::IoError;
  uint32_t w = 0;
  for (uint64_t i = 0; i < n; ++i) {
    if (lab[i] > 31) return Status::CorruptData;
    if (lab[i] == 31) continue;  // ego vehicle
    const float* p = pts.data() + 4 * i;
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) return Status::InvalidInput;
    if (w >= out.capacity) return Status::CapacityExceeded;
    std::memcpy(out.points + 4 * size_t(w), p, 16);
    out.labels[w] = nuscenes_to_kitti(lab[i]);
    ++w;
  }
  out.count = w;
  return Status::Ok;
}

}  // namespace gsf::port
