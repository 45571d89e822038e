#include "gsf/port/semantic_kitti.h"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "scan_files.h"

namespace gsf::port {

// The .bin/.label/logits files are little-endian and copied byte for byte into native floats/ints.
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "scan files are read as native little-endian");

namespace {

constexpr size_t kLogitsHeaderBytes = 12;

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

struct ScanLayout {
  uint32_t count = 0;
  bool logits = false;  // logits present, valid, and the buffer can hold them
};

// Every size/header check of a scan, before anything is copied into `out`. `logits_header` is the
// file's first min(12, logit_bytes) bytes, or nullptr when there is no logits file.
Status check_layout(uint64_t bin_bytes, bool have_labels, uint64_t label_bytes, const char* logits_header,
                    uint64_t logit_bytes, const KittiReadOptions& options, const ScanBuffer& out, ScanLayout* layout) {
  if (bin_bytes % 16 != 0) return Status::CorruptData;
  const uint64_t n = bin_bytes / 16;
  if (n > out.capacity) return Status::CapacityExceeded;
  if (!have_labels) {
    if (options.require_labels) return Status::IoError;
  } else if (label_bytes != n * 4) {
    return Status::CorruptData;
  }
  layout->count = static_cast<uint32_t>(n);
  layout->logits = false;
  if (logits_header != nullptr && out.logits != nullptr) {
    if (logit_bytes < kLogitsHeaderBytes || std::memcmp(logits_header, kLogitsMagic, 4) != 0)
      return Status::CorruptData;
    uint16_t version, d;
    uint32_t count;
    std::memcpy(&version, logits_header + 4, 2);
    std::memcpy(&d, logits_header + 6, 2);
    std::memcpy(&count, logits_header + 8, 4);
    if (version != 1 || d != kNumClasses || count != n || logit_bytes != kLogitsHeaderBytes + n * kNumClasses * 4)
      return Status::CorruptData;
    layout->logits = true;
  }
  return Status::Ok;
}

// After the arrays are filled: zero labels when absent, reject or drop non-finite points (keeping
// labels/logits aligned), then publish count/has_logits. Until this returns Ok, out.count stays 0.
Status finish_scan(const ScanLayout& layout, bool have_labels, const KittiReadOptions& options, ScanBuffer& out) {
  const uint32_t n = layout.count;
  if (!have_labels)
    for (uint32_t i = 0; i < n; ++i) out.labels[i] = 0;
  uint32_t w = 0;
  for (uint32_t i = 0; i < n; ++i) {
    const float* p = out.points + 4 * size_t(i);
    bool finite = std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]) && std::isfinite(p[3]);
    if (layout.logits)
      for (int k = 0; k < kNumClasses && finite; ++k) finite = std::isfinite(out.logits[size_t(i) * kNumClasses + k]);
    if (!finite) {
      if (!options.drop_non_finite) return Status::InvalidInput;
      continue;
    }
    if (w != i) {
      std::memmove(out.points + 4 * size_t(w), p, 16);
      out.labels[w] = out.labels[i];
      if (layout.logits)
        std::memmove(out.logits + size_t(w) * kNumClasses, out.logits + size_t(i) * kNumClasses, kNumClasses * 4);
    }
    ++w;
  }
  out.count = w;
  out.has_logits = layout.logits;
  return Status::Ok;
}

}  // namespace

