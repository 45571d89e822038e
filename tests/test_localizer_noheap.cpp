// Zero heap allocations over >= 1,000 localize calls after init (counting allocator).
#include <catch2/catch.hpp>

#include "alloc_counter.h"
#include "gsf/localizer.h"
#include "tiny_world.h"

using namespace gsf;

TEST_CASE("localize() never allocates after init") {
  const auto& w = gsf_test::tiny_world();
  std::vector<uint64_t> ws(Localizer::required_bytes(w.config) / 8 + 2);
  Localizer loc;
  REQUIRE(loc.init(w.config, w.map, ws.data(), ws.size() * 8) == Status::Ok);
  LocalizeResult r;
  uint32_t calls = 0, ok = 0;
  gsf_test::AllocationScope scope;
  while (calls < 1000) {
    for (const auto& q : w.queries) {
      loc.set_use_gsf(calls % 2 == 0);
      ok += loc.localize(q.view(), &r) == Status::Ok;
      if (++calls >= 1000) break;
    }
  }
  CHECK(scope.allocations() == 0);
  CHECK(calls == 1000);
  CHECK(ok > 500);  // the calls did real work
}
