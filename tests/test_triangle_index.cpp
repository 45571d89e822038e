// The triangle index alone (core/include/gsf/detail/triangle_index.h): lookups and ranges against brute
// force, validation of bad arrays, and noisy copies of the map's triangles found through it.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "arena_buffer.h"
#include "gsf/detail/triangle.h"
#include "gsf/detail/triangle_index.h"
#include "gsf/detail/triangle_matcher.h"
#include "random_points.h"

namespace test_triangle_index {

using namespace gsf;
using gsf_test::random_points;
using gsf_test::some_pose;
using Buffer = gsf_test::ArenaBuffer;

TEST_CASE("Triangle index: lookup equals brute force, validate rejects bad arrays, matching recovers noisy copies") {
  TriangleConfig tc;
  Buffer buf(TriangleBuilder::required_bytes(tc, 128) + 8192 * sizeof(Triangle) + 64);
  TriangleBuilder b;
  FixedVector<Triangle> tris;
  REQUIRE(b.bind(buf.arena, tc, 128) == Status::Ok);
  REQUIRE(tris.bind(buf.arena, 8192));
  const auto pts = random_points(100, 2, 60.0f);
  std::vector<uint8_t> labels(100);
  for (int i = 0; i < 100; ++i) labels[i] = static_cast<uint8_t>(i % 4);
  REQUIRE(b.build(pts.data(), 3, labels.data(), 100, tris) == Status::Ok);
  const uint32_t n = tris.size();
  std::vector<Triangle> sorted(n);
  std::vector<uint64_t> keys(n), scratch(n);
  std::vector<uint32_t> offsets(n + 1), ids(n);
  uint32_t kc = 0;
  REQUIRE(build_triangle_index(tris.data(), n, tc.side_bin, sorted.data(), keys.data(), offsets.data(), &kc,
                               scratch.data(), ids.data()) == Status::Ok);
  TriangleIndexView idx{keys.data(), offsets.data(), kc, n};
  REQUIRE(idx.validate(sorted.data(), tc.side_bin) == Status::Ok);
  // Stored in key order, ties in build order: a permutation of the input.
  for (uint32_t t = 1; t < n; ++t)
    CHECK(triangle_key(sorted[t - 1], tc.side_bin) <= triangle_key(sorted[t], tc.side_bin));
  for (uint32_t k = 0; k < kc; k += 7) {
    uint32_t bgn, end;
    REQUIRE(idx.lookup(keys[k], &bgn, &end));
    std::vector<uint32_t> got, brute;
    for (uint32_t t = bgn; t < end; ++t)
      got.push_back(sorted[t].v[0] * 4096u * 4096u + sorted[t].v[1] * 4096u + sorted[t].v[2]);
    for (uint32_t t = 0; t < n; ++t)
      if (triangle_key(tris[t], tc.side_bin) == keys[k])
        brute.push_back(tris[t].v[0] * 4096u * 4096u + tris[t].v[1] * 4096u + tris[t].v[2]);
    CHECK(got == brute);
  }
  // A range of three q2 neighbours is the union of their lookups.
  for (uint32_t k = 0; k < kc; k += 5) {
    uint32_t rb, re, b0, e0;
    REQUIRE(idx.range(keys[k], keys[k] + 2, &rb, &re));
    uint32_t count = 0;
    for (uint64_t key = keys[k]; key <= keys[k] + 2; ++key)
      if (idx.lookup(key, &b0, &e0)) count += e0 - b0;
    CHECK(rb == idx.offsets[k]);
    CHECK(re - rb == count);
  }
  // range_from over increasing ranges (galloping from where the last ended) equals range() each time,
  // for ranges near each other and far apart, present or not.
  for (uint64_t stride : {uint64_t(1), uint64_t(3), uint64_t(1) << 16, uint64_t(1) << 32, uint64_t(1) << 48}) {
    uint32_t from = 0, checked = 0;
    for (uint64_t lo = keys[0] > 5 ? keys[0] - 5 : 0; lo <= keys[kc - 1] + 1 && checked < 20000;
         lo += stride, ++checked) {
      uint32_t b1, e1, b2, e2;
      const bool r1 = idx.range(lo, lo + 2 < lo + stride ? lo + 2 : lo + stride - 1, &b1, &e1);
      const bool r2 = idx.range_from(lo, lo + 2 < lo + stride ? lo + 2 : lo + stride - 1, &from, &b2, &e2);
      REQUIRE(r1 == r2);
      CHECK(b1 == b2);
      CHECK(e1 == e2);
    }
  }
  uint32_t bgn, end;
  const uint8_t no_labels[3] = {9, 9, 9};
  CHECK_FALSE(idx.lookup(triangle_key(no_labels, 999, 999, 999), &bgn, &end));
  std::swap(keys[0], keys[1]);
  CHECK(idx.validate(sorted.data(), tc.side_bin) == Status::CorruptData);
  std::swap(keys[0], keys[1]);
  std::swap(sorted[0], sorted[n - 1]);  // triangles under another bucket's key
  CHECK(idx.validate(sorted.data(), tc.side_bin) == Status::CorruptData);
  std::swap(sorted[0], sorted[n - 1]);
  offsets[1] = offsets[2] + 1;
  CHECK(idx.validate(sorted.data(), tc.side_bin) == Status::CorruptData);
  build_triangle_index(tris.data(), n, tc.side_bin, sorted.data(), keys.data(), offsets.data(), &kc, scratch.data(),
                       ids.data());
  // Noisy copies (1% per side, under the 3% tolerance) match their originals; wrong labels do not.
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> e(-0.01f, 0.01f);
  Buffer mb(TriangleMatcher::required_bytes(4096) + 64);
  TriangleMatcher matcher;
  REQUIRE(matcher.bind(mb.arena, 4096) == Status::Ok);
  for (uint32_t t = 0; t < n; t += 11) {
    Triangle q = sorted[t];
    for (float& s : q.side) s *= 1.0f + e(rng);
    const TriangleMatchStats st = matcher.match(q, idx, sorted.data(), tc, 0.0f);
    CHECK(st.dropped() == 0);
    bool found = false;
    for (uint32_t k = 0; k < matcher.size(); ++k) found = found || matcher.match_at(k).map == t;
    CHECK(found);
    q.label[0] = static_cast<uint8_t>((q.label[0] + 1) % 4);
    matcher.match(q, idx, sorted.data(), tc, 0.0f);
    for (uint32_t k = 0; k < matcher.size(); ++k) CHECK(matcher.match_at(k).map != t);
  }
}

}  // namespace test_triangle_index
