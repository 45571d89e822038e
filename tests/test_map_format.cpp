// Map blob: round trip, and every single-byte corruption or truncation is rejected (never a crash).
#include <catch2/catch.hpp>

#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "fuzz_seed_map.h"
#include "gsf/detail/crc32.h"
#include "gsf/map_format.h"
#include "gsf/semantic_classes.h"

namespace test_map_format {

using namespace gsf;

namespace {

struct SmallMap {
  std::vector<MapInstance> instances;
  std::vector<uint8_t> mean;
  std::vector<uint16_t> var;
  std::vector<MapRefineTile> refine_tiles;
  std::vector<MapRefinePoint> refine;
  std::vector<MapTriangle> tris;
  std::vector<uint64_t> keys;
  std::vector<uint32_t> offsets;
  MapView view;

  SmallMap() {
    // A georeferenced map: an origin of UTM size with fractions that float32 could not hold.
    view.georef.origin[0] = 512345.25;
    view.georef.origin[1] = 5412345.125;
    view.georef.origin[2] = 251.0625;
    set_frame_name(&view.georef, "utm-32N");
    MapParams& p = view.params;
    std::memset(&p, 0, sizeof(p));
    p.num_classes = kNumClasses;
    p.instance_class_mask = kDefaultInstanceClasses;
    p.field_input_dims = 2;
    p.inducing_stride = 4;
    p.grid_nx = 2;
    p.grid_ny = 2;
    p.grid_layers = 1;
    p.triangle_neighbours = 10;
    p.grid_spacing = 1.5f;
    p.layer_spacing = 1.0f;
    p.grid_z0 = 0.0f;
    p.length_scale = 2.0f;
    p.signal_variance = 1.0f;
    p.noise_variance = 0.05f;
    p.field_radius = 8.0f;
    p.voxel_size = 0.4f;
    p.side_bin = 1.0f;
    p.min_side = 0.5f;
    p.max_side = 50.0f;
    p.class_table_id = 0xC0FFEE01u;
    const uint32_t n = 4, g = 4, d = kNumClasses;
    for (uint32_t i = 0; i < n; ++i) {
      MapInstance in;
      std::memset(&in, 0, sizeof(in));
      in.centroid[0] = float(i) * 3.0f;
      in.centroid[1] = float(i * i);
      in.centroid[2] = 1.0f;
      in.stability = 1.0f;
      in.point_count = 10 + i;
      in.mean_min = -0.1f;
      in.mean_step = 0.005f * float(i + 1);
      in.var_min = 0.05f;
      in.var_step = 1e-5f;
      in.label = kPole;
      instances.push_back(in);
    }
    for (uint32_t i = 0; i < n * g * d; ++i) mean.push_back(uint8_t(i * 7 % 256));
    for (uint32_t i = 0; i < n * g; ++i) var.push_back(uint16_t(i * 4099 % 65536));
    MapTriangle t;
    std::memset(&t, 0, sizeof(t));
    t.v[0] = 0;
    t.v[1] = 1;
    t.v[2] = 2;
    t.side[0] = 3.2f;
    t.side[1] = 5.8f;
    t.side[2] = 8.9f;
    for (int k = 0; k < 3; ++k) t.label[k] = kPole;
    t.orientation = kOrientationCounterClockwise;
    tris.push_back(t);
    t.v[2] = 3;
    t.side[2] = 9.5f;
    tris.push_back(t);
    // Stored in key order (format v5): one key each, (pole x 3; 3, 5, 8) then (pole x 3; 3, 5, 9).
    keys = {triangle_key(tris[0], p.side_bin), triangle_key(tris[1], p.side_bin)};
    offsets = {0, 1, 2};
    // Refinement layer: two tiles, (0, 0) from z cell -1 and (1, 0) from z cell 3; a point without a normal.
    p.refine_cell = 1.0f;
    refine_tiles = {{(32768u << 16) | 32768u, 0, -1}, {(32769u << 16) | 32768u, 2, 3}};
    refine = {{uint16_t(1 << 8 | 2 << 4 | 3), {10, 20, 30}, {0, 0, 127}},
              {uint16_t(1 << 8 | 2 << 4 | 4), {255, 0, 128}, {0, 0, 0}},
              {uint16_t(5), {1, 2, 3}, {90, -90, 0}}};
    view.counts.instances = n;
    view.counts.triangles = 2;
    view.counts.index_keys = 2;
    view.counts.refine_points = 3;
    view.counts.refine_tiles = 2;
    view.counts.road_length_m = 123.0f;
    view.instances = instances.data();
    view.grid_mean = mean.data();
    view.grid_var = var.data();
    view.triangles = tris.data();
    view.index_keys = keys.data();
    view.index_offsets = offsets.data();
    view.refine_tiles = refine_tiles.data();
    view.refine_points = refine.data();
  }
};

// 16-byte aligned byte buffer
struct Blob {
  std::vector<uint64_t> words;
  explicit Blob(size_t bytes) : words((bytes + 15) / 8 + 2, 0) {}
  uint8_t* data() {
    auto p = reinterpret_cast<uintptr_t>(words.data());
    return reinterpret_cast<uint8_t*>((p + 15) & ~uintptr_t(15));
  }
};

bool same_semantic_layer(const MapView& a, const MapView& b) {
  const uint64_t tiles = a.counts.semantic_tiles, tc = a.params.semantic_tile_cells;
  if (tiles == 0) return b.counts.semantic_tiles == 0;
  return std::memcmp(a.semantic_tile_keys, b.semantic_tile_keys, tiles * 4) == 0 &&
         std::memcmp(a.semantic_palette_offsets, b.semantic_palette_offsets, (tiles + 1) * 4) == 0 &&
         std::memcmp(a.semantic_palette, b.semantic_palette, a.counts.semantic_palette * 4) == 0 &&
         std::memcmp(a.semantic_neighbours, b.semantic_neighbours, a.counts.semantic_palette * 4) == 0 &&
         std::memcmp(a.semantic_cells, b.semantic_cells, tiles * tc * tc) == 0;
}

bool same_map(const MapView& a, const MapView& b) {
  if (std::memcmp(&a.georef, &b.georef, sizeof(MapGeoreference)) != 0) return false;
  if (std::memcmp(&a.params, &b.params, sizeof(MapParams)) != 0) return false;
  if (std::memcmp(&a.counts, &b.counts, sizeof(MapCounts)) != 0) return false;
  const uint64_t n = a.counts.instances, g = a.grid_points(), d = a.params.num_classes;
  return std::memcmp(a.instances, b.instances, n * sizeof(MapInstance)) == 0 &&
         std::memcmp(a.grid_mean, b.grid_mean, n * g * d) == 0 && std::memcmp(a.grid_var, b.grid_var, n * g * 2) == 0 &&
         std::memcmp(a.triangles, b.triangles, a.counts.triangles * sizeof(MapTriangle)) == 0 &&
         std::memcmp(a.index_keys, b.index_keys, a.counts.index_keys * 8) == 0 &&
         std::memcmp(a.index_offsets, b.index_offsets, (a.counts.index_keys + 1) * 4) == 0 &&
         std::memcmp(a.refine_tiles, b.refine_tiles, a.counts.refine_tiles * sizeof(MapRefineTile)) == 0 &&
         std::memcmp(a.refine_points, b.refine_points, a.counts.refine_points * sizeof(MapRefinePoint)) == 0 &&
         same_semantic_layer(a, b);
}

// Rewrites the header with `edit` applied and its CRC re-sealed, as a writer of that header would.
template <class Edit>
void reseal_header(uint8_t* blob, Edit edit) {
  MapHeader h;
  std::memcpy(&h, blob, sizeof(h));
  edit(&h);
  h.header_crc = 0;
  std::memcpy(blob, &h, sizeof(h));
  const uint32_t crc = crc32(blob, sizeof(MapHeader) + kMapSectionCount * sizeof(SectionEntry));
  std::memcpy(blob + offsetof(MapHeader, header_crc), &crc, sizeof(crc));
}

std::vector<uint8_t> read_file(const std::string& path) {
  std::vector<uint8_t> bytes;
  FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) return bytes;
  uint8_t buf[4096];
  size_t n;
  while ((n = std::fread(buf, 1, sizeof(buf), f)) > 0) bytes.insert(bytes.end(), buf, buf + n);
  std::fclose(f);
  return bytes;
}

}  // namespace

