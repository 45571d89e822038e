// port::MappedFile: a map file memory-mapped read-only, or read into an aligned buffer when mapping is
// refused or not wanted; either way load_map validates it and uses it in place.
#include <catch2/catch.hpp>

#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "fuzz_seed_map.h"
#include "gsf/map_format.h"
#include "gsf/port/mapped_file.h"

namespace test_mapped_file {

using namespace gsf;

namespace {

std::string write_tmp(const std::string& name, const void* data, size_t bytes) {
  const std::string path = std::string(GSF_TEST_TMP_DIR) + "/" + name;
  FILE* f = std::fopen(path.c_str(), "wb");
  REQUIRE(f != nullptr);
  if (bytes) REQUIRE(std::fwrite(data, 1, bytes, f) == bytes);
  std::fclose(f);
  return path;
}

}  // namespace

TEST_CASE("A map file loads the same mapped or read, in place, 16-byte aligned") {
  size_t bytes = 0;
  const std::vector<uint64_t> blob = gsf_test::fuzz_seed_map(&bytes);
  const std::string path = write_tmp("mapped_file_map.gsfmap", blob.data(), bytes);
  for (bool allow_mmap : {true, false}) {
    INFO("allow_mmap " << allow_mmap);
    port::MappedFile f;
    REQUIRE(f.open(path, allow_mmap) == Status::Ok);
    CHECK(f.mapped() == allow_mmap);  // a regular file on the host's filesystem maps
    REQUIRE(f.size() == bytes);
    CHECK(reinterpret_cast<uintptr_t>(f.data()) % 16 == 0);
    CHECK(std::memcmp(f.data(), blob.data(), bytes) == 0);
    MapView v;
    REQUIRE(load_map(f.data(), f.size(), &v) == Status::Ok);
    const auto* base = static_cast<const uint8_t*>(f.data());
    CHECK(reinterpret_cast<const uint8_t*>(v.instances) > base);  // zero copy: the view points into it
    CHECK(reinterpret_cast<const uint8_t*>(v.instances) < base + bytes);
    CHECK(std::string(v.georef.frame) == "utm-32N");
  }
}

TEST_CASE("Missing, empty and non-regular files: IoError, or an empty buffer load_map calls truncated") {
  port::MappedFile f;
  CHECK(f.open(std::string(GSF_TEST_TMP_DIR) + "/no-such-file.gsfmap") == Status::IoError);
  CHECK(f.size() == 0);
  CHECK_FALSE(f.mapped());
  MapView v;
  const std::string empty = write_tmp("mapped_file_empty.gsfmap", nullptr, 0);
  REQUIRE(f.open(empty) == Status::Ok);  // mmap cannot map 0 bytes: read instead
  CHECK_FALSE(f.mapped());
  CHECK(f.size() == 0);
  REQUIRE(f.data() != nullptr);
  CHECK(load_map(f.data(), f.size(), &v) == Status::Truncated);
  REQUIRE(f.open("/dev/null") == Status::Ok);  // a character device: not mapped, read to its end
  CHECK_FALSE(f.mapped());
  CHECK(f.size() == 0);
}

TEST_CASE("Reopening replaces the contents; closing empties") {
  const char a[] = "first file", b[] = "the second, longer file";
  const std::string pa = write_tmp("mapped_file_a.bin", a, sizeof(a)),
                    pb = write_tmp("mapped_file_b.bin", b, sizeof(b));
  port::MappedFile f;
  REQUIRE(f.open(pa) == Status::Ok);
  CHECK(f.size() == sizeof(a));
  CHECK(std::memcmp(f.data(), a, sizeof(a)) == 0);
  REQUIRE(f.open(pb, false) == Status::Ok);
  CHECK(f.size() == sizeof(b));
  CHECK(std::memcmp(f.data(), b, sizeof(b)) == 0);
  f.close();
  CHECK(f.size() == 0);
  CHECK_FALSE(f.mapped());
}

}  // namespace test_mapped_file
