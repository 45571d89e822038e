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

// The other paths: refinement on (the tiny world), and a lattice whose queries run the shift votes,
// the coarse/full/refined verification and the heading votes at full tilt (tiny-lattice world).
TEST_CASE("localize() never allocates after init with refinement on, nor on a lattice") {
  for (int which = 0; which < 2; ++which) {
    const auto& w = which == 0 ? gsf_test::tiny_world() : gsf_test::tiny_lattice_world();
    LocalizerConfig cfg = w.config;
    cfg.refine.enabled = which == 0;
    cfg.refine.max_map_points = w.map.counts.refine_points + 1;
    std::vector<uint64_t> ws(Localizer::required_bytes(cfg) / 8 + 2);
    Localizer loc;
    REQUIRE(loc.init(cfg, w.map, ws.data(), ws.size() * 8) == Status::Ok);
    LocalizeResult r;
    uint32_t calls = 0, ok = 0, refined = 0, voted = 0;
    gsf_test::AllocationScope scope;
    for (int pass = 0; pass < 2; ++pass)
      for (const auto& q : w.queries) {
        loc.set_use_gsf(pass == 0);
        ok += loc.localize(q.view(), &r) == Status::Ok;
        refined += r.refined;
        voted += r.hypotheses > r.clique_searches;  // more hypotheses than cliques: shift votes ran
        ++calls;
      }
    const uint64_t allocations = scope.allocations();  // before INFO, which allocates its message
    INFO((which == 0 ? "tiny world, refinement" : "tiny lattice") << ": " << ok << " of " << calls << " answered");
    CHECK(allocations == 0);
    CHECK(ok * 2 > calls);
    if (which == 0) CHECK(refined > 0);
    else CHECK(voted > 0);
  }
}
