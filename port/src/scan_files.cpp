#include "scan_files.h"

#include <cmath>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace gsf::port::detail {

bool frame_path(char (&out)[kMaxPathBytes], const std::string& dir, const char* sub, uint32_t frame, const char* ext) {
  const int n = std::snprintf(out, sizeof(out), "%s/%s/%06u%s", dir.c_str(), sub, frame, ext);
  return n > 0 && static_cast<size_t>(n) < sizeof(out);
}

bool parse_frame_name(const std::string& name, const char* ext, uint32_t* frame) {
  const size_t ext_len = std::strlen(ext);
  if (name.size() != 6 + ext_len || name.compare(6, ext_len, ext) != 0) return false;
  uint32_t v = 0;
  for (size_t i = 0; i < 6; ++i) {
    if (name[i] < '0' || name[i] > '9') return false;
    v = v * 10 + static_cast<uint32_t>(name[i] - '0');
  }
  *frame = v;
  return true;
}

Status list_frames(const std::string& dir, const char* sub, const char* ext, std::vector<uint32_t>* frames) {
  namespace fs = std::filesystem;
  frames->clear();
  std::error_code ec;
  const fs::path folder = fs::path(dir) / sub;
  if (!fs::is_directory(folder, ec)) return Status::IoError;
  fs::directory_iterator it(folder, ec);
  for (; !ec && it != fs::directory_iterator(); it.increment(ec)) {
    uint32_t f;
    if (parse_frame_name(it->path().filename().string(), ext, &f)) frames->push_back(f);
  }
  if (ec) {
    frames->clear();
    return Status::IoError;
  }
  std::sort(frames->begin(), frames->end());
  return Status::Ok;
}

Status read_text(const std::string& path, std::string* text) {
  std::ifstream f(path);
  if (!f) return Status::NotFound;
  std::stringstream s;
  s << f.rdbuf();
  *text = s.str();
  return f.bad() ? Status::IoError : Status::Ok;
}

InputFile::~InputFile() {
  if (fd_ >= 0) ::close(fd_);
}

Status InputFile::open(const char* path) {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  size_ = 0;
  const int fd = ::open(path, O_RDONLY | O_CLOEXEC);
  if (fd < 0) return errno == ENOENT ? Status::NotFound : Status::IoError;
  struct stat st;
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode) || st.st_size < 0) {
    ::close(fd);
    return Status::IoError;
  }
  fd_ = fd;
  size_ = static_cast<uint64_t>(st.st_size);
  return Status::Ok;
}

Status InputFile::read_exact(void* dst, size_t bytes) {
  if (fd_ < 0) return Status::IoError;
  char* p = static_cast<char*>(dst);
  size_t done = 0;
  // Bounded: each pass either makes progress, retries an interrupted call, or returns.
  while (done < bytes) {
    const ssize_t r = ::read(fd_, p + done, bytes - done);
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) return Status::IoError;
    done += static_cast<size_t>(r);
  }
  return Status::Ok;
}

namespace {

// Removes the frame files (NNNNNN<ext>) of <d>/<sub>, if that folder exists; other files stay.
bool remove_frames(const std::string& d, const char* sub, const char* ext) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path folder = fs::path(d) / sub;
  if (!fs::is_directory(folder, ec)) return true;
  std::vector<fs::path> stale;
  fs::directory_iterator it(folder, ec);
  for (; !ec && it != fs::directory_iterator(); it.increment(ec)) {
    uint32_t f;
    if (parse_frame_name(it->path().filename().string(), ext, &f)) stale.push_back(it->path());
  }
  for (const fs::path& p : stale)
    if (!ec) fs::remove(p, ec);
  return !ec;
}

}  // namespace

Status make_sequence_dirs(const std::string& root, const std::string& seq, const char* label_sub, std::string* dir) {
  namespace fs = std::filesystem;
  dir->clear();
  const std::string d = root + "/sequences/" + seq;
  std::error_code ec;
  fs::create_directories(fs::path(d) / "velodyne", ec);
  if (!ec) fs::create_directories(fs::path(d) / label_sub, ec);
  if (ec) return Status::IoError;
  // A sequence written before into the same place may have had more frames: the readers list the frame
  // files, so its stale ones would join the new sequence (without poses: build-map failed NotFound).
  if (!remove_frames(d, "velodyne", ".bin") || !remove_frames(d, label_sub, ".label") ||
      !remove_frames(d, "logits", ".bin"))
    return Status::IoError;
  *dir = d;
  return Status::Ok;
}

bool write_file(const std::string& path, std::initializer_list<std::pair<const void*, size_t>> parts) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  for (const auto& p : parts)
    if (p.second) f.write(static_cast<const char*>(p.first), static_cast<std::streamsize>(p.second));
  f.close();
  return !f.fail();
}

Status write_pose_files(const std::string& dir, const std::vector<Eigen::Isometry3d>& poses) {
  std::string text;
  char b[64];
  for (const auto& p : poses) {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) {
        const double v = p.matrix()(r, c);
        if (!std::isfinite(v)) return Status::InvalidInput;
        std::snprintf(b, sizeof(b), "%.17g%c", v, (r == 2 && c == 3) ? '\n' : ' ');  // %.17g: exact round trip
        text += b;
      }
  }
  static const char kIdentityTr[] = "Tr: 1 0 0 0 0 1 0 0 0 0 1 0\n";
  return write_file(dir + "/poses.txt", {{text.data(), text.size()}}) &&
                 write_file(dir + "/calib.txt", {{kIdentityTr, sizeof(kIdentityTr) - 1}})
             ? Status::Ok
             : Status::IoError;
}

}  // namespace gsf::port::detail
