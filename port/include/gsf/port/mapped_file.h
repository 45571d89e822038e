// A file's bytes, read-only, at a 16-byte-aligned address: what gsf::load_map needs for a map file.
// Where the platform allows, the file is memory-mapped (POSIX mmap, read-only, private): nothing is
// copied, pages are read on first touch and the page cache shares them between processes. Otherwise
// (mmap refused, e.g. a pipe or a filesystem without mmap, or allow_mmap = false) the bytes are read into
// an aligned heap buffer. Either way data() stays valid and unchanged until the object is destroyed or
// reopened, so a MapView loaded over it must not outlive it. Host code (port layer).
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "gsf/status.h"

namespace gsf::port {

class MappedFile {
 public:
  MappedFile() = default;
  ~MappedFile() { close(); }
  MappedFile(const MappedFile&) = delete;
  MappedFile& operator=(const MappedFile&) = delete;

  // IoError if the file cannot be opened or read; on failure the object is empty.
  Status open(const std::string& path, bool allow_mmap = true);
  void close();

  const void* data() const { return mapping_ ? mapping_ : static_cast<const void*>(words_.data()); }
  size_t size() const { return size_; }
  bool mapped() const { return mapping_ != nullptr; }  // false: the bytes were read into a buffer

 private:
  void* mapping_ = nullptr;
  size_t size_ = 0;
  std::vector<uint64_t> words_ = std::vector<uint64_t>(2, 0);  // fallback; never empty, so data() != nullptr
};

}  // namespace gsf::port