TEST_CASE("CRC-32 matches the standard check value") {
  const char* s = "123456789";
  CHECK(crc32(s, 9) == 0xCBF43926u);
  CHECK(crc32_update(crc32(s, 4), s + 4, 5) == 0xCBF43926u);
}

TEST_CASE("Map round trip is exact and deterministic") {
  SmallMap sm;
  const size_t size = map_serialized_size(sm.view);
  REQUIRE(size > sizeof(MapHeader));
  Blob a(size), b(size);
  size_t written = 0;
  REQUIRE(write_map(sm.view, a.data(), size, &written) == Status::Ok);
  REQUIRE(written == size);
  REQUIRE(write_map(sm.view, b.data(), size, nullptr) == Status::Ok);
  CHECK(std::memcmp(a.data(), b.data(), size) == 0);  // same contents, same bytes
  MapView loaded;
  REQUIRE(load_map(a.data(), size, &loaded) == Status::Ok);
  CHECK(same_map(sm.view, loaded));
  // The georeference comes back to the bit: doubles, not floats (5412345.125 has no float32).
  CHECK(loaded.georef.origin[0] == 512345.25);
  CHECK(loaded.georef.origin[1] == 5412345.125);
  CHECK(loaded.georef.origin[2] == 251.0625);
  CHECK(std::string(loaded.georef.frame) == "utm-32N");
  CHECK(loaded.params.class_table_id == 0xC0FFEE01u);
  CHECK(reinterpret_cast<const uint8_t*>(loaded.instances) >= a.data());  // zero copy: points into the blob
  CHECK(reinterpret_cast<const uint8_t*>(loaded.instances) < a.data() + size);
  CHECK(write_map(sm.view, a.data(), size - 1, nullptr) == Status::BufferTooSmall);
}

