// The test-world cache (tiny_world.h: save_world / load_world): a world read back equals the one built
// in process, the test_worlds fixture's file equals an in-process build (so tests that read it test
// what they would have built), and a short, corrupted or missing file is refused.
#include <catch2/catch.hpp>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "tiny_world.h"

namespace test_world_cache {

namespace {

const gsf_test::TinyWorld& built_tiny_world() {
  static const gsf_test::TinyWorld* w = gsf_test::build_sim_world(gsf::sim::SimConfig::tiny());
  return *w;
}

void require_equal(const gsf_test::TinyWorld& a, const gsf_test::TinyWorld& b) {
  REQUIRE(a.bytes == b.bytes);
  REQUIRE(std::memcmp(a.blob.data(), b.blob.data(), a.bytes) == 0);
  // The build's counts (its seconds differ from build to build).
  const gsf::mapping::MapBuildStats &s = a.build_stats, &t = b.build_stats;
  REQUIRE(s.scans == t.scans);
  REQUIRE(s.points == t.points);
  REQUIRE(s.map_voxels == t.map_voxels);
  REQUIRE(s.instances == t.instances);
  REQUIRE(s.pole_instances == t.pole_instances);
  REQUIRE(std::memcmp(s.instances_by_class, t.instances_by_class, sizeof(s.instances_by_class)) == 0);
  REQUIRE(s.triangles == t.triangles);
  REQUIRE(s.bytes == t.bytes);
  REQUIRE(a.queries.size() == b.queries.size());
  for (size_t i = 0; i < a.queries.size(); ++i) {
    const gsf_test::QueryScan& x = a.queries[i];
    const gsf_test::QueryScan& y = b.queries[i];
    REQUIRE(x.xyzi == y.xyzi);
    REQUIRE(x.labels == y.labels);
    REQUIRE(x.logits == y.logits);
    REQUIRE(x.truth.matrix() == y.truth.matrix());
    REQUIRE(x.in_zone == y.in_zone);
  }
  REQUIRE(a.map.counts.instances == b.map.counts.instances);
  REQUIRE(a.map.counts.triangles == b.map.counts.triangles);
}

std::string tmp_path(const char* name) { return std::string(GSF_TEST_TMP_DIR) + "/" + name; }

bool load(const std::string& path) {
  gsf_test::TinyWorld* t = gsf_test::new_world(nullptr);
  const bool ok = gsf_test::load_world(path, t);
  delete t;
  return ok;
}

}  // namespace

TEST_CASE("a tiny world saved and read back equals the one built in process") {
  const gsf_test::TinyWorld& built = built_tiny_world();
  REQUIRE(built.queries.size() > 0);
  const std::string path = tmp_path("world_cache_round_trip.world");
  REQUIRE(gsf_test::save_world(built, path));
  gsf_test::TinyWorld* read = gsf_test::new_world(nullptr);
  REQUIRE(gsf_test::load_world(path, read));
  require_equal(built, *read);
  delete read;
}

TEST_CASE("the test_worlds fixture's tiny world equals one built in process") {
  const char* dir = std::getenv("GSF_TEST_WORLDS");
  if (!dir) return;  // run by hand: no fixture to compare (tiny_world() builds in process then)
  gsf_test::TinyWorld* read = gsf_test::new_world(nullptr);
  REQUIRE(gsf_test::load_world(std::string(dir) + "/tiny.world", read));
  require_equal(built_tiny_world(), *read);
  delete read;
}

TEST_CASE("a short, corrupted or missing world file is refused") {
  const std::string path = tmp_path("world_cache_bad.world");
  REQUIRE(gsf_test::save_world(built_tiny_world(), path));
  std::vector<char> bytes;
  {
    FILE* f = std::fopen(path.c_str(), "rb");
    REQUIRE(f);
    char buf[65536];
    size_t n;
    while ((n = std::fread(buf, 1, sizeof(buf), f)) > 0) bytes.insert(bytes.end(), buf, buf + n);
    std::fclose(f);
  }
  const auto write = [&](const std::vector<char>& b) {
    FILE* f = std::fopen(path.c_str(), "wb");
    REQUIRE(f);
    REQUIRE(std::fwrite(b.data(), 1, b.size(), f) == b.size());
    std::fclose(f);
  };
  SECTION("short") {
    write(std::vector<char>(bytes.begin(), bytes.begin() + static_cast<long>(bytes.size() / 2)));
    CHECK_FALSE(load(path));
  }
  SECTION("last byte missing") {
    write(std::vector<char>(bytes.begin(), bytes.end() - 1));
    CHECK_FALSE(load(path));
  }
  SECTION("a map byte flipped (its CRC)") {
    std::vector<char> b = bytes;
    b[8 + 8 + 8 + 200] ^= 0x5a;
    write(b);
    CHECK_FALSE(load(path));
  }
  SECTION("a length made huge") {
    std::vector<char> b = bytes;
    b[8 + 8 + 7] = static_cast<char>(0x7f);
    write(b);
    CHECK_FALSE(load(path));
  }
  SECTION("missing") {
    std::remove(path.c_str());
    CHECK_FALSE(load(path));
  }
}

}  // namespace test_world_cache
