#include "gsf/port/semantic_kitti.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace fs = std::filesystem;

namespace gsf::port {
namespace {

std::string frame_name(uint32_t frame, const char* ext) {
  char b[32];
  std::snprintf(b, sizeof(b), "%06u%s", frame, ext);
  return b;
}

// Reads a whole file into `buf`; false if missing/unreadable.
bool read_file(const std::string& path, std::vector<char>& buf) {
  std::ifstream f(path, std::ios::binary | std::ios::ate);
  if (!f) return false;
  const std::streamoff n = f.tellg();
  if (n < 0) return false;
  buf.resize(static_cast<size_t>(n));
  f.seekg(0);
  return n == 0 || static_cast<bool>(f.read(buf.data(), n));
}

bool parse_numbers(const std::string& line, std::vector<double>& out) {
  out.clear();
  std::istringstream s(line);
  double v;
  while (s >> v) out.push_back(v);
  return s.eof() && !out.empty();
}

Eigen::Isometry3d from_3x4(const double* m) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) t.matrix()(r, c) = m[4 * r + c];
    t.matrix()(r, 3) = m[4 * r + 3];
  }
  return t;
}

}  // namespace

Status SemanticKittiSource::open(const std::string& root, const std::string& seq, const KittiReadOptions& options) {
  frames_.clear();
  poses_.clear();
  has_pose_.clear();
  options_ = options;
  dir_ = (fs::path(root) / "sequences" / seq).string();
  std::error_code ec;
  if (!fs::is_directory(fs::path(dir_) / "velodyne", ec)) return Status::IoError;
  for (const auto& e : fs::directory_iterator(fs::path(dir_) / "velodyne", ec)) {
    const std::string name = e.path().filename().string();
    if (e.path().extension() != ".bin" || name.size() != 10) continue;
    char* end = nullptr;
    const unsigned long v = std::strtoul(name.c_str(), &end, 10);
    if (end != name.c_str() + 6) continue;
    frames_.push_back(static_cast<uint32_t>(v));
  }
  if (ec) return Status::IoError;
  std::sort(frames_.begin(), frames_.end());
  has_logits_ = options.load_logits && fs::is_directory(fs::path(dir_) / "logits", ec);
  // Calibration: Tr maps velodyne into camera 0; identity when absent.
  Eigen::Isometry3d tr = Eigen::Isometry3d::Identity();
  std::ifstream calib(fs::path(dir_) / "calib.txt");
  std::string line;
  std::vector<double> nums;
  while (calib && std::getline(calib, line)) {
    if (line.rfind("Tr:", 0) != 0) continue;
    if (!parse_numbers(line.substr(3), nums) || nums.size() != 12) return Status::CorruptData;
    tr = from_3x4(nums.data());
  }
  std::ifstream poses(fs::path(dir_) / "poses.txt");
  std::stringstream text;
  text << poses.rdbuf();
  const Status ps = parse_poses(text.str(), tr, &poses_);
  if (ps != Status::Ok) return ps;
  has_pose_.assign(poses_.size(), true);
  return Status::Ok;
}

Status parse_poses(const std::string& text, const Eigen::Isometry3d& tr, std::vector<Eigen::Isometry3d>* out) {
  out->clear();
  std::istringstream in(text);
  std::string line;
  std::vector<double> nums;
  const Eigen::Isometry3d tr_inv = tr.inverse();
  while (std::getline(in, line)) {
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    if (!parse_numbers(line, nums) || (nums.size() != 12 && nums.size() != 13)) return Status::CorruptData;
    const double* m = nums.data() + (nums.size() == 13 ? 1 : 0);
    for (int k = 0; k < 12; ++k)
      if (!std::isfinite(m[k])) return Status::CorruptData;
    out->push_back(tr_inv * from_3x4(m) * tr);
  }
  return Status::Ok;
}

Status SemanticKittiSource::pose(uint32_t index, Eigen::Isometry3d* out) const {
  if (index >= frames_.size()) return Status::NotFound;
  const uint32_t f = frames_[index];
  if (f >= poses_.size()) return Status::NotFound;
  *out = poses_[f];
  return Status::Ok;
}