TEST_CASE("Every flipped byte is rejected or loads an equivalent map") {
  SmallMap sm;
  const size_t size = map_serialized_size(sm.view);
  Blob good(size);
  REQUIRE(write_map(sm.view, good.data(), size, nullptr) == Status::Ok);
  Blob work(size);
  size_t rejected = 0;
  for (size_t pos = 0; pos < size; ++pos) {
    for (uint8_t flip : {uint8_t(0x01), uint8_t(0x80), uint8_t(0xFF)}) {
      std::memcpy(work.data(), good.data(), size);
      work.data()[pos] ^= flip;
      MapView v;
      const Status s = load_map(work.data(), size, &v);
      if (s == Status::Ok) {
        INFO("byte " << pos);
        CHECK(same_map(sm.view, v));  // only padding outside every CRC may change silently
      } else {
        ++rejected;
        CHECK(v.instances == nullptr);  // a failed load leaves an empty view
      }
    }
  }
  CHECK(rejected > size);  // the vast majority are caught
}

TEST_CASE("Every flipped byte of the fuzz seed map (semantic palette layer included) is rejected or harmless") {
  size_t size = 0;
  const std::vector<uint64_t> seed = gsf_test::fuzz_seed_map(&size);
  MapView original;
  REQUIRE(load_map(seed.data(), size, &original) == Status::Ok);
  REQUIRE(original.counts.semantic_tiles > 0);
  REQUIRE(original.counts.refine_points > 0);
  Blob work(size);
  size_t rejected = 0;
  for (size_t pos = 0; pos < size; ++pos) {
    for (uint8_t flip : {uint8_t(0x01), uint8_t(0x80), uint8_t(0xFF)}) {
      std::memcpy(work.data(), seed.data(), size);
      work.data()[pos] ^= flip;
      MapView v;
      if (load_map(work.data(), size, &v) == Status::Ok) {
        INFO("byte " << pos);
        CHECK(same_map(original, v));
      } else {
        ++rejected;
      }
    }
  }
  CHECK(rejected > size);
}

