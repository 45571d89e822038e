// Zero heap allocations over 1,000 localize calls after init (counting allocator); in a slow build
// (ASan, qemu: short_run.h) each query once per mode.
#include <catch2/catch.hpp>

#include "alloc_counter.h"
#include "gsf/localizer.h"
#include "short_run.h"
#include "tiny_world.h"

using namespace gsf;

TEST_CASE("localize() never allocates after init") {
  const auto& w = gsf_test::tiny_world();
  std::vector<uint64_t> ws(Localizer::required_bytes(w.config) / 8 + 2);
  Localizer loc;
  REQUIRE(loc.init(w.config, w.map, ws.data(), ws.size() * 8) == Status::Ok);
  LocalizerConfig off = w.config;  // GSF off: the instance-only paths
  off.gsf.enabled = false;
  std::vector<uint64_t> ws_off(Localizer::required_bytes(off) / 8 + 2);
  Localizer loc_off;
  REQUIRE(loc_off.init(off, w.map, ws_off.data(), ws_off.size() * 8) == Status::Ok);
  // Under qemu a call costs ~30x the host's, under ASan ~10x: the same paths (every query of the world,
  // GSF on and off) run once each there; the host release run makes all 1,000 calls.
  const uint32_t target = gsf_test::short_run() ? 2 * static_cast<uint32_t>(w.queries.size()) : 1000;
  LocalizeResult r;
  uint32_t calls = 0, ok = 0;
  gsf_test::AllocationScope scope;
  for (uint32_t pass = 0; calls < target; ++pass) {
    for (const auto& q : w.queries) {  // passes alternate GSF on and off
      ok += (pass % 2 == 0 ? loc : loc_off).localize(q.view(), &r) == Status::Ok;
      if (++calls >= target) break;
    }
  }
  CHECK(scope.allocations() == 0);
  CHECK(calls == target);
  CHECK(ok > target / 2);  // the calls did real work
}

// The other paths: refinement on (the tiny world), a lattice whose queries run the shift votes,
// the coarse/full/refined verification and the heading votes at full tilt (tiny-lattice world), and
// a nuScenes-labelled world (class-table lookups, geometric pole extraction).
TEST_CASE("localize() never allocates after init with refinement on, on a lattice, nor with geometric poles") {
  for (int which = 0; which < 3; ++which) {
    const auto& w = which == 0   ? gsf_test::tiny_world()
                    : which == 1 ? gsf_test::tiny_lattice_world()
                                 : gsf_test::tiny_nuscenes_world();
    LocalizerConfig cfg = w.config;
    cfg.refine.enabled = which == 0;
    std::vector<uint64_t> ws(Localizer::required_bytes(cfg) / 8 + 2);
    Localizer loc;
    REQUIRE(loc.init(cfg, w.map, ws.data(), ws.size() * 8) == Status::Ok);
    LocalizerConfig off = cfg;
    off.gsf.enabled = false;
    std::vector<uint64_t> ws_off(Localizer::required_bytes(off) / 8 + 2);
    Localizer loc_off;
    REQUIRE(loc_off.init(off, w.map, ws_off.data(), ws_off.size() * 8) == Status::Ok);
    LocalizeResult r;
    uint32_t calls = 0, ok = 0, refined = 0, voted = 0, poles = 0;
    gsf_test::AllocationScope scope;
    for (int pass = 0; pass < 2; ++pass)
      for (const auto& q : w.queries) {
        ok += (pass == 0 ? loc : loc_off).localize(q.view(), &r) == Status::Ok;
        refined += r.refined;
        voted += r.hypotheses > r.clique_searches;  // more hypotheses than cliques: shift votes ran
        poles += r.pole_instances > 0;
        ++calls;
      }
    const uint64_t allocations = scope.allocations();  // before INFO, which allocates its message
    INFO((which == 0   ? "tiny world, refinement"
          : which == 1 ? "tiny lattice"
                       : "tiny nuScenes-labelled world")
         << ": " << ok << " of " << calls << " answered");
    CHECK(allocations == 0);
    CHECK(ok * 2 > calls);
    if (which == 0) CHECK(refined > 0);
    else if (which == 1) CHECK(voted > 0);
    else CHECK(poles == calls);
  }
}
