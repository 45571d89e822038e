// Heading votes alone (core/include/gsf/detail/heading_votes.h) on a hand-made map of two scalene
// triangles and query triangles that are turned copies of them: the yaw bin of a match is the turn in
// closed form, the bin most matches vote for wins (with its two neighbours, across 0/360), ties go to the
// lower bin whatever the triangles' order, and the votes come from an even sample of the triangles.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <set>
#include <vector>

#include "arena_buffer.h"
#include "gsf/detail/angles.h"
#include "gsf/detail/fixed_vector.h"
#include "gsf/detail/heading_votes.h"
#include "gsf/detail/triangle.h"
#include "gsf/detail/triangle_index.h"
#include "gsf/detail/triangle_matcher.h"
#include "gsf/map_format.h"
#include "gsf/semantic_classes.h"

namespace test_heading_votes {

using namespace gsf;
using gsf_test::ArenaBuffer;

namespace {

constexpr uint32_t kBins = 36;  // 10 degree bins, the default gsf.yaw_bins

// The map: triangle A (instances 0-2, poles) and triangle B (instances 3-5, trunks), scalene (no two sides
// within the 6% tie tolerance) and of different sides and labels, so a turned copy of one matches it only.
struct TwoTriangleMap {
  std::vector<MapInstance> instances;
  std::vector<uint8_t> labels;
  std::vector<Triangle> input, sorted;
  std::vector<uint64_t> keys, scratch;
  std::vector<uint32_t> offsets, ids;
  TriangleIndexView index;
  MapView view;
  TwoTriangleMap() {
    const float pos[6][3] = {{0, 0, 0}, {7, 1, 0.5f}, {2, 5, 1}, {40, 20, 0}, {52, 20, 0}, {42, 29, 0.5f}};
    instances.assign(6, MapInstance{});
    for (uint32_t i = 0; i < 6; ++i) {
      for (int d = 0; d < 3; ++d) instances[i].centroid[d] = pos[i][d];
      instances[i].label = i < 3 ? kPole : kTrunk;
      labels.push_back(instances[i].label);
    }
    input = {make_triangle(0, 1, 2, pos[0], pos[1], pos[2], labels.data()),
             make_triangle(3, 4, 5, pos[3], pos[4], pos[5], labels.data())};
    sorted.resize(2);
    keys.resize(2);
    scratch.resize(2);
    offsets.resize(3);
    ids.resize(2);
    uint32_t kc = 0;
    REQUIRE(build_triangle_index(input.data(), 2, 1.0f, sorted.data(), keys.data(), offsets.data(), &kc, scratch.data(),
                                 ids.data()) == Status::Ok);
    REQUIRE(kc == 2);
    index = TriangleIndexView{keys.data(), offsets.data(), kc, 2};
    view.instances = instances.data();
    view.triangles = sorted.data();
    view.counts.instances = 6;
    view.counts.triangles = 2;
  }
};

// The query: turned and moved copies of the map's triangles, each with instances of its own. A copy of
// map triangle `which` (0: A, 1: B) at heading yaw_deg: map = R(yaw) query + t, so query = R(-yaw)(map - t).
struct Query {
  std::vector<float> centroids;  // 3 per query instance
  std::vector<uint8_t> labels;
  std::vector<Triangle> triangles;
  void add(const TwoTriangleMap& map, int which, double yaw_deg) {
    const double yaw = yaw_deg * kPi / 180.0, c = std::cos(-yaw), s = std::sin(-yaw);
    const uint32_t first = static_cast<uint32_t>(labels.size());
    for (uint32_t v = 0; v < 3; ++v) {
      const float* m = map.instances[3 * which + v].centroid;
      const double x = m[0] - 25.0, y = m[1] + 10.0;
      centroids.insert(centroids.end(), {float(c * x - s * y), float(s * x + c * y), m[2] - 0.3f});
      labels.push_back(map.instances[3 * which + v].label);
    }
    triangles.push_back(make_triangle(first, first + 1, first + 2, &centroids[3 * first], &centroids[3 * first + 3],
                                      &centroids[3 * first + 6], labels.data()));
  }
};

uint32_t bin_of(double yaw_deg) {
  return uint32_t(((std::llround(yaw_deg / (360.0 / kBins)) % kBins) + kBins) % kBins);
}

// The stage as the localizer binds it, run on `query`; returns the allowed bins.
struct Votes {
  ArenaBuffer buf;
  HeadingVotes votes;
  TriangleMatcher matcher;
  FixedVector<Triangle> triangles;
  uint32_t kept = 0;
  Votes()
      : buf(HeadingVotes::required_bytes(kBins) + TriangleMatcher::required_bytes(64) + 64 * sizeof(Triangle) + 64) {
    REQUIRE(votes.bind(buf.arena, kBins) == Status::Ok);
    REQUIRE(matcher.bind(buf.arena, 64) == Status::Ok);
    REQUIRE(triangles.bind(buf.arena, 64));
  }
  std::set<uint32_t> run(const TwoTriangleMap& map, const Query& q, uint32_t kept_bins, uint32_t sample = 256) {
    triangles.clear();
    for (const Triangle& t : q.triangles) REQUIRE(triangles.push_back(t));
    HeadingVoteParams p;
    p.kept_bins = kept_bins;
    p.sample_triangles = sample;
    kept = votes.vote(triangles, q.centroids.data(), matcher, map.index, map.view, TriangleConfig(), p);
    std::set<uint32_t> allowed;
    for (uint32_t b = 0; b < kBins; ++b)
      if (votes.allowed(b)) allowed.insert(b);
    CHECK(kept == allowed.size());
    return allowed;
  }
};

std::set<uint32_t> around(std::initializer_list<uint32_t> bins) {
  std::set<uint32_t> s;
  for (uint32_t b : bins) s.insert({(b + kBins - 1) % kBins, b, (b + 1) % kBins});
  return s;
}

}  // namespace

TEST_CASE("match_yaw_bin is round(yaw / bin width) of the turn, and pairs each query vertex with its map vertex") {
  const TwoTriangleMap map;
  ArenaBuffer buf(TriangleMatcher::required_bytes(8));
  TriangleMatcher matcher;
  REQUIRE(matcher.bind(buf.arena, 8) == Status::Ok);
  for (int which = 0; which < 2; ++which)
    for (double yaw : {0.0, 4.9, 5.1, 50.0, 123.0, 181.0, 270.0, 356.0, -94.0}) {
      Query q;
      q.add(map, which, yaw);
      INFO("triangle " << which << " yaw " << yaw);
      matcher.match(q.triangles[0], map.index, map.view.triangles, TriangleConfig(), 0.06f);
      REQUIRE(matcher.size() == 1);
      uint32_t qv[3];
      CHECK(match_yaw_bin(q.triangles[0], matcher.match_at(0), q.centroids.data(), map.view, kBins, qv) == bin_of(yaw));
      // qv[j] is the query instance of map vertex j: moved by the known pose it lands on that map instance.
      const Triangle& mt = map.view.triangles[matcher.match_at(0).map];
      const double r = yaw * kPi / 180.0;
      for (int j = 0; j < 3; ++j) {
        const float* p = &q.centroids[3 * qv[j]];
        const float* m = map.instances[mt.v[j]].centroid;
        CHECK(std::cos(r) * p[0] - std::sin(r) * p[1] + 25.0 == Approx(m[0]).margin(1e-4));
        CHECK(std::sin(r) * p[0] + std::cos(r) * p[1] - 10.0 == Approx(m[1]).margin(1e-4));
      }
    }
}

TEST_CASE("The bin most matches vote for wins with its two neighbours; the next best follow by votes") {
  const TwoTriangleMap map;
  Votes v;
  Query q;  // 5 matches at 50 deg (bin 5), 3 at 200 deg (bin 20), interleaved
  for (int k = 0; k < 8; ++k) q.add(map, k % 2 == 0 || k == 7 ? 0 : 1, k % 2 == 0 || k == 7 ? 50.0 : 200.0);
  CHECK(v.run(map, q, 1) == around({5}));
  CHECK(v.kept == 3);
  CHECK(v.run(map, q, 2) == around({5, 20}));
  CHECK(v.kept == 6);
  // Only two bins have votes: asking for more keeps those two.
  CHECK(v.run(map, q, 6) == around({5, 20}));
  // The order of the triangles does not matter.
  Query r = q;
  std::reverse(r.triangles.begin(), r.triangles.end());
  CHECK(v.run(map, r, 1) == around({5}));
  // The neighbours wrap around 0 / 360 degrees: a win at 358 deg (bin 0) keeps bins 35, 0 and 1.
  Query w;
  for (int k = 0; k < 3; ++k) w.add(map, 1, 358.0);
  w.add(map, 0, 90.0);
  CHECK(v.run(map, w, 1) == std::set<uint32_t>{35, 0, 1});
  // kept_bins 0: the votes are off and every heading goes on.
  CHECK(v.run(map, q, 0).size() == kBins);
  CHECK(v.kept == kBins);
}

TEST_CASE("A tie between bins goes to the lower bin, whatever the order of the triangles") {
  const TwoTriangleMap map;
  Votes v;
  Query q;  // 2 votes at 200 deg (bin 20) first, then 2 at 50 deg (bin 5)
  q.add(map, 0, 200.0);
  q.add(map, 0, 200.0);
  q.add(map, 1, 50.0);
  q.add(map, 1, 50.0);
  CHECK(v.run(map, q, 1) == around({5}));
  Query r = q;
  std::reverse(r.triangles.begin(), r.triangles.end());
  CHECK(v.run(map, r, 1) == around({5}));
  std::rotate(r.triangles.begin(), r.triangles.begin() + 1, r.triangles.end());
  CHECK(v.run(map, r, 1) == around({5}));
  // One more vote for bin 20 breaks the tie its way: the lower bin wins ties only.
  q.add(map, 0, 200.0);
  CHECK(v.run(map, q, 1) == around({20}));
  // The same input twice: the same bins.
  CHECK(v.run(map, q, 2) == v.run(map, q, 2));
}

TEST_CASE("The votes come from every stride-th triangle over the whole scan, not the first ones") {
  // 12 triangles: those at 0, 3, 6, 9 turn by 200 deg (bin 20), the 8 others by 50 deg (bin 5).
  const TwoTriangleMap map;
  Votes v;
  Query q;
  for (int k = 0; k < 12; ++k) q.add(map, k % 3 == 0 ? 0 : 1, k % 3 == 0 ? 200.0 : 50.0);
  // All 12 sampled: bin 5 has 8 votes to 4.
  CHECK(v.run(map, q, 1, 12) == around({5}));
  CHECK(v.run(map, q, 1, 256) == around({5}));
  // A sample of 4 is every 3rd triangle (0, 3, 6, 9): bin 20 alone has votes. The first 4 triangles
  // would have tied 2 : 2 and given bin 5.
  CHECK(v.run(map, q, 1, 4) == around({20}));
  CHECK(v.run(map, q, 2, 4) == around({20}));  // and no vote at all for bin 5
  // A sample of 5 rounds the stride up (ceil(12 / 5) = 3): the same four triangles.
  CHECK(v.run(map, q, 1, 5) == around({20}));
  // A sample of 6 is every 2nd triangle (0, 2, ..., 10): bin 20 at 0 and 6, bin 5 at 2, 4, 8 and 10.
  CHECK(v.run(map, q, 1, 6) == around({5}));
}

TEST_CASE("Heading votes: bind refuses zero bins; required_bytes is what bind takes") {
  const size_t need = HeadingVotes::required_bytes(kBins);
  ArenaBuffer buf(need);
  Arena exact(buf.words.data(), need);
  HeadingVotes hv;
  CHECK(hv.bind(exact, kBins) == Status::Ok);
  CHECK(exact.used() == need);
  CHECK(hv.bins() == kBins);
  Arena short_arena(buf.words.data(), need - 1);
  CHECK(hv.bind(short_arena, kBins) == Status::BufferTooSmall);
  CHECK(hv.bind(buf.arena, 0) == Status::InvalidArgument);
}

}  // namespace test_heading_votes