TEST_CASE("Every truncation and bad framing is rejected") {
  SmallMap sm;
  const size_t size = map_serialized_size(sm.view);
  Blob good(size);
  REQUIRE(write_map(sm.view, good.data(), size, nullptr) == Status::Ok);
  for (size_t len = 0; len < size; ++len) {
    MapView v;
    const Status s = load_map(good.data(), len, &v);
    INFO("length " << len);
    CHECK(s != Status::Ok);
  }
  MapView v;
  CHECK(load_map(nullptr, size, &v) == Status::InvalidArgument);
  CHECK(load_map(good.data() + 4, size - 4, &v) == Status::InvalidArgument);  // misaligned
  Blob bigger(size + 16);
  std::memcpy(bigger.data(), good.data(), size);
  CHECK(load_map(bigger.data(), size + 16, &v) == Status::CorruptData);  // trailing bytes are not ours
}

TEST_CASE("Version and class-table mismatches are named, not just corrupt") {
  SmallMap sm;
  sm.view.params.num_classes = kNumClasses + 1;
  sm.mean.resize(sm.view.counts.instances * 4 * (kNumClasses + 1));
  sm.view.grid_mean = sm.mean.data();
  const size_t size = map_serialized_size(sm.view);
  Blob blob(size);
  CHECK(write_map(sm.view, blob.data(), size, nullptr) == Status::InvalidArgument);

  SmallMap ok;
  const size_t s2 = map_serialized_size(ok.view);
  Blob b2(s2);
  REQUIRE(write_map(ok.view, b2.data(), s2, nullptr) == Status::Ok);
  // Rewrite the version and fix up the header CRC, as a newer writer would.
  MapHeader h;
  std::memcpy(&h, b2.data(), sizeof(h));
  h.version = kMapVersion + 1;
  h.header_crc = 0;
  std::memcpy(b2.data(), &h, sizeof(h));
  MapView v;
  CHECK(load_map(b2.data(), s2, &v) == Status::VersionMismatch);
}

TEST_CASE("Semantically invalid contents with valid CRCs are rejected") {
  SmallMap sm;
  sm.tris[0].v[2] = 99;  // vertex out of range
  const size_t size = map_serialized_size(sm.view);
  Blob blob(size);
  REQUIRE(write_map(sm.view, blob.data(), size, nullptr) == Status::Ok);
  MapView v;
  CHECK(load_map(blob.data(), size, &v) == Status::CorruptData);
  // A triangle orientation that is none of the three senses (triangle.h); every sense itself loads.
  for (uint8_t o = 0; o <= 4; ++o) {
    SmallMap om;
    om.tris[0].orientation = o;
    Blob b2(size);
    REQUIRE(write_map(om.view, b2.data(), size, nullptr) == Status::Ok);
    INFO("orientation " << int(o));
    CHECK(load_map(b2.data(), size, &v) ==
          (o >= kOrientationCounterClockwise && o <= kOrientationFlat ? Status::Ok : Status::CorruptData));
  }

  // Quantisation scales whose levels are not all finite (or variances below 0), behind valid CRCs.
  for (int which = 0; which < 4; ++which) {
    SmallMap bad;
    MapInstance& in = bad.instances[2];
    if (which == 0) in.mean_min = std::numeric_limits<float>::quiet_NaN();
    if (which == 1) in.mean_step = 3e36f;  // min + 255 step overflows
    if (which == 2) in.var_min = -0.5f;
    if (which == 3) in.var_step = -1e-6f;
    Blob b2(size);
    REQUIRE(write_map(bad.view, b2.data(), size, nullptr) == Status::Ok);
    INFO("scale case " << which);
    CHECK(load_map(b2.data(), size, &v) == Status::CorruptData);
  }
  // Refinement layer: unsorted cells in a tile, a normal far from unit length, tiles out of order.
  for (int which = 0; which < 3; ++which) {
    SmallMap bad;
    if (which == 0) std::swap(bad.refine[0], bad.refine[1]);
    if (which == 1) bad.refine[2].normal[2] = 100;  // |(90, -90, 100)| = 162
    if (which == 2) std::swap(bad.refine_tiles[0].key, bad.refine_tiles[1].key);
    Blob b2(size);
    REQUIRE(write_map(bad.view, b2.data(), size, nullptr) == Status::Ok);
    INFO("refine case " << which);
    CHECK(load_map(b2.data(), size, &v) == Status::CorruptData);
  }

  SmallMap unsorted;
  std::swap(unsorted.keys[0], unsorted.keys[1]);
  Blob b3(size);
  REQUIRE(write_map(unsorted.view, b3.data(), size, nullptr) == Status::Ok);
  CHECK(load_map(b3.data(), size, &v) == Status::CorruptData);
  // Behind valid CRCs and sorted keys: triangles out of key order (each under the other's key), a side
  // moved to another bin, labels changed consistently with their instances (labels are part of the key),
  // one bucket holding both triangles.
  for (int which = 0; which < 4; ++which) {
    SmallMap bad;
    if (which == 0) std::swap(bad.tris[0], bad.tris[1]);
    if (which == 1) bad.tris[1].side[2] = 10.5f;
    if (which == 2) {
      for (MapInstance& in : bad.instances) in.label = kTrunk;
      for (MapTriangle& t : bad.tris)
        for (int k = 0; k < 3; ++k) t.label[k] = kTrunk;
    }
    if (which == 3) bad.offsets = {0, 2, 2};
    Blob b4(size);
    REQUIRE(write_map(bad.view, b4.data(), size, nullptr) == Status::Ok);
    INFO("index case " << which);
    CHECK(load_map(b4.data(), size, &v) == Status::CorruptData);
  }
  // A side bin too fine for the keys' 16-bit sides (max_side / side_bin >= 65534).
  SmallMap fine;
  fine.view.params.side_bin = 50.0f / 65534.0f;
  Blob b5(size);
  CHECK(write_map(fine.view, b5.data(), size, nullptr) == Status::InvalidArgument);
}

