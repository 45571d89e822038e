// The metric-semantic layer alone: exact per-voxel means, first-insertion order, softmax averaging,
// rejection and counting of bad points, statuses, capacity overflow (voxels and gather columns),
// gather_within against brute force, bitwise determinism.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "arena_buffer.h"
#include "gsf/detail/voxel_layer.h"
#include "test_cloud.h"

namespace test_voxel_layer {

using namespace gsf;
using gsf_test::ArenaBuffer;

namespace {

using Cloud = gsf_test::Cloud;

// A cluttered street: ground, poles, a wall, random clutter; mixed labels.
Cloud street(uint32_t seed) {
  Cloud c;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (float x = -25; x <= 25; x += 0.35f)
    for (float y = -12; y <= 12; y += 0.35f) c.add(x, y, -1.7f + 0.05f * u(rng), std::fabs(y) < 4 ? 40u : 48u);
  for (int p = 0; p < 6; ++p)
    for (int k = 0; k < 150; ++k) {
      const float a = 6.2831853f * u(rng);
      c.add(-20 + 8 * p + 0.1f * std::cos(a), 6 + 0.1f * std::sin(a), -1.5f + 6 * u(rng), 80u);
    }
  for (int k = 0; k < 3000; ++k) c.add(-20 + 40 * u(rng), -11, -1.7f + 5 * u(rng), 50u);
  const uint32_t clutter[] = {10u, 70u, 71u, 72u, 81u};
  for (int k = 0; k < 2000; ++k) c.add(-25 + 50 * u(rng), -12 + 24 * u(rng), -1.7f + 4 * u(rng), clutter[k % 5]);
  return c;
}

std::vector<uint32_t> brute_gather(const VoxelLayer& l, const float c[3], float r, bool horizontal) {
  std::vector<uint32_t> ids;
  for (uint32_t i = 0; i < l.size(); ++i) {
    const float* p = l.voxel(i).centroid;
    const float dx = p[0] - c[0], dy = p[1] - c[1], dz = horizontal ? 0.0f : p[2] - c[2];
    if (dx * dx + dy * dy + dz * dz <= r * r) ids.push_back(i);
  }
  return ids;
}

}  // namespace

TEST_CASE("required_bytes is what bind takes; bind validates the config and the buffer") {
  VoxelConfig vc;
  vc.max_voxels = 1000;
  vc.max_columns = 200;
  const size_t need = VoxelLayer::required_bytes(vc);
  CHECK(need > 1000 * sizeof(Voxel));
  {
    ArenaBuffer buf(need);
    Arena exact(buf.words.data(), need);
    VoxelLayer l;
    CHECK(l.bind(exact, vc) == Status::Ok);
    CHECK(exact.used() == need);
  }
  {
    ArenaBuffer buf(need);
    Arena short_arena(buf.words.data(), need - 1);
    VoxelLayer l;
    CHECK(l.bind(short_arena, vc) == Status::BufferTooSmall);
    Cloud c;
    c.add(5, 0, 0, 80);
    CHECK(l.build(c.view(), nullptr) == Status::NotInitialized);
    CHECK(l.size() == 0);
  }
  ArenaBuffer buf(need);
  VoxelLayer l;
  VoxelConfig bad = vc;
  bad.voxel_size = 0.0f;
  CHECK(l.bind(buf.arena, bad) == Status::InvalidArgument);
  bad = vc;
  bad.voxel_size = std::nanf("");
  CHECK(l.bind(buf.arena, bad) == Status::InvalidArgument);
  bad = vc;
  bad.column_size = 0.2f;  // smaller than a voxel
  CHECK(l.bind(buf.arena, bad) == Status::InvalidArgument);
  bad = vc;
  bad.max_voxels = 0;
  CHECK(l.bind(buf.arena, bad) == Status::InvalidArgument);
  bad = vc;
  bad.max_range = bad.min_range;
  CHECK(l.bind(buf.arena, bad) == Status::InvalidArgument);
  CHECK(buf.arena.used() == 0);  // rejected configs take no memory
}

TEST_CASE("Each voxel is the exact mean of its points, in order of first insertion") {
  VoxelConfig vc;
  vc.voxel_size = 0.5f;
  ArenaBuffer buf(VoxelLayer::required_bytes(vc));
  VoxelLayer l;
  REQUIRE(l.bind(buf.arena, vc) == Status::Ok);
  Cloud c;
  c.add(10.1f, 3.2f, 0.1f, 72);              // voxel 0: terrain, cell (20, 6, 0)
  c.add(5.1f, 0.1f, 0.1f, 80);               // voxel 1: cell (10, 0, 0)
  c.add(5.3f, 0.2f, 0.3f, 80 | (7u << 16));  // instance bits do not change the class
  c.add(5.4f, 0.4f, 0.2f, 80);
  c.add(5.2f, 0.3f, 0.4f, 40);  // one road point among three pole points
  c.add(10.4f, 3.4f, 0.4f, 72);
  c.add(-5.1f, -0.1f, -0.1f, 10);  // voxel 2: negative coordinates, cell (-11, -1, -1)
  VoxelStats st;
  REQUIRE(l.build(c.view(), &st) == Status::Ok);
  REQUIRE(l.size() == 3);
  CHECK(st.voxels == 3);
  CHECK(st.points_in == 7);

  const Voxel& a = l.voxel(0);
  CHECK(a.count == 2);
  CHECK(a.centroid[0] == Approx(10.25f).margin(1e-5));
  CHECK(a.centroid[1] == Approx(3.3f).margin(1e-5));
  CHECK(a.centroid[2] == Approx(0.25f).margin(1e-5));
  CHECK(a.label == kTerrain);
  CHECK(a.prob[kTerrain] == 1.0f);

  const Voxel& b = l.voxel(1);
  CHECK(b.count == 4);
  CHECK(b.centroid[0] == Approx(5.25f).margin(1e-5));
  CHECK(b.centroid[1] == Approx(0.25f).margin(1e-5));
  CHECK(b.centroid[2] == Approx(0.25f).margin(1e-5));
  CHECK(b.label == kPole);
  CHECK(b.prob[kPole] == Approx(0.75f));
  CHECK(b.prob[kRoad] == Approx(0.25f));
  float sum = 0.0f;
  for (int k = 0; k < kNumClasses; ++k) sum += b.prob[k];
  CHECK(sum == Approx(1.0f));

  const Voxel& d = l.voxel(2);
  CHECK(d.count == 1);
  CHECK(d.label == kCar);
  CHECK(d.centroid[0] == -5.1f);

  // Lookups agree with the dense array.
  const float q[3] = {5.45f, 0.05f, 0.45f}, miss[3] = {0.0f, 20.0f, 0.0f};
  CHECK(l.find(q) == 1);
  CHECK(l.find(miss) == UINT32_MAX);
  int32_t cell[3];
  REQUIRE(l.cell_of(c.pts.data() + 4 * 6, cell));
  CHECK((cell[0] == -11 && cell[1] == -1 && cell[2] == -1));
  CHECK(l.find_cell(-11, -1, -1) == 2);
}

TEST_CASE("With logits, a voxel holds the mean softmax and its label is the argmax of that mean") {
  VoxelConfig vc;
  ArenaBuffer buf(VoxelLayer::required_bytes(vc));
  VoxelLayer l;
  REQUIRE(l.bind(buf.arena, vc) == Status::Ok);
  Cloud c;
  // Two points lean to pole (51/49 against car), one is confidently car: the hard-label majority is pole,
  // the mean probability is car.
  const double lean = std::log(51.0 / 49.0);
  auto add_logits = [&](float pole, float car) {
    c.logits.resize(c.logits.size() + kNumClasses, -30.0f);
    float* l0 = c.logits.data() + c.logits.size() - kNumClasses;
    l0[kPole] = pole;
    l0[kCar] = car;
  };
  // All in voxel cell (12, 0, 0) = [4.8, 5.2) x [0, 0.4)^2.
  c.add(4.85f, 0.05f, 0.05f, 80);
  add_logits(static_cast<float>(lean), 0.0f);
  c.add(4.90f, 0.10f, 0.10f, 80);
  add_logits(static_cast<float>(lean), 0.0f);
  c.add(4.95f, 0.15f, 0.15f, 10);
  add_logits(0.0f, static_cast<float>(std::log(99.0)));
  c.add(5.00f, 0.20f, 0.20f, 80);
  add_logits(std::nanf(""), 0.0f);  // non-finite logits: rejected
  c.add(5.05f, 0.25f, 0.25f, 0);
  add_logits(0.0f, 9.0f);  // unlabeled: ignored despite logits
  VoxelStats st;
  REQUIRE(l.build(c.view(), &st) == Status::Ok);
  CHECK(st.non_finite == 1);
  CHECK(st.ignored == 1);
  REQUIRE(l.size() == 1);
  const Voxel& v = l.voxel(0);
  CHECK(v.count == 3);
  // Closed form: (0.51 + 0.51 + 0.01) / 3 for pole, (0.49 + 0.49 + 0.99) / 3 for car (others ~e-13).
  CHECK(v.prob[kPole] == Approx(1.03 / 3).epsilon(1e-5));
  CHECK(v.prob[kCar] == Approx(1.97 / 3).epsilon(1e-5));
  CHECK(v.label == kCar);

  // The same points without logits: one-hot, majority pole.
  Cloud hard = c;
  hard.logits.clear();
  REQUIRE(l.build(hard.view(), nullptr) == Status::Ok);
  CHECK(l.voxel(0).label == kPole);
  CHECK(l.voxel(0).prob[kPole] == Approx(0.75f));  // the NaN-logit point counts when logits are absent

  ScanView wrong_dim = c.view();
  wrong_dim.logit_dim = 20;
  CHECK(l.build(wrong_dim, nullptr) == Status::InvalidArgument);
  CHECK(l.size() == 0);
}

TEST_CASE("Bad points are counted and skipped; statuses for unusable scans") {
  VoxelConfig vc;  // min_range 2.5, max_range 80
  ArenaBuffer buf(VoxelLayer::required_bytes(vc));
  VoxelLayer l;
  REQUIRE(l.bind(buf.arena, vc) == Status::Ok);
  Cloud c;
  c.add(2.5f, 0, 0, 80);   // exactly at min_range: kept
  c.add(2.49f, 0, 0, 80);  // inside: gated
  c.add(0, 0, 79.9f, 80);  // kept
  c.add(0, 80.1f, 0, 80);  // beyond: gated
  c.add(1e30f, 0, 0, 80);  // finite but absurd: gated, no overflow
  c.add(std::nanf(""), 5, 0, 80);
  c.add(5, INFINITY, 0, 80);
  c.add(5, 0, -INFINITY, 80);
  c.add(6, 0, 0, 12345);  // not a SemanticKITTI id
  c.add(7, 0, 0, 0);      // unlabeled
  c.add(8, 0, 0, 1);      // outlier
  c.add(9, 0, 0, 52);     // other-structure
  c.add(10, 0, 0, 99);    // other-object
  VoxelStats st;
  REQUIRE(l.build(c.view(), &st) == Status::Ok);
  CHECK(st.points_in == 13);
  CHECK(st.non_finite == 3);
  CHECK(st.out_of_range == 3);
  CHECK(st.unknown_label == 1);
  CHECK(st.ignored == 4);
  CHECK(st.dropped_points == 0);
  CHECK(l.size() == 2);

  Cloud empty;
  CHECK(l.build(empty.view(), &st) == Status::InvalidInput);
  CHECK(st.points_in == 0);
  CHECK(l.size() == 0);
  Cloud unusable;
  unusable.add(std::nanf(""), 0, 0, 80);
  unusable.add(1, 0, 0, 80);
  unusable.add(20, 0, 0, 0);
  CHECK(l.build(unusable.view(), &st) == Status::InvalidInput);
  CHECK((st.non_finite == 1 && st.out_of_range == 1 && st.ignored == 1));
  CHECK(l.size() == 0);
  const float probe[3] = {10, 0, 0};
  uint32_t out[4], total = 7;
  CHECK(l.gather_within(probe, 100.0f, false, out, 4, &total) == 0);  // empty layer, nothing stale
  CHECK(total == 0);

  ScanView v = c.view();
  v.points = nullptr;
  CHECK(l.build(v, nullptr) == Status::InvalidArgument);
  v = c.view();
  v.labels = nullptr;
  CHECK(l.build(v, nullptr) == Status::InvalidArgument);
  v = c.view();
  v.stride = 2;
  CHECK(l.build(v, nullptr) == Status::InvalidArgument);
  // Stride > 4: only x, y, z are read.
  std::vector<float> wide;
  for (uint32_t i = 0; i < c.labels.size(); ++i)
    wide.insert(wide.end(), {c.pts[4 * i], c.pts[4 * i + 1], c.pts[4 * i + 2], 0, 0, 0});
  v = c.view();
  v.points = wide.data();
  v.stride = 6;
  REQUIRE(l.build(v, &st) == Status::Ok);
  CHECK(l.size() == 2);
  CHECK(st.non_finite == 3);
}

TEST_CASE("Voxel capacity: the first max_voxels cells are kept, later new cells dropped, layer reusable") {
  VoxelConfig vc;
  vc.voxel_size = 0.5f;
  vc.max_voxels = 10;
  ArenaBuffer buf(VoxelLayer::required_bytes(vc));
  VoxelLayer l;
  REQUIRE(l.bind(buf.arena, vc) == Status::Ok);
  Cloud c;
  for (int i = 0; i < 20; ++i) {  // 20 cells along x, two points each
    c.add(5.1f + 0.5f * i, 0.1f, 0.1f, 80);
    c.add(5.2f + 0.5f * i, 0.2f, 0.2f, 80);
  }
  for (int i = 0; i < 20; ++i) c.add(5.3f + 0.5f * i, 0.3f, 0.3f, 72);  // a third point in every cell
  VoxelStats st;
  REQUIRE(l.build(c.view(), &st) == Status::CapacityExceeded);
  REQUIRE(l.size() == 10);
  CHECK(st.voxels == 10);
  CHECK(st.dropped_points == 10 * 2 + 10);
  for (uint32_t i = 0; i < 10; ++i) {
    CHECK(l.voxel(i).count == 3);  // points of existing cells still accumulate after the overflow
    CHECK(l.voxel(i).centroid[0] == Approx(5.2f + 0.5f * i).margin(1e-5));
    CHECK(l.voxel(i).label == kPole);
  }
  const std::vector<Voxel> first(l.voxels(), l.voxels() + l.size());
  REQUIRE(l.build(c.view(), nullptr) == Status::CapacityExceeded);
  CHECK(std::memcmp(first.data(), l.voxels(), sizeof(Voxel) * first.size()) == 0);
  // The gather index covers the kept voxels.
  const float center[3] = {7.0f, 0.0f, 0.0f};
  uint32_t out[20];
  CHECK(l.gather_within(center, 100.0f, false, out, 20) == 10);

  Cloud small;
  for (int i = 0; i < 4; ++i) small.add(-5.1f - 0.5f * i, 0.1f, 0.1f, 10);
  REQUIRE(l.build(small.view(), &st) == Status::Ok);
  CHECK(l.size() == 4);
  CHECK(st.dropped_points == 0);
  CHECK(l.voxel(0).label == kCar);
}

TEST_CASE("Gather-index column overflow is reported; the indexed voxels are still gathered exactly") {
  VoxelConfig vc;
  vc.max_columns = 3;
  ArenaBuffer buf(VoxelLayer::required_bytes(vc));
  VoxelLayer l;
  REQUIRE(l.bind(buf.arena, vc) == Status::Ok);
  Cloud c;
  for (int i = 0; i < 6; ++i) {  // six 2 m columns along x, two voxels each
    c.add(4.5f + 2 * i, 0.5f, 0.1f, 80);
    c.add(4.5f + 2 * i, 0.5f, 1.1f, 80);
  }
  VoxelStats st;
  CHECK(l.build(c.view(), &st) == Status::CapacityExceeded);
  CHECK(l.size() == 12);  // all voxels are in the layer
  CHECK(st.dropped_points == 0);
  CHECK(st.unindexed_voxels == 6);  // the last three columns are not searchable
  const float center[3] = {10.0f, 0.0f, 0.0f};
  std::vector<uint32_t> out(12);
  const uint32_t n = l.gather_within(center, 100.0f, true, out.data(), 12);
  out.resize(n);
  std::sort(out.begin(), out.end());
  CHECK(out == std::vector<uint32_t>({0, 1, 2, 3, 4, 5}));  // first-inserted columns got the slots
}

TEST_CASE("gather_within returns exactly the brute-force set; truncation keeps the order's prefix") {
  VoxelConfig vc;
  ArenaBuffer buf(VoxelLayer::required_bytes(vc));
  VoxelLayer l;
  REQUIRE(l.bind(buf.arena, vc) == Status::Ok);
  const Cloud c = street(11);
  REQUIRE(l.build(c.view(), nullptr) == Status::Ok);
  REQUIRE(l.size() > 5000);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<uint32_t> got(l.size()), part(l.size());
  uint32_t nonempty = 0;
  for (int t = 0; t < 120; ++t) {
    // Centres inside and beyond the scene, radii from sub-voxel to larger than the scene.
    const float center[3] = {-40 + 80 * u(rng), -25 + 50 * u(rng), -3 + 8 * u(rng)};
    const float radius = t % 10 == 0 ? 60.0f : 0.3f + 11.7f * u(rng);
    const bool horizontal = t % 2 == 0;
    uint32_t total = 0;
    const uint32_t n = l.gather_within(center, radius, horizontal, got.data(), l.size(), &total);
    REQUIRE(n == total);
    std::vector<uint32_t> sorted(got.begin(), got.begin() + n);
    std::sort(sorted.begin(), sorted.end());
    REQUIRE(std::adjacent_find(sorted.begin(), sorted.end()) == sorted.end());  // no duplicates
    REQUIRE(sorted == brute_gather(l, center, radius, horizontal));
    nonempty += n > 0;
    if (n >= 4) {
      const uint32_t k = n / 2;
      uint32_t total2 = 0;
      CHECK(l.gather_within(center, radius, horizontal, part.data(), k, &total2) == k);
      CHECK(total2 == n);
      CHECK(std::equal(part.begin(), part.begin() + k, got.begin()));
    }
  }
  CHECK(nonempty > 60);
  // Degenerate queries.
  const float mid[3] = {0, 0, 0}, nan_c[3] = {std::nanf(""), 0, 0};
  CHECK(l.gather_within(mid, 0.0f, false, got.data(), l.size()) == 0);
  CHECK(l.gather_within(mid, -1.0f, false, got.data(), l.size()) == 0);
  CHECK(l.gather_within(mid, std::nanf(""), false, got.data(), l.size()) == 0);
  CHECK(l.gather_within(nan_c, 10.0f, false, got.data(), l.size()) == 0);
  CHECK(l.gather_within(mid, 1e30f, false, got.data(), l.size()) == l.size());  // clipped, not 1e29^2 cells
  CHECK(l.gather_within(mid, INFINITY, true, got.data(), l.size()) == l.size());
  const float far_away[3] = {1e6f, -1e6f, 0};
  CHECK(l.gather_within(far_away, 50.0f, false, got.data(), l.size()) == 0);
}

TEST_CASE("The same scan twice gives bitwise identical layers, whatever the arena address") {
  VoxelConfig vc;
  ArenaBuffer b1(VoxelLayer::required_bytes(vc) + 64), b2(VoxelLayer::required_bytes(vc));
  b1.arena.allocate_bytes(48, 16);  // shift the second layer's memory
  VoxelLayer l1, l2;
  REQUIRE(l1.bind(b1.arena, vc) == Status::Ok);
  REQUIRE(l2.bind(b2.arena, vc) == Status::Ok);
  Cloud c = street(23);
  std::mt19937 rng(9);
  std::normal_distribution<float> n(0.0f, 2.0f);
  c.logits.resize(c.labels.size() * kNumClasses);
  for (float& x : c.logits) x = n(rng);
  VoxelStats s1, s2;
  REQUIRE(l1.build(c.view(), &s1) == Status::Ok);
  REQUIRE(l2.build(street(1).view(), nullptr) == Status::Ok);  // different history
  REQUIRE(l2.build(c.view(), &s2) == Status::Ok);
  REQUIRE(l1.size() == l2.size());
  CHECK(std::memcmp(l1.voxels(), l2.voxels(), sizeof(Voxel) * l1.size()) == 0);
  CHECK(std::memcmp(&s1, &s2, sizeof(VoxelStats)) == 0);
  std::vector<uint32_t> g1(l1.size()), g2(l2.size());
  const float center[3] = {1.0f, 2.0f, 0.0f};
  const uint32_t n1 = l1.gather_within(center, 9.0f, true, g1.data(), l1.size());
  const uint32_t n2 = l2.gather_within(center, 9.0f, true, g2.data(), l2.size());
  REQUIRE(n1 == n2);
  CHECK(std::equal(g1.begin(), g1.begin() + n1, g2.begin()));  // same order, not just the same set
}

TEST_CASE("Without the gather index the voxels are the same bits and gather_within matches nothing") {
  VoxelConfig vc;
  ArenaBuffer b1(VoxelLayer::required_bytes(vc)), b2(VoxelLayer::required_bytes(vc));
  VoxelLayer with, without;
  REQUIRE(with.bind(b1.arena, vc) == Status::Ok);
  REQUIRE(without.bind(b2.arena, vc) == Status::Ok);
  const Cloud c = street(17);
  VoxelStats s1, s2;
  REQUIRE(with.build(c.view(), &s1) == Status::Ok);
  REQUIRE(without.build(street(3).view(), nullptr) == Status::Ok);  // an indexed layer before
  REQUIRE(without.build(c.view(), &s2, false) == Status::Ok);
  REQUIRE(with.size() == without.size());
  CHECK(std::memcmp(with.voxels(), without.voxels(), sizeof(Voxel) * with.size()) == 0);
  CHECK(s2.unindexed_voxels == 0);
  std::vector<uint32_t> out(with.size());
  const float center[3] = {0.0f, 0.0f, 0.0f};
  CHECK(with.gather_within(center, 20.0f, true, out.data(), with.size()) > 100);
  CHECK(without.gather_within(center, 20.0f, true, out.data(), without.size()) == 0);  // nothing stale
  CHECK(without.gather_within(center, INFINITY, false, out.data(), without.size()) == 0);
}

TEST_CASE("prob_samples: the softmax of a voxel's first k points, then of every 2nd, 4th, ... point") {
  // The documented rule, written out: the point finding n points in its voxel adds its softmax when
  // n < k or n is a multiple of 2^bit_width(n / k).
  auto takes = [](uint32_t n, uint32_t k) {
    if (k == 0 || n < k) return true;
    uint32_t width = 0;
    for (uint32_t q = n / k; q; q >>= 1) ++width;
    return n % (1u << width) == 0;
  };
  for (uint32_t k : {0u, 1u, 3u, 4u, 16u, 17u})
    for (uint32_t n = 0; n < 3000; ++n) {
      uint32_t brute = 0;
      for (uint32_t j = 0; j < n; ++j) brute += takes(j, k) ? 1 : 0;
      REQUIRE(VoxelLayer::samples_of(n, k) == brute);
    }
  CHECK(VoxelLayer::samples_of(40, 4) == 11);                   // 0 1 2 3 | 4 6 | 8 12 | 16 24 | 32
  CHECK(VoxelLayer::samples_of(UINT32_MAX, 16) < 16 + 8 * 32);  // logarithmic in the count

  // One voxel of 40 points: even points are confidently pole, odd ones car. With k = 4 the samples are
  // 0 1 2 3 4 6 8 12 16 24 32: nine poles and two cars; position and count still take every point.
  Cloud c;
  for (int j = 0; j < 40; ++j) {
    c.add(4.81f + 0.009f * j, 0.05f, 0.05f + 0.005f * j, 80);
    c.logits.resize(c.logits.size() + kNumClasses, -30.0f);
    c.logits[c.logits.size() - kNumClasses + (j % 2 ? kCar : kPole)] = 30.0f;
  }
  VoxelConfig exact_cfg, thin_cfg;
  exact_cfg.prob_samples = 0;
  thin_cfg.prob_samples = 4;
  ArenaBuffer b1(VoxelLayer::required_bytes(exact_cfg)), b2(VoxelLayer::required_bytes(thin_cfg));
  VoxelLayer exact, thin;
  REQUIRE(exact.bind(b1.arena, exact_cfg) == Status::Ok);
  REQUIRE(thin.bind(b2.arena, thin_cfg) == Status::Ok);
  VoxelStats se, st;
  REQUIRE(exact.build(c.view(), &se) == Status::Ok);
  REQUIRE(thin.build(c.view(), &st) == Status::Ok);
  REQUIRE(exact.size() == 1);
  REQUIRE(thin.size() == 1);
  CHECK(se.unsampled_points == 0);
  CHECK(st.unsampled_points == 40 - 11);
  CHECK(exact.voxel(0).prob[kPole] == Approx(0.5f).epsilon(1e-5));
  CHECK(thin.voxel(0).prob[kPole] == Approx(9.0f / 11.0f).epsilon(1e-5));
  CHECK(thin.voxel(0).prob[kCar] == Approx(2.0f / 11.0f).epsilon(1e-5));
  CHECK(thin.voxel(0).count == 40);
  CHECK(std::memcmp(thin.voxel(0).centroid, exact.voxel(0).centroid, sizeof(float) * 3) == 0);
  CHECK(thin.voxel(0).label == kPole);

  // Without logits every point adds its one-hot label whatever prob_samples says.
  Cloud hard = c;
  hard.logits.clear();
  REQUIRE(thin.build(hard.view(), &st) == Status::Ok);
  CHECK(st.unsampled_points == 0);
  CHECK(thin.voxel(0).prob[kPole] == Approx(1.0f));  // every label is pole
}

TEST_CASE("prob_samples at or above every voxel's count is bitwise the exact layer; below, only probabilities move") {
  Cloud c = street(31);
  std::mt19937 rng(4);
  std::normal_distribution<float> n(0.0f, 2.0f);
  c.logits.resize(c.labels.size() * kNumClasses);
  for (float& x : c.logits) x = n(rng);
  VoxelConfig exact_cfg;
  exact_cfg.prob_samples = 0;
  ArenaBuffer b0(VoxelLayer::required_bytes(exact_cfg));
  VoxelLayer exact;
  REQUIRE(exact.bind(b0.arena, exact_cfg) == Status::Ok);
  REQUIRE(exact.build(c.view(), nullptr) == Status::Ok);
  uint32_t most = 0;
  for (uint32_t i = 0; i < exact.size(); ++i) most = std::max(most, exact.voxel(i).count);
  REQUIRE(most > 4);
  for (uint32_t k : {most, 3u, 1u}) {
    VoxelConfig vc;
    vc.prob_samples = k;
    ArenaBuffer b(VoxelLayer::required_bytes(vc));
    VoxelLayer l;
    REQUIRE(l.bind(b.arena, vc) == Status::Ok);
    VoxelStats st;
    REQUIRE(l.build(c.view(), &st) == Status::Ok);
    REQUIRE(l.size() == exact.size());
    uint64_t unsampled = 0;
    for (uint32_t i = 0; i < l.size(); ++i) {
      const Voxel &a = l.voxel(i), &e = exact.voxel(i);
      CHECK(std::memcmp(a.centroid, e.centroid, sizeof a.centroid) == 0);
      CHECK(a.count == e.count);
      unsampled += a.count - VoxelLayer::samples_of(a.count, k);
      float sum = 0.0f;
      for (int j = 0; j < kNumClasses; ++j) sum += a.prob[j];
      CHECK(sum == Approx(1.0f).epsilon(1e-4));
    }
    CHECK(st.unsampled_points == unsampled);
    if (k == most) {
      CHECK(st.unsampled_points == 0);
      CHECK(std::memcmp(l.voxels(), exact.voxels(), sizeof(Voxel) * l.size()) == 0);
    } else {
      CHECK(st.unsampled_points > 0);
    }
  }
}

}  // namespace test_voxel_layer
