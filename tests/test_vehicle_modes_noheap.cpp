// Zero heap allocations after init in the vehicle modes: localize with a position prior (right and
// wrong) and track (near and far predictions), over every query of the tiny world (counting allocator).
#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

#include "alloc_counter.h"
#include "gsf/localizer.h"
#include "tiny_world.h"

using namespace gsf;

TEST_CASE("localize with a prior and track never allocate after init") {
  const auto& w = gsf_test::tiny_world();
  std::vector<uint64_t> ws(Localizer::required_bytes(w.config) / 8 + 2);
  Localizer loc;
  REQUIRE(loc.init(w.config, w.map, ws.data(), ws.size() * 8) == Status::Ok);
  LocalizeResult r;
  uint32_t calls = 0, ok = 0, confident = 0;
  gsf_test::AllocationScope scope;
  for (const auto& q : w.queries) {
    for (double off : {5.0, 100.0}) {
      PositionPrior p;
      p.x = q.truth.translation().x() + off;
      p.y = q.truth.translation().y();
      p.radius_m = 20.0f;
      p.has_heading = off < 50.0;
      p.heading_deg = float(std::atan2(q.truth.linear()(1, 0), q.truth.linear()(0, 0)) * 180.0 / M_PI);
      p.heading_tolerance_deg = 20.0f;
      ok += loc.localize(q.view(), p, &r) == Status::Ok;
      ++calls;
    }
    for (double off : {1.0, 30.0}) {
      Eigen::Isometry3d predicted = q.truth;
      predicted.translation().y() += off;
      ok += loc.track(q.view(), predicted, &r) == Status::Ok;
      confident += r.confident;
      ++calls;
    }
  }
  const uint64_t allocations = scope.allocations();
  CHECK(allocations == 0);
  CHECK(ok > calls / 2);  // the calls did real work
  CHECK(confident > 0);
}

TEST_CASE("localize_sequence (several scans) never allocates after init") {
  const auto& w = gsf_test::tiny_lattice_world();
  LocalizerConfig cfg = w.config;
  cfg.window.scans = 4;
  std::vector<uint64_t> ws(Localizer::required_bytes(cfg) / 8 + 2);
  Localizer loc;
  REQUIRE(loc.init(cfg, w.map, ws.data(), ws.size() * 8) == Status::Ok);
  LocalizeResult r;
  uint32_t combined = 0;
  gsf_test::AllocationScope scope;
  for (uint32_t k = 0; k < w.queries.size(); ++k) {
    // Consecutive queries are metres apart: the odometry between them fills the window.
    const Eigen::Isometry3d odo =
        k == 0 ? Eigen::Isometry3d::Identity() : w.queries[k - 1].truth.inverse() * w.queries[k].truth;
    loc.localize_sequence(w.queries[k].view(), odo, &r);
    combined += r.window_combined;
    if (k == w.queries.size() / 2) loc.reset_sequence();
  }
  const uint64_t allocations = scope.allocations();
  CHECK(allocations == 0);
  CHECK(r.sequence_index > 0);
  INFO("window answers " << combined);
}

TEST_CASE("localize_next (the vehicle loop) never allocates after init") {
  const auto& w = gsf_test::tiny_world();
  std::vector<uint64_t> ws(Localizer::required_bytes(w.config) / 8 + 2);
  Localizer loc;
  REQUIRE(loc.init(w.config, w.map, ws.data(), ws.size() * 8) == Status::Ok);
  LocalizeResult r;
  uint32_t tracked = 0, lost = 0;
  gsf_test::AllocationScope scope;
  for (uint32_t k = 0; k < w.queries.size(); ++k) {
    Eigen::Isometry3d odo =
        k == 0 ? Eigen::Isometry3d::Identity() : w.queries[k - 1].truth.inverse() * w.queries[k].truth;
    if (k == w.queries.size() / 2) odo.translation().x() += 30.0;  // a loss
    PositionPrior gnss;
    gnss.x = w.queries[k].truth.translation().x();
    gnss.y = w.queries[k].truth.translation().y();
    gnss.radius_m = 20.0f;
    loc.localize_next(w.queries[k].view(), odo, k % 3 == 0 ? &gnss : nullptr, &r);
    tracked += r.tracked;
    lost += r.track_lost;
  }
  const uint64_t allocations = scope.allocations();
  CHECK(allocations == 0);
  CHECK(tracked > 0);  // the calls did real work: tracked scans and a loss
  CHECK(lost > 0);
}