TEST_CASE("Version 1 to 5 maps are refused as VersionMismatch, real v2, v3, v4 and v5 files included") {
  // Real files: the fuzz seed map as each older format version wrote it.
  struct OldFile {
    const char* name;
    size_t bytes;
  };
  const OldFile files[] = {
      {"map_v5_small.gsfmap", 1376},  // 12 sections, a palette of masks without their neighbour masks
      {"map_v4_small.gsfmap", 1424},  // 13 sections, an IndexEntries section, triangles in build order
      {"map_v3_small.gsfmap", 2928},  // 240-byte header, float grids, inducing inputs and alpha
      {"map_v2_small.gsfmap", 2880},  // 184-byte header
  };
  MapView v;
  for (const OldFile& f : files) {
    const std::vector<uint8_t> bytes = read_file(std::string(GSF_SOURCE_DIR) + "/tests/data/" + f.name);
    INFO(f.name);
    REQUIRE(bytes.size() == f.bytes);
    Blob old(bytes.size());
    std::memcpy(old.data(), bytes.data(), bytes.size());
    v.instances = reinterpret_cast<const MapInstance*>(&f);  // load_map must clear it
    CHECK(load_map(old.data(), bytes.size(), &v) == Status::VersionMismatch);
    CHECK(v.instances == nullptr);
  }
  // A current map relabelled as an older version (header CRC re-sealed): the version decides, not the CRC.
  SmallMap sm;
  const size_t size = map_serialized_size(sm.view);
  for (uint32_t version : {1u, 2u, 3u, 4u, 5u}) {
    Blob b(size);
    REQUIRE(write_map(sm.view, b.data(), size, nullptr) == Status::Ok);
    reseal_header(b.data(), [&](MapHeader* h) { h->version = version; });
    INFO("version " << version);
    CHECK(load_map(b.data(), size, &v) == Status::VersionMismatch);
  }
}