Status parse_scan(const void* bin, size_t bin_bytes, const void* labels, size_t label_bytes, const void* logits_file,
                  size_t logit_bytes, const KittiReadOptions& options, ScanBuffer& out) {
  out.count = 0;
  out.has_logits = false;
  char header[kLogitsHeaderBytes] = {};
  if (logits_file) std::memcpy(header, logits_file, logit_bytes < sizeof(header) ? logit_bytes : sizeof(header));
  ScanLayout layout;
  const Status s = check_layout(bin_bytes, labels != nullptr, label_bytes, logits_file ? header : nullptr, logit_bytes,
                                options, out, &layout);
  if (s != Status::Ok) return s;
  const size_t n = layout.count;
  if (n) std::memcpy(out.points, bin, n * 16);
  if (labels && n) std::memcpy(out.labels, labels, n * 4);
  if (layout.logits && n)
    std::memcpy(out.logits, static_cast<const char*>(logits_file) + kLogitsHeaderBytes, n * kNumClasses * 4);
  return finish_scan(layout, labels != nullptr, options, out);
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

Status SemanticKittiSource::open(const std::string& root, const std::string& seq, const KittiReadOptions& options) {
  frames_.clear();
  poses_.clear();
  has_logits_ = false;
  options_ = options;
  dir_ = root + "/sequences/" + seq;
  std::vector<uint32_t> frames;
  const Status fs = detail::list_frames(dir_, "velodyne", ".bin", &frames);
  if (fs != Status::Ok) return fs;
  // Calibration: Tr maps velodyne into camera 0; identity when the file or the line is absent.
  Eigen::Isometry3d tr = Eigen::Isometry3d::Identity();
  std::string text;
  Status s = detail::read_text(dir_ + "/calib.txt", &text);
  if (s == Status::IoError) return s;
  if (s == Status::Ok) {
    std::istringstream calib(text);
    std::string line;
    std::vector<double> nums;
    while (std::getline(calib, line)) {
      if (line.rfind("Tr:", 0) != 0) continue;
      if (!parse_numbers(line.substr(3), nums) || nums.size() != 12) return Status::CorruptData;
      tr = from_3x4(nums.data());
    }
  }
  // Poses: optional (pose() then reports NotFound), but a malformed file fails open().
  std::vector<Eigen::Isometry3d> poses;
  s = detail::read_text(dir_ + "/poses.txt", &text);
  if (s == Status::IoError) return s;
  if (s == Status::Ok) {
    s = parse_poses(text, tr, &poses);
    if (s != Status::Ok) return s;
  }
  frames_.swap(frames);
  poses_.swap(poses);
  std::error_code ec;
  has_logits_ = options.load_logits && std::filesystem::is_directory(dir_ + "/logits", ec);
  return Status::Ok;
}

Status SemanticKittiSource::pose(uint32_t index, Eigen::Isometry3d* out) const {
  if (index >= frames_.size()) return Status::NotFound;
  const uint32_t f = frames_[index];
  if (f >= poses_.size()) return Status::NotFound;
  *out = poses_[f];
  return Status::Ok;
}

// No heap: paths in stack buffers, file bytes read straight into the caller's arrays.
Status SemanticKittiSource::read(uint32_t index, ScanBuffer& out) {
  out.count = 0;
  out.has_logits = false;
  if (index >= frames_.size()) return Status::NotFound;
  const uint32_t frame = frames_[index];
  char path[detail::kMaxPathBytes];
  detail::InputFile bin, labels, logits;
  if (!detail::frame_path(path, dir_, "velodyne", frame, ".bin") || bin.open(path) != Status::Ok)
    return Status::IoError;
  if (!detail::frame_path(path, dir_, "labels", frame, ".label")) return Status::IoError;
  const Status ls = labels.open(path);
  if (ls == Status::IoError) return ls;
  char header[kLogitsHeaderBytes] = {};
  if (has_logits_ && out.logits != nullptr) {
    if (!detail::frame_path(path, dir_, "logits", frame, ".bin")) return Status::IoError;
    const Status gs = logits.open(path);
    if (gs == Status::IoError) return gs;
    if (logits.is_open() && logits.size() >= sizeof(header) && logits.read_exact(header, sizeof(header)) != Status::Ok)
      return Status::IoError;
  }
  ScanLayout layout;
  const Status s = check_layout(bin.size(), labels.is_open(), labels.size(), logits.is_open() ? header : nullptr,
                                logits.size(), options_, out, &layout);
  if (s != Status::Ok) return s;
  const size_t n = layout.count;
  if (bin.read_exact(out.points, n * 16) != Status::Ok) return Status::IoError;
  if (labels.is_open() && labels.read_exact(out.labels, n * 4) != Status::Ok) return Status::IoError;
  if (layout.logits && logits.read_exact(out.logits, n * kNumClasses * 4) != Status::Ok) return Status::IoError;
  return finish_scan(layout, labels.is_open(), options_, out);
}

Status SemanticKittiWriter::open(const std::string& root, const std::string& seq) {
  return detail::make_sequence_dirs(root, seq, "labels", &dir_);
}

Status SemanticKittiWriter::write_scan(uint32_t frame, const float* xyzi, const uint32_t* labels, const float* logits,
                                       uint32_t count) {
  if (dir_.empty()) return Status::NotInitialized;
  if (frame > 999999) return Status::InvalidInput;  // file names have six digits
  if (count > 0 && (xyzi == nullptr || labels == nullptr)) return Status::InvalidInput;
  char path[detail::kMaxPathBytes];
  if (!detail::frame_path(path, dir_, "velodyne", frame, ".bin") ||
      !detail::write_file(path, {{xyzi, size_t(count) * 16}}))
    return Status::IoError;
  if (!detail::frame_path(path, dir_, "labels", frame, ".label") ||
      !detail::write_file(path, {{labels, size_t(count) * 4}}))
    return Status::IoError;
  if (logits) {
    std::error_code ec;
    std::filesystem::create_directories(dir_ + "/logits", ec);
    char header[kLogitsHeaderBytes];
    const uint16_t version = 1, d = kNumClasses;
    std::memcpy(header, kLogitsMagic, 4);
    std::memcpy(header + 4, &version, 2);
    std::memcpy(header + 6, &d, 2);
    std::memcpy(header + 8, &count, 4);
    if (ec || !detail::frame_path(path, dir_, "logits", frame, ".bin") ||
        !detail::write_file(path, {{header, sizeof(header)}, {logits, size_t(count) * kNumClasses * 4}}))
      return Status::IoError;
  }
  return Status::Ok;
}

Status SemanticKittiWriter::write_poses(const std::vector<Eigen::Isometry3d>& poses) {
  if (dir_.empty()) return Status::NotInitialized;
  return detail::write_pose_files(dir_, poses);
}

}  // namespace gsf::port