Status parse_scan(const void* bin, size_t bin_bytes, const void* labels, size_t label_bytes, const void* logits_file,
                  size_t logit_bytes, const KittiReadOptions& options, ScanBuffer& out) {
  out.count = 0;
  out.has_logits = false;
  if (bin_bytes % 16 != 0) return Status::CorruptData;
  const uint64_t n64 = bin_bytes / 16;
  if (n64 > out.capacity) return Status::CapacityExceeded;
  const uint32_t n = static_cast<uint32_t>(n64);
  if (labels == nullptr) {
    if (options.require_labels) return Status::IoError;
  } else if (label_bytes != size_t(n) * 4) {
    return Status::CorruptData;
  }
  bool logits = false;
  if (logits_file != nullptr && out.logits != nullptr) {
    const char* lg = static_cast<const char*>(logits_file);
    if (logit_bytes < 12 || std::memcmp(lg, kLogitsMagic, 4) != 0) return Status::CorruptData;
    uint16_t version, d;
    uint32_t count;
    std::memcpy(&version, lg + 4, 2);
    std::memcpy(&d, lg + 6, 2);
    std::memcpy(&count, lg + 8, 4);
    if (version != 1 || d != kNumClasses || count != n || logit_bytes != 12 + size_t(n) * kNumClasses * 4)
      return Status::CorruptData;
    logits = true;
  }
  if (n) std::memcpy(out.points, bin, size_t(n) * 16);
  if (labels) {
    if (n) std::memcpy(out.labels, labels, size_t(n) * 4);
  } else {
    for (uint32_t i = 0; i < n; ++i) out.labels[i] = 0;
  }
  if (logits && n) std::memcpy(out.logits, static_cast<const char*>(logits_file) + 12, size_t(n) * kNumClasses * 4);
  // Finite check (and optional compaction keeping labels/logits aligned).
  uint32_t w = 0;
  for (uint32_t i = 0; i < n; ++i) {
    const float* p = out.points + 4 * size_t(i);
    bool finite = std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]) && std::isfinite(p[3]);
    if (logits)
      for (int k = 0; k < kNumClasses && finite; ++k) finite = std::isfinite(out.logits[size_t(i) * kNumClasses + k]);
    if (!finite) {
      if (!options.drop_non_finite) return Status::InvalidInput;
      continue;
    }
    if (w != i) {
      std::memmove(out.points + 4 * size_t(w), p, 16);
      out.labels[w] = out.labels[i];
      if (logits) std::memmove(out.logits + size_t(w) * kNumClasses, out.logits + size_t(i) * kNumClasses, kNumClasses * 4);
    }
    ++w;
  }
  out.count = w;
  out.has_logits = logits;
  return Status::Ok;
}

Status SemanticKittiSource::read(uint32_t index, ScanBuffer& out) {
  out.count = 0;
  out.has_logits = false;
  if (index >= frames_.size()) return Status::NotFound;
  const uint32_t frame = frames_[index];
  if (!read_file((fs::path(dir_) / "velodyne" / frame_name(frame, ".bin")).string(), bytes_)) return Status::IoError;
  std::vector<char> lab, lg;
  const bool have_labels = read_file((fs::path(dir_) / "labels" / frame_name(frame, ".label")).string(), lab);
  const bool have_logits = has_logits_ && out.logits && read_file((fs::path(dir_) / "logits" / frame_name(frame, ".bin")).string(), lg);
  return parse_scan(bytes_.data(), bytes_.size(), have_labels ? lab.data() : nullptr, lab.size(),
                    have_logits ? lg.data() : nullptr, lg.size(), options_, out);
}

Status SemanticKittiWriter::open(const std::string& root, const std::string& seq) {
  dir_ = (fs::path(root) / "sequences" / seq).string();
  std::error_code ec;
  fs::create_directories(fs::path(dir_) / "velodyne", ec);
  fs::create_directories(fs::path(dir_) / "labels", ec);
  return ec ? Status::IoError : Status::Ok;
}

Status SemanticKittiWriter::write_scan(uint32_t frame, const float* xyzi, const uint32_t* labels, const float* logits,
                                       uint32_t count) {
  if (dir_.empty()) return Status::NotInitialized;
  {
    std::ofstream f(fs::path(dir_) / "velodyne" / frame_name(frame, ".bin"), std::ios::binary | std::ios::trunc);
    if (!f.write(reinterpret_cast<const char*>(xyzi), std::streamsize(count) * 16)) return Status::IoError;
  }
  {
    std::ofstream f(fs::path(dir_) / "labels" / frame_name(frame, ".label"), std::ios::binary | std::ios::trunc);
    if (!f.write(reinterpret_cast<const char*>(labels), std::streamsize(count) * 4)) return Status::IoError;
  }
  if (logits) {
    std::error_code ec;
    fs::create_directories(fs::path(dir_) / "logits", ec);
    std::ofstream f(fs::path(dir_) / "logits" / frame_name(frame, ".bin"), std::ios::binary | std::ios::trunc);
    const uint16_t version = 1, d = kNumClasses;
    f.write(kLogitsMagic, 4);
    f.write(reinterpret_cast<const char*>(&version), 2);
    f.write(reinterpret_cast<const char*>(&d), 2);
    f.write(reinterpret_cast<const char*>(&count), 4);
    if (!f.write(reinterpret_cast<const char*>(logits), std::streamsize(count) * kNumClasses * 4)) return Status::IoError;
  }
  return Status::Ok;
}

Status SemanticKittiWriter::write_poses(const std::vector<Eigen::Isometry3d>& poses) {
  if (dir_.empty()) return Status::NotInitialized;
  std::ofstream f(fs::path(dir_) / "poses.txt", std::ios::trunc);
  char b[64];
  for (const auto& p : poses) {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) {
        std::snprintf(b, sizeof(b), "%.17g", p.matrix()(r, c));
        f << b << ((r == 2 && c == 3) ? "\n" : " ");
      }
  }
  std::ofstream cal(fs::path(dir_) / "calib.txt", std::ios::trunc);
  cal << "Tr: 1 0 0 0 0 1 0 0 0 0 1 0\n";
  return (f && cal) ? Status::Ok : Status::IoError;
}

}  // namespace gsf::port