TEST_CASE("A bad georeference is refused: on write InvalidArgument, on load CorruptData even with a valid CRC") {
  struct Bad {
    const char* what;
    void (*edit)(MapGeoreference*);
  };
  const Bad bad[] = {
      {"empty frame name", [](MapGeoreference* g) { std::memset(g->frame, 0, sizeof(g->frame)); }},
      {"no terminating NUL", [](MapGeoreference* g) { std::memset(g->frame, 'a', sizeof(g->frame)); }},
      {"control character", [](MapGeoreference* g) { g->frame[2] = '\n'; }},
      {"byte above ASCII", [](MapGeoreference* g) { g->frame[0] = static_cast<char>(0xC3); }},
      {"bytes after the NUL", [](MapGeoreference* g) { g->frame[20] = 'x'; }},
      {"NaN origin", [](MapGeoreference* g) { g->origin[1] = std::numeric_limits<double>::quiet_NaN(); }},
      {"infinite origin", [](MapGeoreference* g) { g->origin[2] = -std::numeric_limits<double>::infinity(); }},
  };
  SmallMap sm;
  const size_t size = map_serialized_size(sm.view);
  for (const Bad& b : bad) {
    INFO(b.what);
    SmallMap m;
    b.edit(&m.view.georef);
    CHECK_FALSE(valid_georeference(m.view.georef));
    Blob out(size);
    CHECK(write_map(m.view, out.data(), size, nullptr) == Status::InvalidArgument);
    Blob blob(size);
    REQUIRE(write_map(sm.view, blob.data(), size, nullptr) == Status::Ok);
    reseal_header(blob.data(), [&](MapHeader* h) { b.edit(&h->georef); });
    MapView v;
    CHECK(load_map(blob.data(), size, &v) == Status::CorruptData);
  }
  // The longest name that fits (31 characters) is accepted; one more is not, and leaves the name as it was.
  MapGeoreference g = local_georeference();
  CHECK(set_frame_name(&g, "0123456789012345678901234567890"));
  CHECK(valid_georeference(g));
  CHECK_FALSE(set_frame_name(&g, "01234567890123456789012345678901"));
  CHECK_FALSE(set_frame_name(&g, ""));
  CHECK_FALSE(set_frame_name(&g, "tab\there"));
  CHECK(std::string(g.frame) == "0123456789012345678901234567890");
}

TEST_CASE("Map-local and map-frame poses differ by the origin, added and removed in double") {
  MapGeoreference g = local_georeference();
  g.origin[0] = 512345.0;
  g.origin[1] = 5412343.0;
  g.origin[2] = 2.0;
  Eigen::Isometry3d local = Eigen::Isometry3d::Identity();
  local.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  local.translation() = Eigen::Vector3d(123.456789012345, -45.678901234567, 0.123456789);
  const Eigen::Isometry3d frame = to_map_frame(g, local);
  CHECK(frame.linear() == local.linear());  // a translation only
  CHECK(frame.translation().x() == 512345.0 + 123.456789012345);
  CHECK(frame.translation().y() == 5412343.0 + -45.678901234567);
  // frame -> local -> frame is exact (the subtraction near the origin is).
  const Eigen::Isometry3d back = to_map_frame(g, to_map_local(g, frame));
  CHECK(back.matrix() == frame.matrix());
  CHECK((to_map_local(g, frame).translation() - local.translation()).norm() < 1e-9);
}

TEST_CASE("The fuzz seed map is the current format's (GSF_WRITE_SEED=1 rewrites it)") {
  size_t bytes = 0;
  const std::vector<uint64_t> seed = gsf_test::fuzz_seed_map(&bytes);
  MapView v;
  REQUIRE(load_map(seed.data(), bytes, &v) == Status::Ok);
  CHECK(std::string(v.georef.frame) == "utm-32N");
  const std::string path = std::string(GSF_SOURCE_DIR) + "/fuzz/corpus/fuzz_map_loader/tiny_valid.gsfmap";
  if (std::getenv("GSF_WRITE_SEED")) {
    FILE* f = std::fopen(path.c_str(), "wb");
    REQUIRE(f != nullptr);
    std::fwrite(seed.data(), 1, bytes, f);
    std::fclose(f);
  }
  const std::vector<uint8_t> file = read_file(path);
  REQUIRE(file.size() == bytes);
  CHECK(std::memcmp(file.data(), seed.data(), bytes) == 0);
}

}  // namespace test_map_format
