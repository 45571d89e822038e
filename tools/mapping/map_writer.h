// Offline (host, may use the heap): writes a map (map_format.h) section by section, so the map never
// has to exist as a whole in memory. The builder hands each section over in id order as soon as it is
// computed and frees it; the sink computes each section's CRC-32 as the bytes pass, zero-pads to the
// next 16-byte offset and, at finish(), writes the header and section table that write_map would write
// (map_layout / write_map_header: the format's own code, so the bytes are write_map's) in front of them.
// MemoryMapSink builds the blob in memory (tests, in-process callers); FileMapSink writes a file and
// seeks back for the header, holding nothing but the header.
#pragma once
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "gsf/map_format.h"

namespace gsf::mapping {

class MapSink {
 public:
  virtual ~MapSink() = default;
  // The next section (sections come in id order, each once): whole, or in pieces between
  // begin_section and end_section. InvalidArgument for a section out of order.
  Status section(MapSection id, const void* data, size_t bytes);
  Status begin_section(MapSection id);
  Status append(const void* data, size_t bytes);
  Status end_section();
  // After the last section: checks that what was written is the layout `contents` (params, counts,
  // georeference) implies (InvalidArgument otherwise), then writes the header and section table.
  // *bytes: the map's size.
  Status finish(const MapView& contents, size_t* bytes);

 protected:
  // Bytes at the end of what was written so far; the header at offset 0 (at finish); then commit.
  virtual Status write(const void* data, size_t bytes) = 0;
  virtual Status write_header(const void* data, size_t bytes) = 0;
  virtual Status commit() { return Status::Ok; }

 private:
  Status pad_to(uint64_t offset);
  uint64_t at_ = 0;      // bytes written (the header counted from the start)
  uint32_t next_ = 0;    // index of the next section
  bool open_ = false;    // inside begin_section / end_section
  bool failed_ = false;  // a write failed: every later call fails
  uint64_t offset_[kMapSectionCount] = {}, bytes_[kMapSectionCount] = {};
  uint32_t crc_[kMapSectionCount] = {};
};

// The map in memory as 16-byte aligned words (blob->size() * 8 >= *bytes, the tail zero).
class MemoryMapSink : public MapSink {
 public:
  explicit MemoryMapSink(std::vector<uint64_t>* blob);

 protected:
  Status write(const void* data, size_t bytes) override;
  Status write_header(const void* data, size_t bytes) override;

 private:
  std::vector<uint64_t>* blob_;
  size_t size_ = 0;
};

// The map written to `path`, through a temporary file next to it (path + ".partial") renamed over
// `path` at finish(), so a failed build never leaves a partial map under the final name. IoError
// (from the first section on) when the file cannot be created, written or renamed.
class FileMapSink : public MapSink {
 public:
  explicit FileMapSink(const std::string& path);
  ~FileMapSink() override;                           // closes and removes the temporary file unless finish() succeeded
  bool is_open() const { return file_ != nullptr; }  // the temporary file could be created

 protected:
  Status write(const void* data, size_t bytes) override;
  Status write_header(const void* data, size_t bytes) override;
  Status commit() override;

 private:
  std::string path_, partial_;
  std::FILE* file_ = nullptr;
  bool done_ = false;
};

}  // namespace gsf::mapping
