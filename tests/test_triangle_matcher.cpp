// The triangle matcher alone (core/include/gsf/detail/triangle_matcher.h) over a triangle index built
// from hand-made map triangles: ranking before the cap, vertex-order ties, mirror images refused.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

#include "arena_buffer.h"
#include "gsf/detail/rng.h"
#include "gsf/detail/triangle.h"
#include "gsf/detail/triangle_index.h"
#include "gsf/detail/triangle_matcher.h"
#include "gsf/map_format.h"
#include "gsf/position_prior.h"
#include "gsf/semantic_classes.h"

namespace test_triangle_matcher {

using namespace gsf;
using gsf_test::ArenaBuffer;

namespace {

// The map's triangles in key order (format v5) with their index; input(i) is the position in the
// builder's list of stored triangle i.
struct Index {
  std::vector<Triangle> tris;
  std::vector<uint64_t> keys, scratch;
  std::vector<uint32_t> offsets, ids;
  TriangleIndexView view;
  explicit Index(const std::vector<Triangle>& t, float bin) {
    const uint32_t n = static_cast<uint32_t>(t.size());
    tris.resize(n + 1);
    keys.resize(n + 1);
    scratch.resize(n + 1);
    offsets.resize(n + 2);
    ids.resize(n + 1);
    uint32_t kc = 0;
    REQUIRE(build_triangle_index(t.data(), n, bin, tris.data(), keys.data(), offsets.data(), &kc, scratch.data(),
                                 ids.data()) == Status::Ok);
    view.keys = keys.data();
    view.offsets = offsets.data();
    view.key_count = kc;
    view.triangle_count = n;
  }
  uint32_t input(uint32_t stored) const { return ids[stored]; }
};

Triangle triangle_with_sides(uint32_t id0, float s0, float s1, float s2) {
  Triangle t{};
  t.v[0] = id0;
  t.v[1] = id0 + 1;
  t.v[2] = id0 + 2;
  t.side[0] = s0;
  t.side[1] = s1;
  t.side[2] = s2;
  for (int k = 0; k < 3; ++k) t.label[k] = kPole;
  return t;
}

}  // namespace

TEST_CASE("Ranked matching keeps the best-fitting map triangle when a cap would have cut it in storage order") {
  // 300 map triangles in a lattice all fit the query within tolerance (1-2% off); the one exact copy is
  // stored last (map x order puts it at the end). A cap of 8 in storage order would drop it.
  std::vector<Triangle> map;
  for (uint32_t i = 0; i < 300; ++i) {
    const float e = 1.0f + 0.01f + 0.01f * float((i * 37) % 100) / 100.0f;
    map.push_back(triangle_with_sides(3 * i, 8.0f * e, 8.0f * 1.3f * e, 8.0f * 1.9f * e));
  }
  map.push_back(triangle_with_sides(900, 8.0f, 8.0f * 1.3f, 8.0f * 1.9f));
  Index idx(map, 1.0f);
  TriangleConfig tc;
  ArenaBuffer buf(TriangleMatcher::required_bytes(8));
  TriangleMatcher matcher;
  REQUIRE(matcher.bind(buf.arena, 8) == Status::Ok);
  const Triangle q = triangle_with_sides(0, 8.0f, 8.0f * 1.3f, 8.0f * 1.9f);
  const TriangleMatchStats st = matcher.match(q, idx.view, idx.tris.data(), tc, 0.0f);
  CHECK(st.accepted == 301);
  CHECK(st.kept == 8);
  CHECK(st.dropped() == 293);  // every drop is counted
  REQUIRE(matcher.size() == 8);
  CHECK(idx.input(matcher.match_at(0).map) == 300);  // the exact copy ranks first
  CHECK(matcher.match_at(0).residual == 0.0f);
  for (uint32_t i = 1; i < matcher.size(); ++i) CHECK(matcher.match_at(i - 1).residual <= matcher.match_at(i).residual);
}

TEST_CASE("Tied query sides are tried in both vertex orders") {
  // Isosceles map triangle: sides 5, 5.05, 8 (a lattice's right angles give such ties). The query's
  // noise put its two short sides the other way round, so its canonical order pairs the vertices
  // differently; only the tied order pairs them as the map does.
  std::vector<Triangle> map = {triangle_with_sides(0, 5.0f, 5.05f, 8.0f)};
  map[0].label[1] = kTrunk;  // labels (pole, trunk, pole), part of the key
  Index idx(map, 1.0f);
  TriangleConfig tc;
  ArenaBuffer buf(TriangleMatcher::required_bytes(16));
  TriangleMatcher matcher;
  REQUIRE(matcher.bind(buf.arena, 16) == Status::Ok);
  Triangle q = triangle_with_sides(10, 5.0f, 5.04f, 8.0f);  // canonical (a, b, c)
  q.label[0] = kPole;
  q.label[1] = kTrunk;
  q.label[2] = kPole;
  // Without ties only the canonical order is tried.
  TriangleMatchStats st = matcher.match(q, idx.view, idx.tris.data(), tc, 0.0f);
  CHECK(st.orders == 1);
  // With the tie tolerance the reversed order (c, b, a) with sides (5.04, 5, 8) is tried as well; both
  // pairings pass the 3% side check here and both are kept.
  st = matcher.match(q, idx.view, idx.tris.data(), tc, 0.06f);
  CHECK(st.orders == 2);
  REQUIRE(matcher.size() == 2);
  bool reversed = false;
  for (uint32_t i = 0; i < matcher.size(); ++i)
    if (matcher.match_at(i).order == 1) {
      reversed = true;
      CHECK(TriangleMatcher::query_vertex(q, 1, 0) == q.v[2]);
      CHECK(TriangleMatcher::query_vertex(q, 1, 2) == q.v[0]);
    }
  CHECK(reversed);
  // A scalene triangle gets no second order.
  const Triangle scalene = triangle_with_sides(20, 4.0f, 6.0f, 9.0f);
  CHECK(matcher.match(scalene, idx.view, idx.tris.data(), tc, 0.06f).orders == 1);
}

TEST_CASE("A mirror image has the same sides but the other sense: the matcher refuses it before the cap") {
  // Map: a scalene triangle A and its mirror image B (y -> -y, moved 50 m); same sides, opposite senses.
  std::vector<float> xyz = {0, 0, 0, 4, 0, 0, 1, 6, 0, 50, 0, 0, 54, 0, 0, 51, -6, 0};
  const std::vector<uint8_t> labels(16, kPole);
  std::vector<Triangle> map = {make_triangle(0, 1, 2, &xyz[0], &xyz[3], &xyz[6], labels.data()),
                               make_triangle(3, 4, 5, &xyz[9], &xyz[12], &xyz[15], labels.data())};
  REQUIRE(map[0].orientation != map[1].orientation);
  REQUIRE((map[0].orientation == kOrientationCounterClockwise || map[0].orientation == kOrientationClockwise));
  for (int k = 0; k < 3; ++k) REQUIRE(map[0].side[k] == Approx(map[1].side[k]));
  Index idx(map, 1.0f);
  const uint32_t id_a = idx.input(0) == 0 ? 0 : 1;  // stored position of A
  TriangleConfig tc;
  ArenaBuffer buf(TriangleMatcher::required_bytes(16));
  TriangleMatcher matcher;
  REQUIRE(matcher.bind(buf.arena, 16) == Status::Ok);
  // The query sees A turned by any yaw and moved: it matches A only; its mirror image matches B only.
  for (int deg = 0; deg < 360; deg += 15) {
    const float c = std::cos(float(deg) * 0.0174533f), s = std::sin(float(deg) * 0.0174533f);
    float q[9], m[9];
    for (int v = 0; v < 3; ++v) {
      const float x = xyz[3 * v], y = xyz[3 * v + 1];
      q[3 * v] = c * x - s * y + 7.0f;
      q[3 * v + 1] = s * x + c * y - 3.0f;
      m[3 * v] = c * x + s * y;  // the mirror image (y -> -y), turned
      m[3 * v + 1] = s * x - c * y;
      q[3 * v + 2] = m[3 * v + 2] = 0.2f;
    }
    INFO("yaw " << deg);
    const Triangle qt = make_triangle(10, 11, 12, q, q + 3, q + 6, labels.data());
    TriangleMatchStats st = matcher.match(qt, idx.view, idx.tris.data(), tc, 0.0f);
    CHECK(st.accepted == 1);
    CHECK(st.mirrored == 1);
    REQUIRE(matcher.size() == 1);
    CHECK(matcher.match_at(0).map == id_a);
    const Triangle mt = make_triangle(10, 11, 12, m, m + 3, m + 6, labels.data());
    st = matcher.match(mt, idx.view, idx.tris.data(), tc, 0.0f);
    CHECK(st.mirrored == 1);
    REQUIRE(matcher.size() == 1);
    CHECK(matcher.match_at(0).map == 1 - id_a);
    // Without the check both are candidates, as they were before senses were recorded.
    matcher.set_mirror_check(false);
    st = matcher.match(qt, idx.view, idx.tris.data(), tc, 0.0f);
    CHECK(st.accepted == 2);
    CHECK(st.mirrored == 0);
    matcher.set_mirror_check(true);
  }
  // A near-collinear triangle (apex 0.5 m off its longest side: flat) is never refused.
  const float flat[9] = {0, 0, 0, 10, 0, 0, 5, 0.5f, 0};
  CHECK(make_triangle(0, 1, 2, flat, flat + 3, flat + 6, labels.data()).orientation == kOrientationFlat);
  CHECK(triangle_orientation(flat, flat + 3, flat + 6, 10.0f) == kOrientationFlat);
  const float apex[9] = {0, 0, 0, 10, 0, 0, 5, 1.2f, 0};
  CHECK(triangle_orientation(apex, apex + 3, apex + 6, 10.0f) == kOrientationCounterClockwise);
  CHECK(triangle_orientation(apex, apex + 6, apex + 3, 10.0f) == kOrientationClockwise);
  // An isosceles triangle is its own mirror image up to a turn: its vertex order with the tied sides
  // swapped (an odd permutation) matches the mirror image with the senses agreeing.
  const float iso[9] = {0, 0, 0, 4, 0, 0, 2, 7, 0}, iso_m[9] = {0, 0, 0, 4, 0, 0, 2, -7, 0};
  std::vector<Triangle> iso_map = {make_triangle(0, 1, 2, iso, iso + 3, iso + 6, labels.data())};
  Index iso_idx(iso_map, 1.0f);
  const Triangle iq = make_triangle(10, 11, 12, iso_m, iso_m + 3, iso_m + 6, labels.data());
  TriangleMatchStats st = matcher.match(iq, iso_idx.view, iso_idx.tris.data(), tc, 0.06f);
  CHECK(st.orders == 2);
  CHECK(st.mirrored == 1);
  REQUIRE(matcher.size() == 1);
  const uint8_t o = matcher.match_at(0).order;
  CHECK((o >= 1 && o <= 3));
}

// The sparse rematch (localizer.cpp match_scan) compares accepted + outside with a threshold, so that a
// prior does not change whether it happens: a mirror twin outside the region must count as mirrored,
// as it does without a region, not as outside.
TEST_CASE(
    "With a prior's region, accepted + outside is what the scan finds without one; mirror twins count as mirrored") {
  // Map: triangle A and its mirror image B, 50 m apart.
  std::vector<float> xyz = {0, 0, 0, 4, 0, 0, 1, 6, 0, 50, 0, 0, 54, 0, 0, 51, -6, 0};
  const std::vector<uint8_t> labels(16, kPole);
  std::vector<Triangle> map = {make_triangle(0, 1, 2, &xyz[0], &xyz[3], &xyz[6], labels.data()),
                               make_triangle(3, 4, 5, &xyz[9], &xyz[12], &xyz[15], labels.data())};
  REQUIRE(map[0].orientation != map[1].orientation);
  Index idx(map, 1.0f);
  std::vector<MapInstance> instances(6);
  for (int i = 0; i < 6; ++i)
    for (int k = 0; k < 3; ++k) instances[i].centroid[k] = xyz[3 * i + k];
  const float query[9] = {0, 0, 0, 4, 0, 0, 1, 6, 0};  // A as the scan sees it, sensor at the origin
  const Triangle qt = make_triangle(0, 1, 2, query, query + 3, query + 6, labels.data());
  TriangleConfig tc;
  ArenaBuffer buf(TriangleMatcher::required_bytes(16));
  TriangleMatcher matcher;
  REQUIRE(matcher.bind(buf.arena, 16) == Status::Ok);
  const TriangleMatchStats free = matcher.match(qt, idx.view, idx.tris.data(), tc, 0.0f);
  REQUIRE(free.accepted == 1);
  REQUIRE(free.mirrored == 1);
  PriorRegion far_away;  // reaches neither triangle
  far_away.cx = 1000.0f;
  far_away.radius = 5.0f;
  PriorRegion near_b;  // reaches the mirror twin B only
  near_b.cx = 52.0f;
  near_b.radius = 1.0f;
  for (const PriorRegion* region : {&far_away, &near_b}) {
    matcher.set_region(region, instances.data(), query);
    const TriangleMatchStats st = matcher.match(qt, idx.view, idx.tris.data(), tc, 0.0f);
    CHECK(st.accepted + st.outside == free.accepted);
    CHECK(st.mirrored == free.mirrored);
    CHECK(matcher.outside_region() == st.outside);
  }
  matcher.set_region(nullptr, nullptr, nullptr);
}

// The matcher searches only the key bins a side within the tolerance can fall in (of the 27 around the
// query's): it must accept exactly the map triangles a scan of those 27 keys with the tolerance test
// accepts, also for sides just below, at and above a bin edge and at the sparse rematch's tolerance.
TEST_CASE("The matcher's searched bins lose no map triangle within the tolerance") {
  Rng rng(11);
  auto uniform = [&rng](float lo, float hi) { return lo + (hi - lo) * float(rng.next_u64() >> 40) / float(1 << 24); };
  auto edge_side = [&](float lo, float hi) {  // half the sides within 1 mm of a 1 m bin edge
    const float s = uniform(lo, hi);
    return rng.uniform(2) ? s : std::round(s) + uniform(-0.001f, 0.001f);
  };
  std::vector<Triangle> map;
  for (uint32_t i = 0; i < 3000; ++i)
    map.push_back(triangle_with_sides(3 * i, edge_side(2, 8), edge_side(8, 20), edge_side(20, 45)));
  const Index idx(map, 1.0f);
  const uint32_t n = static_cast<uint32_t>(map.size());
  ArenaBuffer buf(TriangleMatcher::required_bytes(n));
  TriangleMatcher matcher;
  REQUIRE(matcher.bind(buf.arena, n) == Status::Ok);
  uint32_t total = 0;
  for (float tolerance : {0.03f, 0.075f}) {
    TriangleConfig tc;
    tc.relative_side_tolerance = tolerance;
    for (int k = 0; k < 300; ++k) {
      const Triangle& near = idx.tris[rng.uniform(n)];
      const Triangle q =
          triangle_with_sides(0, near.side[0] * uniform(0.97f, 1.03f), near.side[1] * uniform(0.97f, 1.03f),
                              near.side[2] * uniform(0.97f, 1.03f));
      std::vector<uint32_t> expected;
      for (uint32_t m = 0; m < n; ++m) {
        bool ok = true;
        for (int s = 0; s < 3; ++s) {
          const float qs = q.side[s], ms = idx.tris[m].side[s];
          ok = ok && std::fabs(std::floor(qs) - std::floor(ms)) <= 1.0f && std::fabs(qs - ms) < tolerance * qs;
        }
        if (ok) expected.push_back(m);
      }
      const TriangleMatchStats st = matcher.match(q, idx.view, idx.tris.data(), tc, 0.0f);
      std::vector<uint32_t> got;
      for (uint32_t i = 0; i < matcher.size(); ++i) got.push_back(matcher.match_at(i).map);
      std::sort(got.begin(), got.end());
      CHECK(st.accepted == expected.size());
      CHECK(got == expected);
      total += static_cast<uint32_t>(expected.size());
    }
  }
  CHECK(total > 600);  // the queries do find matches (more than one a query)
}

}  // namespace test_triangle_matcher
