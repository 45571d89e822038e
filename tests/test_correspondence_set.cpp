// The correspondence stage alone: votes and best similarity per pair, selection by votes x weight with
// hash tie-breaks (not instance id), the positions handed to the clique, and both caps counted.
#include <catch2/catch.hpp>

#include <set>
#include <vector>

#include "arena_buffer.h"
#include "gsf/detail/correspondence_set.h"

namespace test_correspondence_set {

using namespace gsf;
using gsf_test::ArenaBuffer;

namespace {

std::vector<MapInstance> map_instances(uint32_t n) {
  std::vector<MapInstance> m(n);
  for (uint32_t i = 0; i < n; ++i) {
    m[i].centroid[0] = 100.0f + i;
    m[i].centroid[1] = -float(i);
    m[i].centroid[2] = 0.5f;
  }
  return m;
}

}  // namespace

TEST_CASE("required_bytes is what bind takes; zero capacities are refused") {
  const size_t need = CorrespondenceSet::required_bytes(1000, 64);
  ArenaBuffer buf(need);
  Arena exact(buf.words.data(), need);
  CorrespondenceSet cs;
  CHECK(cs.bind(exact, 1000, 64) == Status::Ok);
  CHECK(exact.used() == need);
  Arena short_arena(buf.words.data(), need - 1);
  CHECK(cs.bind(short_arena, 1000, 64) == Status::BufferTooSmall);
  CHECK(cs.bind(buf.arena, 0, 64) == Status::InvalidArgument);
  CHECK(cs.bind(buf.arena, 1000, 0) == Status::InvalidArgument);
}

TEST_CASE("Selection keeps the pairs with most votes x weight, and hands their positions on") {
  ArenaBuffer buf(CorrespondenceSet::required_bytes(64, 3));
  CorrespondenceSet cs;
  REQUIRE(cs.bind(buf.arena, 64, 3) == Status::Ok);
  // (0,5): 3 votes, best omega 0.9 -> 2.7; (1,6): 4 votes x 0.5 = 2.0; (2,7): 1 x 1.0; (3,8): 2 x 0.8 = 1.6
  for (float w : {0.4f, 0.9f, 0.6f}) REQUIRE(cs.add(0, 5, w));
  for (int k = 0; k < 4; ++k) REQUIRE(cs.add(1, 6, 0.5f));
  REQUIRE(cs.add(2, 7, 1.0f));
  REQUIRE(cs.add(3, 8, 0.8f));
  REQUIRE(cs.add(3, 8, 0.2f));
  CHECK(cs.candidates() == 4);
  const float query[4 * 3] = {0, 0, 0, 1, 1, 1, 2, 2, 2, 3, 3, 3};
  const auto map = map_instances(10);
  const uint32_t C = cs.select(3, query, map.data());
  REQUIRE(C == 3);
  CHECK(cs.selected_pair(0).query == 0);
  CHECK(cs.selected_pair(0).votes == 3);
  CHECK(cs.selected_pair(0).weight == 0.9f);
  CHECK(cs.selected_pair(1).query == 1);
  CHECK(cs.selected_pair(2).query == 3);  // 1.6 > 1.0: support, not insertion order
  CHECK(cs.query_xyz()[3 * 2] == 3.0f);
  CHECK(cs.map_xyz()[3 * 2] == 108.0f);
  CHECK(cs.map_xyz()[3 * 2 + 1] == -8.0f);
  CHECK(cs.weights()[1] == 0.5f);
  // A smaller request keeps a prefix of the same ranking.
  CHECK(cs.select(1, query, map.data()) == 1);
  CHECK(cs.selected_pair(0).query == 0);
}

TEST_CASE("Equal support is decided by a hash of the pair, not by map instance id") {
  // 200 pairs with equal support; keep 20. Storage/id order would keep map ids 0..19.
  ArenaBuffer buf(CorrespondenceSet::required_bytes(256, 20));
  CorrespondenceSet cs;
  REQUIRE(cs.bind(buf.arena, 256, 20) == Status::Ok);
  for (uint32_t m = 0; m < 200; ++m) REQUIRE(cs.add(0, m, 1.0f));
  std::vector<float> query(3, 0.0f);
  const auto map = map_instances(200);
  REQUIRE(cs.select(20, query.data(), map.data()) == 20);
  std::set<uint32_t> kept;
  for (uint32_t k = 0; k < 20; ++k) kept.insert(cs.selected_pair(k).map);
  uint32_t low = 0;
  for (uint32_t m : kept) low += m < 20;
  CHECK(low < 10);  // the hash spreads the kept ids over 0..199 (expected 2 below 20)
  CHECK(*kept.rbegin() >= 100);
  // Deterministic: the same input gives the same selection.
  CorrespondenceSet again;
  ArenaBuffer buf2(CorrespondenceSet::required_bytes(256, 20));
  REQUIRE(again.bind(buf2.arena, 256, 20) == Status::Ok);
  for (uint32_t m = 0; m < 200; ++m) again.add(0, m, 1.0f);
  again.select(20, query.data(), map.data());
  for (uint32_t k = 0; k < 20; ++k) CHECK(again.selected_pair(k).map == cs.selected_pair(k).map);
}

TEST_CASE("A full candidate set refuses new pairs but still counts votes for known ones") {
  ArenaBuffer buf(CorrespondenceSet::required_bytes(8, 8));
  CorrespondenceSet cs;
  REQUIRE(cs.bind(buf.arena, 8, 8) == Status::Ok);
  for (uint32_t m = 0; m < 8; ++m) REQUIRE(cs.add(1, m, 0.5f));
  CHECK_FALSE(cs.add(1, 100, 1.0f));  // new pair, no room: the caller counts it as dropped
  CHECK(cs.add(1, 3, 1.0f));          // known pair: still accumulates
  CHECK(cs.candidates() == 8);
  std::vector<float> query(6, 0.0f);
  const auto map = map_instances(101);
  REQUIRE(cs.select(8, query.data(), map.data()) == 8);
  CHECK(cs.selected_pair(0).map == 3);
  CHECK(cs.selected_pair(0).votes == 2);
  cs.clear();
  CHECK(cs.candidates() == 0);
  CHECK(cs.selected() == 0);
  CHECK(cs.add(1, 100, 1.0f));  // room again after clear
}

TEST_CASE("Pairs below the GSF gate (tier 0) rank after every pair that passed, and only fill a short set") {
  ArenaBuffer buf(CorrespondenceSet::required_bytes(64, 8));
  CorrespondenceSet cs;
  REQUIRE(cs.bind(buf.arena, 64, 8) == Status::Ok);
  // Tier 1: (0,10) 1 vote x 0.4 and (1,11) 2 x 0.5. Tier 0: (2,12) 9 votes x 0.25, more support than
  // either, and (3,13), (4,14), (5,15) one vote each at 0.2, 0.15, 0.1.
  REQUIRE(cs.add(0, 10, 0.4f, 1));
  REQUIRE(cs.add(1, 11, 0.5f, 1));
  REQUIRE(cs.add(1, 11, 0.3f, 1));
  for (int k = 0; k < 9; ++k) REQUIRE(cs.add(2, 12, 0.25f, 0));
  REQUIRE(cs.add(3, 13, 0.2f, 0));
  REQUIRE(cs.add(4, 14, 0.15f, 0));
  REQUIRE(cs.add(5, 15, 0.1f, 0));
  // A tier-0 vote on a tier-1 pair is ignored: its votes and weight stay the filter's.
  REQUIRE(cs.add(0, 10, 0.9f, 0));
  // A tier-1 vote on a tier-0 pair restarts it at tier 1: (5,15) now 1 vote x 0.45, above (0,10).
  REQUIRE(cs.add(5, 15, 0.45f, 1));
  CHECK(cs.candidates() == 6);
  const float query[6 * 3] = {};
  const auto map = map_instances(16);
  // fill_to 4: the three tier-1 pairs, then one tier-0 pair (the best supported) to make four.
  REQUIRE(cs.select(8, query, map.data(), 4) == 4);
  CHECK(cs.selected_pair(0).query == 1);
  CHECK(cs.selected_pair(1).query == 5);
  CHECK(cs.selected_pair(1).votes == 1);
  CHECK(cs.selected_pair(1).tier == 1);
  CHECK(cs.selected_pair(2).query == 0);
  CHECK(cs.selected_pair(2).weight == 0.4f);
  CHECK(cs.selected_pair(2).votes == 1);
  CHECK(cs.selected_pair(3).query == 2);
  CHECK(cs.selected_pair(3).tier == 0);
  // No filling (fill_to 0 or below the tier-1 count): the tier-1 pairs alone.
  CHECK(cs.select(8, query, map.data(), 0) == 3);
  CHECK(cs.select(8, query, map.data(), 2) == 3);
  // A large fill_to takes every pair, still within max_selected.
  CHECK(cs.select(8, query, map.data(), 100) == 6);
  CHECK(cs.select(5, query, map.data(), 100) == 5);
  CHECK(cs.selected_pair(4).query == 3);
}

}  // namespace test_correspondence_set
