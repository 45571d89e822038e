// Internal to port/: allocation-free file access for the scan readers. read() must not touch the heap
// after open() (firmware-facing contract of ScanBuffer filling), so paths go into a fixed stack buffer
// and files are read with POSIX open/fstat/read straight into the caller's ScanBuffer, not through
// std::ifstream / std::filesystem / std::vector (which allocate on every call).
#pragma once
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "gsf/status.h"

namespace gsf::port::detail {

constexpr size_t kMaxPathBytes = 4096;

// "<dir>/<sub>/NNNNNN<ext>" into `out`; false when it does not fit.
bool frame_path(char (&out)[kMaxPathBytes], const std::string& dir, const char* sub, uint32_t frame, const char* ext);

// Strict frame file name: exactly six decimal digits then `ext` ("000052.bin"); anything else is not a frame.
bool parse_frame_name(const std::string& name, const char* ext, uint32_t* frame);

// The sorted frame numbers of <dir>/<sub>/NNNNNN<ext>. IoError when the folder is missing/unreadable.
Status list_frames(const std::string& dir, const char* sub, const char* ext, std::vector<uint32_t>* frames);

// Reads a whole text file (open() time only: allocates). Missing file -> NotFound.
Status read_text(const std::string& path, std::string* text);

// Writers (host tools: allocate). Creates <root>/sequences/<seq>/velodyne and .../<label_sub>, removes
// the frame files (NNNNNN.bin / .label) a sequence written there before left in velodyne, <label_sub>
// and logits (a writer writes a whole sequence), and sets *dir to <root>/sequences/<seq> (cleared on
// failure). IoError when a folder cannot be created or a stale frame file removed.
Status make_sequence_dirs(const std::string& root, const std::string& seq, const char* label_sub, std::string* dir);
// Writes `parts` to `path`; false unless every byte reached the file.
bool write_file(const std::string& path, std::initializer_list<std::pair<const void*, size_t>> parts);
// <dir>/poses.txt (3x4 row-major LiDAR poses, %.17g so they read back exactly, line i = frame i) and
// <dir>/calib.txt with an identity Tr. InvalidInput for a non-finite pose, IoError for a failed write.
Status write_pose_files(const std::string& dir, const std::vector<Eigen::Isometry3d>& world_T_lidar);

// One open file, closed on destruction. No allocation.
class InputFile {
 public:
  InputFile() = default;
  InputFile(const InputFile&) = delete;
  InputFile& operator=(const InputFile&) = delete;
  ~InputFile();
  // Ok, NotFound (no such file) or IoError (exists but cannot be opened / is not a regular file).
  Status open(const char* path);
  bool is_open() const { return fd_ >= 0; }
  uint64_t size() const { return size_; }
  // Exactly `bytes` bytes from the current position, else IoError (short file, read error).
  Status read_exact(void* dst, size_t bytes);

 private:
  int fd_ = -1;
  uint64_t size_ = 0;
};

}  // namespace gsf::port::detail
