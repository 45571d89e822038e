// Arena, fixed-capacity containers, Status and the class table.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>

#include "gsf/detail/arena.h"
#include "gsf/detail/bounded_hash_map.h"
#include "gsf/detail/fixed_vector.h"
#include "gsf/semantic_classes.h"
#include "gsf/status.h"

namespace test_foundation {

using namespace gsf;

TEST_CASE("Arena: counting pass predicts the real layout exactly") {
  auto layout = [](Arena& a) {
    a.allocate<double>(7);
    a.allocate<uint8_t>(3);
    a.allocate<float>(100);
    FixedVector<int> v;
    v.bind(a, 33);
    BoundedHashMap<float> m;
    m.bind(a, 50);
  };
  Arena counting;
  layout(counting);
  REQUIRE(counting.counting());
  const size_t need = counting.used();
  REQUIRE(need > 7 * 8 + 3 + 400);

  alignas(16) static uint8_t buf[8192];
  REQUIRE(need <= sizeof(buf));
  Arena exact(buf, need);
  layout(exact);
  CHECK_FALSE(exact.overflowed());
  CHECK(exact.used() == need);

  Arena short_by_one(buf, need - 1);
  layout(short_by_one);
  CHECK(short_by_one.overflowed());
  CHECK(short_by_one.used() <= need - 1);  // never hands out bytes past the end
}

TEST_CASE("Arena: alignment, overflow and rewind") {
  alignas(16) static uint8_t buf[256];
  Arena a(buf, sizeof(buf));
  auto* c = a.allocate<uint8_t>(1);
  auto* d = a.allocate<double>(2);
  REQUIRE(c != nullptr);
  REQUIRE(d != nullptr);
  CHECK(reinterpret_cast<uintptr_t>(d) % 16 == 0);
  const size_t m = a.mark();
  CHECK(a.allocate<uint8_t>(1000) == nullptr);
  CHECK(a.overflowed());
  CHECK(a.used() == m);  // failed allocation consumed nothing
  a.rewind(m);
  CHECK_FALSE(a.overflowed());
  CHECK(a.allocate<uint8_t>(16) != nullptr);
  CHECK(a.allocate<uint64_t>(SIZE_MAX / 4) == nullptr);  // size overflow is caught, not wrapped
}

TEST_CASE("FixedVector / StaticVector: bounded push, no growth") {
  StaticVector<int, 4> v;
  for (int i = 0; i < 4; ++i) REQUIRE(v.push_back(i));
  CHECK(v.full());
  CHECK_FALSE(v.push_back(99));
  CHECK(v.size() == 4);
  CHECK(v[3] == 3);
  StaticVector<int, 4> w = v;
  w[0] = 42;
  CHECK(v[0] == 0);  // copy owns its own storage
  CHECK(w[0] == 42);
  CHECK_FALSE(w.resize(5));
  w.truncate(1);
  CHECK(w.size() == 1);
  FixedVector<int>& erased = w;  // capacity-erased interface
  CHECK(erased.capacity() == 4);
}

TEST_CASE("BoundedHashMap: insert, find, capacity limit, determinism") {
  alignas(16) static uint8_t buf[1 << 16];
  Arena a(buf, sizeof(buf));
  BoundedHashMap<int> m;
  REQUIRE(m.bind(a, 100));
  for (uint64_t k = 0; k < 100; ++k) {
    bool inserted = false;
    int* v = m.find_or_insert(k * 7919u, &inserted);
    REQUIRE(v != nullptr);
    REQUIRE(inserted);
    *v = static_cast<int>(k);
  }
  CHECK(m.size() == 100);
  CHECK(m.find_or_insert(123456789u) == nullptr);  // full: new keys refused
  bool inserted = true;
  int* again = m.find_or_insert(7919u * 5, &inserted);
  REQUIRE(again != nullptr);
  CHECK_FALSE(inserted);
  CHECK(*again == 5);
  CHECK(m.find(3u) == nullptr);
  uint64_t sum = 0;
  m.for_each([&](uint64_t, int& v) { sum += static_cast<uint64_t>(v); });
  CHECK(sum == 99 * 100 / 2);
  m.clear();
  CHECK(m.size() == 0);
  CHECK(m.find(7919u) == nullptr);
}

TEST_CASE("Status names are distinct and never null") {
  for (int i = 0; i <= static_cast<int>(Status::Unsupported); ++i) {
    const char* s = to_string(static_cast<Status>(i));
    REQUIRE(s != nullptr);
    CHECK(std::strcmp(s, "Unknown") != 0);
    for (int j = 0; j < i; ++j) CHECK(std::strcmp(s, to_string(static_cast<Status>(j))) != 0);
  }
}

TEST_CASE("Semantic class table round trips and stability follows Table III") {
  for (int c = 0; c < kNumClasses; ++c) CHECK(class_from_kitti(kitti_from_class(c)) == c);
  CHECK(class_from_kitti(10) == kCar);
  CHECK(class_from_kitti(252) == kCar);                // moving-car folds into car
  CHECK(class_from_kitti((7u << 16) | 80u) == kPole);  // instance id in the high bits is ignored
  CHECK(class_from_kitti(0) == kIgnoredClass);
  CHECK(class_from_kitti(52) == kIgnoredClass);
  CHECK(class_from_kitti(12345) == kUnknownClass);
  CHECK(stability_weight(kPerson) == Approx(0.1f));
  CHECK(stability_weight(kTruck) == Approx(0.1f));
  CHECK(stability_weight(kCar) == Approx(0.5f));
  CHECK(stability_weight(kVegetation) == Approx(0.5f));
  CHECK(stability_weight(kPole) == Approx(1.0f));
  CHECK(stability_weight(kBuilding) == Approx(1.0f));
  CHECK(stability_weight(-1) == 0.0f);
}

}  // namespace test_foundation
