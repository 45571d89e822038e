#include "mapping/map_writer.h"

#include <algorithm>
#include <cstring>

#include "gsf/detail/crc32.h"

namespace gsf::mapping {
namespace {

uint64_t align16(uint64_t v) { return (v + 15) & ~uint64_t(15); }

}  // namespace

Status MapSink::pad_to(uint64_t offset) {
  static const uint8_t zeros[64] = {};
  while (at_ < offset) {
    const size_t n = static_cast<size_t>(std::min<uint64_t>(offset - at_, sizeof(zeros)));
    const Status s = write(zeros, n);
    if (s != Status::Ok) {
      failed_ = true;
      return s;
    }
    at_ += n;
  }
  return Status::Ok;
}

Status MapSink::begin_section(MapSection id) {
  if (failed_) return Status::IoError;
  if (open_ || next_ >= kMapSectionCount || static_cast<uint32_t>(id) != next_ + 1) return Status::InvalidArgument;
  // The header and table are written at finish(); sections start 16-aligned after them.
  const Status s = pad_to(align16(next_ == 0 ? map_header_bytes() : at_));
  if (s != Status::Ok) return s;
  offset_[next_] = at_;
  bytes_[next_] = 0;
  crc_[next_] = 0;
  open_ = true;
  return Status::Ok;
}

Status MapSink::append(const void* data, size_t bytes) {
  if (failed_) return Status::IoError;
  if (!open_ || (bytes > 0 && data == nullptr)) return Status::InvalidArgument;
  if (bytes == 0) return Status::Ok;
  const Status s = write(data, bytes);
  if (s != Status::Ok) {
    failed_ = true;
    return s;
  }
  crc_[next_] = crc32_update(crc_[next_], data, bytes);
  bytes_[next_] += bytes;
  at_ += bytes;
  return Status::Ok;
}

Status MapSink::end_section() {
  if (failed_) return Status::IoError;
  if (!open_) return Status::InvalidArgument;
  open_ = false;
  ++next_;
  return Status::Ok;
}

Status MapSink::section(MapSection id, const void* data, size_t bytes) {
  Status s = begin_section(id);
  if (s == Status::Ok) s = append(data, bytes);
  if (s == Status::Ok) s = end_section();
  return s;
}

Status MapSink::finish(const MapView& contents, size_t* bytes) {
  if (bytes) *bytes = 0;
  if (failed_) return Status::IoError;
  if (open_ || next_ != kMapSectionCount) return Status::InvalidArgument;
  MapSectionLayout layout[kMapSectionCount];
  size_t total = 0;
  Status s = map_layout(contents, layout, &total);
  if (s != Status::Ok) return s;
  for (uint32_t i = 0; i < kMapSectionCount; ++i)
    if (layout[i].offset != offset_[i] || layout[i].bytes != bytes_[i]) return Status::InvalidArgument;
  s = pad_to(total);
  if (s != Status::Ok) return s;
  std::vector<uint8_t> header(map_header_bytes());
  s = write_map_header(contents, crc_, header.data(), header.size());
  if (s != Status::Ok) return s;
  s = write_header(header.data(), header.size());
  if (s == Status::Ok) s = commit();
  if (s != Status::Ok) {
    failed_ = true;
    return s;
  }
  if (bytes) *bytes = total;
  return Status::Ok;
}

MemoryMapSink::MemoryMapSink(std::vector<uint64_t>* blob) : blob_(blob) { blob_->clear(); }

Status MemoryMapSink::write(const void* data, size_t bytes) {
  // Words up to the end, plus two words of zero tail (as the map's blobs always had).
  blob_->resize((size_ + bytes) / 8 + 2, 0);
  std::memcpy(reinterpret_cast<uint8_t*>(blob_->data()) + size_, data, bytes);
  size_ += bytes;
  return Status::Ok;
}

Status MemoryMapSink::write_header(const void* data, size_t bytes) {
  if (bytes > size_) return Status::InvalidArgument;
  std::memcpy(blob_->data(), data, bytes);
  return Status::Ok;
}

FileMapSink::FileMapSink(const std::string& path) : path_(path), partial_(path + ".partial") {
  file_ = std::fopen(partial_.c_str(), "wb");
}

FileMapSink::~FileMapSink() {
  if (file_) std::fclose(file_);
  if (!done_) std::remove(partial_.c_str());
}

Status FileMapSink::write(const void* data, size_t bytes) {
  if (!file_ || std::fwrite(data, 1, bytes, file_) != bytes) return Status::IoError;
  return Status::Ok;
}

Status FileMapSink::write_header(const void* data, size_t bytes) {
  if (!file_ || std::fseek(file_, 0, SEEK_SET) != 0 || std::fwrite(data, 1, bytes, file_) != bytes)
    return Status::IoError;
  return Status::Ok;
}

Status FileMapSink::commit() {
  if (!file_) return Status::IoError;
  const bool ok = std::fflush(file_) == 0 && !std::ferror(file_);
  const bool closed = std::fclose(file_) == 0;
  file_ = nullptr;
  if (!ok || !closed || std::rename(partial_.c_str(), path_.c_str()) != 0) return Status::IoError;
  done_ = true;
  return Status::Ok;
}

}  // namespace gsf::mapping
