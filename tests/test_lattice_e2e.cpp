// End to end on the tiny-lattice world (a 2-D lattice of identical columns): whole-scan verification
// of the peeled hypotheses localizes lattice queries that the paper's pipeline (the maximum clique's
// pose) cannot, and the GSF filter still earns its place where there is no verification; the missing
// twin's proposals (twin_completion.h) run in its zone and lose nothing there. Bars are the measured
// counts with margin (docs/results.md has the suite's numbers).
#include <catch2/catch.hpp>

#include <algorithm>
#include <vector>

#include "gsf/localizer.h"
#include "tiny_world.h"

namespace test_lattice_e2e {

using namespace gsf;

namespace {

struct Count {
  int zone = 0, zone_ok = 0, answered_wrong = 0, proposed = 0, found = 0;
};

Count run(bool gsf_on, bool verify, bool twins = true) {
  const gsf_test::TinyWorld& w = gsf_test::tiny_lattice_world();
  LocalizerConfig cfg = w.config;
  cfg.gsf.enabled = gsf_on;
  cfg.verify.enabled = verify;
  cfg.hypotheses.complete_twins = twins;
  if (!verify) {  // the paper's pipeline: the maximum clique's pose, no upright prior
    cfg.hypotheses.max_hypotheses = 1;
    cfg.hypotheses.max_tilt_deg = 0.0f;
  }
  std::vector<uint64_t> ws(Localizer::required_bytes(cfg) / 8 + 2);
  Localizer loc;
  REQUIRE(loc.init(cfg, w.map, ws.data(), ws.size() * 8) == Status::Ok);
  Count c;
  for (const auto& q : w.queries) {
    LocalizeResult r;
    loc.localize(q.view(), &r);
    const bool ok = r.status == Status::Ok && gsf_test::pose_ok(r.map_T_scan, q.truth);
    if (q.in_zone) {
      ++c.zone;
      c.zone_ok += ok;
    }
    if (r.status == Status::Ok && r.confident && !ok) ++c.answered_wrong;
    c.proposed += r.twins_proposed > 0;
    c.found += r.twins_found > 0;
  }
  return c;
}

}  // namespace

TEST_CASE("Tiny lattice: verification localizes lattice queries the maximum clique alone cannot") {
  const gsf_test::TinyWorld& w = gsf_test::tiny_lattice_world();
  REQUIRE(w.map.counts.semantic_tiles > 0);
  const Count paper_instance = run(false, false), paper_gsf = run(true, false);
  const Count verified_instance = run(false, true), verified_gsf = run(true, true);
  INFO("zone successes of " << paper_instance.zone << ": instance " << paper_instance.zone_ok << ", gsf "
                            << paper_gsf.zone_ok << "; with verification: instance " << verified_instance.zone_ok
                            << ", gsf " << verified_gsf.zone_ok);
  REQUIRE(paper_instance.zone >= 8);
  // Measured (instance / gsf, of 10): x86-64 3 / 5 with the paper's pipeline, 8 / 5 with hypotheses
  // and verification; ARM64 4 / 4 and 7 / 7. Ten queries are few, and the last bits of floating point differ between
  // the ISAs, so the bars are on what holds on both: verification adds successes in both modes together and its better
  // mode localizes most of the zone.
  const int paper = paper_instance.zone_ok + paper_gsf.zone_ok;
  const int verified = verified_instance.zone_ok + verified_gsf.zone_ok;
  CHECK(verified >= paper + 3);
  CHECK(std::max(verified_instance.zone_ok, verified_gsf.zone_ok) * 10 >= paper_instance.zone * 6);
  CHECK(std::max(verified_instance.zone_ok, verified_gsf.zone_ok) >
        std::max(paper_instance.zone_ok, paper_gsf.zone_ok));
}

TEST_CASE("Tiny lattice: the missing twin's proposals run in the zone and lose nothing there") {
  // The lattice's hypotheses are rows of twins at two headings, so the proposals run on its zone queries
  // (docs/confidence.md, *The missing twin*); here generation already holds every true pose (measured:
  // 13 and 11 of the queries proposed, none outscored the answer), so the answers must stay as they are.
  for (bool gsf_on : {false, true}) {
    const Count off = run(gsf_on, true, false), on = run(gsf_on, true, true);
    INFO("gsf " << gsf_on << ": zone " << off.zone_ok << " -> " << on.zone_ok << " of " << on.zone << ", wrong "
                << off.answered_wrong << " -> " << on.answered_wrong << ", proposed " << on.proposed << ", found "
                << on.found);
    CHECK(off.proposed == 0);
    CHECK(on.proposed >= on.zone / 2);
    CHECK(on.zone_ok >= off.zone_ok);
    CHECK(on.answered_wrong <= off.answered_wrong);
  }
}

}  // namespace test_lattice_e2e
