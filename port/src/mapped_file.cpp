#include "gsf/port/mapped_file.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace gsf::port {
namespace {

// Reads everything from fd (regular file or not) into 16-byte-aligned words.
bool read_all(int fd, std::vector<uint64_t>* words, size_t* size) {
  std::vector<char> bytes;
  char chunk[65536];
  while (true) {
    const ssize_t n = ::read(fd, chunk, sizeof(chunk));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return false;
    if (n == 0) break;
    bytes.insert(bytes.end(), chunk, chunk + n);
  }
  // operator new aligns to 16 on the hosts we build for (__STDCPP_DEFAULT_NEW_ALIGNMENT__), and the
  // words start the buffer; the +2 keeps it non-empty and padded.
  static_assert(__STDCPP_DEFAULT_NEW_ALIGNMENT__ >= 16, "aligned fallback buffer");
  words->assign(bytes.size() / 8 + 2, 0);
  if (!bytes.empty()) std::memcpy(words->data(), bytes.data(), bytes.size());
  *size = bytes.size();
  return true;
}

}  // namespace

void MappedFile::close() {
  if (mapping_) ::munmap(mapping_, size_);
  mapping_ = nullptr;
  size_ = 0;
  words_.assign(2, 0);
}

Status MappedFile::open(const std::string& path, bool allow_mmap) {
  close();
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return Status::IoError;
  struct stat st {};
  const bool regular = ::fstat(fd, &st) == 0 && S_ISREG(st.st_mode);
  if (allow_mmap && regular && st.st_size > 0) {
    void* p = ::mmap(nullptr, static_cast<size_t>(st.st_size), PROT_READ, MAP_PRIVATE, fd, 0);
    if (p != MAP_FAILED) {  // page-aligned, so 16-byte aligned
      mapping_ = p;
      size_ = static_cast<size_t>(st.st_size);
      ::close(fd);
      return Status::Ok;
    }
  }
  const bool ok = read_all(fd, &words_, &size_);
  ::close(fd);
  if (!ok) {
    close();
    return Status::IoError;
  }
  return Status::Ok;
}

}  // namespace gsf::port
