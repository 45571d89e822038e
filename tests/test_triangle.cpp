// Triangle descriptors alone (core/include/gsf/detail/triangle.h): the canonical vertex order and the
// permutation-invariant key, the builder (dedup, side range, rigid invariance, capacity), the turning
// sense (kept by a turn, reversed by a mirror image) and the vertex-set key.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <set>
#include <vector>

#include "arena_buffer.h"
#include "gsf/detail/triangle.h"
#include "gsf/semantic_classes.h"
#include "random_points.h"

namespace test_triangle {

using namespace gsf;
using gsf_test::random_points;
using gsf_test::some_pose;
using Buffer = gsf_test::ArenaBuffer;

TEST_CASE("Triangles: canonical order, permutation-invariant key") {
  const float p[9] = {0, 0, 0, 3, 0, 0, 0, 4, 0};  // sides 3, 4, 5
  const uint8_t labels[3] = {1, 2, 3};
  for (auto perm : {std::array<uint32_t, 3>{0, 1, 2}, {2, 0, 1}, {1, 2, 0}, {2, 1, 0}}) {
    const Triangle t =
        make_triangle(perm[0], perm[1], perm[2], p + 3 * perm[0], p + 3 * perm[1], p + 3 * perm[2], labels);
    CHECK(t.side[0] == Approx(3));
    CHECK(t.side[1] == Approx(4));
    CHECK(t.side[2] == Approx(5));
    CHECK(t.v[0] == 1);  // joins the shortest (3: 0-1) and longest (5: 1-2) sides
    CHECK(t.v[1] == 0);
    CHECK(t.v[2] == 2);
    CHECK(t.label[0] == 2);                   // labels follow the vertex order
    const uint8_t key_labels[3] = {2, 1, 3};  // in vertex order (ids 1, 0, 2)
    CHECK(triangle_key(t, 1.0f) == triangle_key(key_labels, 3, 4, 5));
  }
  // Key fields: labels above the sides, q2 lowest; what does not fit is never a valid key.
  const uint8_t l[3] = {1, 2, 3};
  CHECK(triangle_key(l, 3, 4, 5) + 1 == triangle_key(l, 3, 4, 6));
  CHECK(triangle_key(l, 65535, 65535, 65535) < triangle_key(l, 0, 0, 0) + (uint64_t(1) << 48));
  Triangle big{};
  big.side[0] = big.side[1] = 1.0f;
  big.side[2] = 65536.0f;
  CHECK(triangle_key(big, 1.0f) == kInvalidTriangleKey);
  big.side[2] = 2.0f;
  big.label[1] = 32;
  CHECK(triangle_key(big, 1.0f) == kInvalidTriangleKey);
  TriangleConfig fine;
  fine.side_bin = fine.max_side / 65534.0f;
  CHECK(validate(fine) == Status::InvalidArgument);
}

TEST_CASE("TriangleBuilder: dedup, side range, rigid invariance, capacity") {
  TriangleConfig tc;
  Buffer buf(2 * TriangleBuilder::required_bytes(tc, 64) + 2 * tc.max_triangles * sizeof(Triangle) + 64);
  TriangleBuilder b;
  FixedVector<Triangle> a, c;
  REQUIRE(b.bind(buf.arena, tc, 64) == Status::Ok);
  REQUIRE(a.bind(buf.arena, tc.max_triangles));
  REQUIRE(c.bind(buf.arena, tc.max_triangles));
  const auto pts = random_points(30, 1);
  std::vector<uint8_t> labels(30);
  for (int i = 0; i < 30; ++i) labels[i] = static_cast<uint8_t>(i % 3);
  REQUIRE(b.build(pts.data(), 3, labels.data(), 30, a) == Status::Ok);
  REQUIRE(a.size() > 30);
  std::set<std::array<uint32_t, 3>> sets;
  for (const Triangle& t : a) {
    std::array<uint32_t, 3> s = {t.v[0], t.v[1], t.v[2]};
    std::sort(s.begin(), s.end());
    CHECK(sets.insert(s).second);  // each vertex set once
    CHECK(t.side[0] <= t.side[1]);
    CHECK(t.side[1] <= t.side[2]);
    CHECK(t.side[0] >= tc.min_side);
    CHECK(t.side[2] <= tc.max_side);
  }
  // A rigidly moved copy gives the same triangles (sides within float rounding, same labels).
  const Eigen::Isometry3d T = some_pose();
  std::vector<float> moved(pts.size());
  for (int i = 0; i < 30; ++i) {
    const Eigen::Vector3d q = T * Eigen::Vector3d(pts[3 * i], pts[3 * i + 1], pts[3 * i + 2]);
    for (int k = 0; k < 3; ++k) moved[3 * i + k] = static_cast<float>(q[k]);
  }
  REQUIRE(b.build(moved.data(), 3, labels.data(), 30, c) == Status::Ok);
  CHECK(c.size() == a.size());
  for (uint32_t i = 0; i < std::min(a.size(), c.size()); ++i) {
    CHECK(c[i].side[2] == Approx(a[i].side[2]).epsilon(1e-4));
    CHECK(c[i].label[0] == a[i].label[0]);
  }
  FixedVector<Triangle> small;
  REQUIRE(small.bind(buf.arena, 5));
  CHECK(b.build(pts.data(), 3, labels.data(), 30, small) == Status::CapacityExceeded);
  CHECK(small.size() == 5);
  CHECK(std::equal(small.begin(), small.end(), a.begin(), [](const Triangle& x, const Triangle& y) {
    return x.v[0] == y.v[0] && x.v[1] == y.v[1] && x.v[2] == y.v[2];
  }));  // deterministic prefix
}

TEST_CASE("Triangle senses: a turn keeps them, a mirror image reverses them, a near-collinear one has none") {
  // p0 -> p1 -> p2 counter-clockwise seen from above, apex 3 m off the longest side.
  const float p[9] = {0, 0, 0, 6, 0, 0.5f, 2, 3, 1};
  const uint8_t labels[6] = {kPole, kPole, kPole, kPole, kPole, kPole};
  for (int deg = 0; deg < 360; deg += 30) {
    const float c = std::cos(float(deg) * 0.0174533f), s = std::sin(float(deg) * 0.0174533f);
    float q[9], m[9];
    for (int v = 0; v < 3; ++v) {
      q[3 * v] = c * p[3 * v] - s * p[3 * v + 1] + 17.0f;
      q[3 * v + 1] = s * p[3 * v] + c * p[3 * v + 1] - 4.0f;
      m[3 * v] = q[3 * v];
      m[3 * v + 1] = -q[3 * v + 1];  // mirror image (y -> -y)
      q[3 * v + 2] = m[3 * v + 2] = p[3 * v + 2];
    }
    INFO("yaw " << deg);
    CHECK(triangle_orientation(q, q + 3, q + 6, 6.0f) == kOrientationCounterClockwise);
    CHECK(triangle_orientation(m, m + 3, m + 6, 6.0f) == kOrientationClockwise);
    CHECK(triangle_orientation(q, q + 6, q + 3, 6.0f) == kOrientationClockwise);  // the other vertex order
    // make_triangle records the sense of its canonical order, whatever order the vertices came in; the
    // mirror image's is the opposite one.
    const Triangle t = make_triangle(0, 1, 2, q, q + 3, q + 6, labels);
    const Triangle t2 = make_triangle(1, 0, 2, q + 3, q, q + 6, labels);  // an odd permutation of the input
    const float* by_id[3] = {q, q + 3, q + 6};
    CHECK(t.orientation == triangle_orientation(by_id[t.v[0]], by_id[t.v[1]], by_id[t.v[2]], t.side[2]));
    const Triangle tm = make_triangle(3, 4, 5, m, m + 3, m + 6, labels);
    CHECK(t.orientation == t2.orientation);
    CHECK((t.orientation == kOrientationCounterClockwise || t.orientation == kOrientationClockwise));
    CHECK(tm.orientation != t.orientation);
    CHECK(orientations_contradict(t.orientation, tm.orientation, false));
    CHECK_FALSE(orientations_contradict(t.orientation, tm.orientation, true));
    CHECK_FALSE(orientations_contradict(t.orientation, t2.orientation, false));
  }
  // Apex 0.9 m from a 10 m side (below kOrientationMinHeight): flat; flat never contradicts.
  const float flat[9] = {0, 0, 0, 10, 0, 0, 4, 0.9f, 0};
  CHECK(triangle_orientation(flat, flat + 3, flat + 6, 10.0f) == kOrientationFlat);
  for (uint8_t o : {kOrientationCounterClockwise, kOrientationClockwise})
    for (bool flip : {false, true}) {
      CHECK_FALSE(orientations_contradict(kOrientationFlat, o, flip));
      CHECK_FALSE(orientations_contradict(o, kOrientationFlat, flip));
    }
  // The matcher's one-byte form names exactly the senses the test calls contradicting.
  for (uint8_t a = 0; a <= kOrientationFlat; ++a)
    for (bool flip : {false, true})
      for (uint8_t b = kOrientationCounterClockwise; b <= kOrientationFlat; ++b)
        CHECK((b == contradicting_orientation(a, flip)) == orientations_contradict(a, b, flip));
}

TEST_CASE("The vertex-set key is the same for every order of three ids and differs between sets") {
  const uint32_t ids[3] = {7, 2097151, 12345};  // 2^21 - 1 is the largest id
  const uint64_t key = triangle_vertex_set_key(ids[0], ids[1], ids[2]);
  const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (const auto& p : perms) CHECK(triangle_vertex_set_key(ids[p[0]], ids[p[1]], ids[p[2]]) == key);
  CHECK(key == ((uint64_t(7) << 42) | (uint64_t(12345) << 21) | 2097151u));
  std::set<uint64_t> keys;
  for (uint32_t a = 0; a < 12; ++a)
    for (uint32_t b = a + 1; b < 12; ++b)
      for (uint32_t c = b + 1; c < 12; ++c) keys.insert(triangle_vertex_set_key(c, a, b));
  CHECK(keys.size() == 220);  // 12 choose 3: no two sets share a key
}

}  // namespace test_triangle
