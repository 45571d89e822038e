// Map blob: round trip, and every single-byte corruption or truncation is rejected (never a crash).
#include <catch2/catch.hpp>

#include <cstring>
#include <vector>

#include "gsf/crc32.h"
#include "gsf/map_format.h"
#include "gsf/semantic_classes.h"

using namespace gsf;

namespace {

struct SmallMap {
  std::vector<MapInstance> instances;
  std::vector<float> inputs, alpha, mean, var, refine;
  std::vector<MapTriangle> tris;
  std::vector<uint64_t> keys;
  std::vector<uint32_t> offsets, entries;
  MapView view;

  SmallMap() {
    MapParams& p = view.params;
    std::memset(&p, 0, sizeof(p));
    p.num_classes = kNumClasses;
    p.instance_class_mask = kDefaultInstanceClasses;
    p.field_input_dims = 2;
    p.inducing_stride = 4;
    p.grid_nx = 2; p.grid_ny = 2; p.grid_layers = 1;
    p.triangle_neighbours = 10;
    p.grid_spacing = 1.5f; p.layer_spacing = 1.0f; p.grid_z0 = 0.0f;
    p.length_scale = 2.0f; p.signal_variance = 1.0f; p.noise_variance = 0.05f;
    p.field_radius = 8.0f; p.voxel_size = 0.4f; p.side_bin = 1.0f; p.min_side = 0.5f; p.max_side = 50.0f;
    const uint32_t n = 4, g = 4, d = kNumClasses;
    for (uint32_t i = 0; i < n; ++i) {
      MapInstance in;
      std::memset(&in, 0, sizeof(in));
      in.centroid[0] = float(i) * 3.0f; in.centroid[1] = float(i * i); in.centroid[2] = 1.0f;
      in.stability = 1.0f; in.inducing_count = 3; in.point_count = 10 + i; in.label = kPole;
      instances.push_back(in);
    }
    for (uint32_t i = 0; i < n * 4 * 3; ++i) inputs.push_back(0.1f * float(i % 17));
    for (uint32_t i = 0; i < n * 4 * d; ++i) alpha.push_back(0.01f * float(i % 13) - 0.05f);
    for (uint32_t i = 0; i < n * g * d; ++i) mean.push_back(0.02f * float(i % 11));
    for (uint32_t i = 0; i < n * g; ++i) var.push_back(0.5f + 0.01f * float(i));
    MapTriangle t;
    std::memset(&t, 0, sizeof(t));
    t.v[0] = 0; t.v[1] = 1; t.v[2] = 2; t.side[0] = 3.2f; t.side[1] = 5.8f; t.side[2] = 8.9f;
    for (int k = 0; k < 3; ++k) t.label[k] = kPole;
    tris.push_back(t);
    t.v[2] = 3; t.side[2] = 9.5f;
    tris.push_back(t);
    keys = {11, 42};
    offsets = {0, 1, 2};
    entries = {1, 0};
    refine = {1, 2, 3, 40, 4, 5, 6, 50};
    view.counts.instances = n;
    view.counts.triangles = 2;
    view.counts.index_keys = 2;
    view.counts.refine_points = 2;
    view.counts.road_length_m = 123.0f;
    view.instances = instances.data();
    view.field_inputs = inputs.data();
    view.field_alpha = alpha.data();
    view.grid_mean = mean.data();
    view.grid_var = var.data();
    view.triangles = tris.data();
    view.index_keys = keys.data();
    view.index_offsets = offsets.data();
    view.index_entries = entries.data();
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

bool same_map(const MapView& a, const MapView& b) {
  if (std::memcmp(&a.params, &b.params, sizeof(MapParams)) != 0) return false;
  if (std::memcmp(&a.counts, &b.counts, sizeof(MapCounts)) != 0) return false;
  const uint64_t n = a.counts.instances, g = a.grid_points(), d = a.params.num_classes, s = a.params.inducing_stride;
  return std::memcmp(a.instances, b.instances, n * sizeof(MapInstance)) == 0 &&
         std::memcmp(a.field_inputs, b.field_inputs, n * s * 3 * 4) == 0 &&
         std::memcmp(a.field_alpha, b.field_alpha, n * s * d * 4) == 0 &&
         std::memcmp(a.grid_mean, b.grid_mean, n * g * d * 4) == 0 &&
         std::memcmp(a.grid_var, b.grid_var, n * g * 4) == 0 &&
         std::memcmp(a.triangles, b.triangles, a.counts.triangles * sizeof(MapTriangle)) == 0 &&
         std::memcmp(a.index_keys, b.index_keys, a.counts.index_keys * 8) == 0 &&
         std::memcmp(a.index_offsets, b.index_offsets, (a.counts.index_keys + 1) * 4) == 0 &&
         std::memcmp(a.index_entries, b.index_entries, a.counts.triangles * 4) == 0 &&
         std::memcmp(a.refine_points, b.refine_points, a.counts.refine_points * 16) == 0;
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
  sm.alpha.resize(sm.view.counts.instances * 4 * (kNumClasses + 1));
  sm.mean.resize(sm.view.counts.instances * 4 * (kNumClasses + 1));
  sm.view.field_alpha = sm.alpha.data();
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

  SmallMap nan_map;
  nan_map.mean[5] = std::numeric_limits<float>::quiet_NaN();
  Blob b2(size);
  REQUIRE(write_map(nan_map.view, b2.data(), size, nullptr) == Status::Ok);
  CHECK(load_map(b2.data(), size, &v) == Status::CorruptData);

  SmallMap unsorted;
  unsorted.keys = {42, 11};
  unsorted.view.index_keys = unsorted.keys.data();
  Blob b3(size);
  REQUIRE(write_map(unsorted.view, b3.data(), size, nullptr) == Status::Ok);
  CHECK(load_map(b3.data(), size, &v) == Status::CorruptData);
}
