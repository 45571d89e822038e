// The vehicle loop in the library (Localizer::localize_next, docs/vehicle-modes.md "The loop"): the same
// answers, bit for bit, as the loop written by hand from track(), localize(scan, prior) and
// localize_sequence(); a start-up, then tracking; a loss detected and the same scan localized again; a
// GNSS prior used at start-up; bad odometry refused with the drive restarted.
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <vector>

#include "gsf/localizer.h"
#include "ready_localizer.h"
#include "tiny_world.h"

namespace test_localize_next {

using namespace gsf;

namespace {

using Ready = gsf_test::ReadyLocalizer;

// The odometry from query k - 1 to query k (the tiny world's queries are metres apart).
Eigen::Isometry3d odometry(const gsf_test::TinyWorld& w, uint32_t k) {
  return k == 0 ? Eigen::Isometry3d::Identity() : w.queries[k - 1].truth.inverse() * w.queries[k].truth;
}

// docs/vehicle-modes.md's loop, written by hand.
struct HandLoop {
  Localizer& loc;
  bool have_pose = false;
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  void step(const ScanView& scan, const Eigen::Isometry3d& odo, const PositionPrior* gnss, LocalizeResult* r) {
    bool sequence = false;
    if (have_pose) loc.track(scan, pose * odo, r);
    if (!have_pose || !(r->status == Status::Ok && r->confident)) {
      if (gnss) {
        loc.localize(scan, *gnss, r);
      } else {
        loc.localize_sequence(scan, odo, r);
        sequence = true;
      }
    }
    if (!sequence) loc.reset_sequence();
    have_pose = r->status == Status::Ok && r->confident;
    if (have_pose) pose = r->map_frame_T_scan;
  }
};

bool same_bits(const LocalizeResult& a, const LocalizeResult& b) {
  return a.status == b.status && a.map_frame_T_scan.matrix() == b.map_frame_T_scan.matrix() &&
         a.confidence == b.confidence && a.confident == b.confident && a.tracked == b.tracked &&
         a.prior_used == b.prior_used && a.window_combined == b.window_combined && a.sequence_index == b.sequence_index;
}

}  // namespace

TEST_CASE("localize_next answers as the loop written by hand, bit for bit, with and without a GNSS prior") {
  const auto& w = gsf_test::tiny_world();
  for (const bool with_gnss : {false, true}) {
    Ready lib(w), hand(w);
    HandLoop loop{hand.loc};
    uint32_t tracked = 0, confident = 0, lost = 0;
    bool previous_confident = false;
    // Twice over the queries: the second pass starts from the last query's pose, a jump the odometry
    // carries exactly (every scan after the first of the drive is tracked or a loss).
    for (uint32_t pass = 0; pass < 2; ++pass) {
      for (uint32_t k = 0; k < w.queries.size(); ++k) {
        const auto& q = w.queries[k];
        Eigen::Isometry3d odo = pass == 1 && k == 0 ? w.queries.back().truth.inverse() * q.truth : odometry(w, k);
        if (k == w.queries.size() / 2) odo.translation().x() += 30.0;  // a loss: the same scan from scratch
        PositionPrior gnss;
        gnss.x = q.truth.translation().x() + 4.0;
        gnss.y = q.truth.translation().y() - 3.0;
        gnss.radius_m = 20.0f;
        LocalizeResult a, b;
        lib.loc.localize_next(q.view(), odo, with_gnss ? &gnss : nullptr, &a);
        loop.step(q.view(), odo, with_gnss ? &gnss : nullptr, &b);
        INFO("pass " << pass << " query " << k << (with_gnss ? " with a prior" : ""));
        CHECK(same_bits(a, b));
        // Tracking runs after a confident scan only; a loss is a tracked attempt that fell back.
        CHECK((!a.tracked || previous_confident));
        CHECK(a.track_lost == (previous_confident && !a.tracked));
        previous_confident = a.status == Status::Ok && a.confident;
        tracked += a.tracked;
        lost += a.track_lost;
        confident += a.status == Status::Ok && a.confident;
        // Never a confident wrong pose.
        if (a.status == Status::Ok && a.confident) CHECK(gsf_test::pose_ok(a.map_frame_T_scan, q.truth));
      }
    }
    CHECK(tracked > w.queries.size());  // most scans after the start-up are tracked
    CHECK(confident > w.queries.size());
    CHECK(lost >= 2);  // the two 30 m odometry errors
  }
}

TEST_CASE("localize_next: start-up, tracking, a loss localized again on its scan, a restart after bad odometry") {
  const auto& w = gsf_test::tiny_world();
  Ready r(w);
  const auto& q0 = w.queries[0];
  const auto& q1 = w.queries[1];
  LocalizeResult a;
  REQUIRE(r.loc.localize_next(q0.view(), Eigen::Isometry3d::Identity(), nullptr, &a) == Status::Ok);
  CHECK(!a.tracked);
  CHECK(!a.track_lost);
  CHECK(a.sequence_index == 0);  // the start-up went through the window
  REQUIRE(a.confident);
  REQUIRE(gsf_test::pose_ok(a.map_frame_T_scan, q0.truth));

  // The next scan with the true odometry: tracked.
  REQUIRE(r.loc.localize_next(q1.view(), odometry(w, 1), nullptr, &a) == Status::Ok);
  CHECK(a.tracked);
  CHECK(a.query_instances == 0);  // no global search ran
  CHECK(gsf_test::pose_ok(a.map_frame_T_scan, q1.truth));

  // An odometry 30 m off: tracking loses the scan, and the same scan is localized from scratch.
  Eigen::Isometry3d off = Eigen::Isometry3d::Identity();
  off.translation() = Eigen::Vector3d(30.0, 0.0, 0.0);
  r.loc.localize_next(q1.view(), off, nullptr, &a);
  CHECK(a.track_lost);
  CHECK(!a.tracked);
  CHECK(a.query_instances > 0);  // the global search ran
  if (a.status == Status::Ok && a.confident) CHECK(gsf_test::pose_ok(a.map_frame_T_scan, q1.truth));

  // A non-finite odometry is refused and the drive restarts: the next call is a start-up, not tracked.
  Eigen::Isometry3d bad = Eigen::Isometry3d::Identity();
  bad.translation().x() = std::numeric_limits<double>::quiet_NaN();
  CHECK(r.loc.localize_next(q1.view(), bad, nullptr, &a) == Status::InvalidArgument);
  r.loc.localize_next(q1.view(), Eigen::Isometry3d::Identity(), nullptr, &a);
  CHECK(!a.tracked);
  CHECK(!a.track_lost);
  CHECK(a.sequence_index == 0);
  // reset_drive() does the same.
  r.loc.reset_drive();
  r.loc.localize_next(q1.view(), Eigen::Isometry3d::Identity(), nullptr, &a);
  CHECK(!a.tracked);
  CHECK(a.sequence_index == 0);

  // Before init: NotInitialized.
  Localizer fresh;
  CHECK(fresh.localize_next(q0.view(), Eigen::Isometry3d::Identity(), nullptr, &a) == Status::NotInitialized);
}

TEST_CASE("localize_next with a GNSS prior starts from it; a prior 5 km off is never a confident pose") {
  const auto& w = gsf_test::tiny_world();
  Ready r(w);
  const auto& q = w.queries[0];
  PositionPrior gnss;
  gnss.x = q.truth.translation().x() + 5.0;
  gnss.y = q.truth.translation().y();
  gnss.radius_m = 20.0f;
  LocalizeResult a;
  r.loc.localize_next(q.view(), Eigen::Isometry3d::Identity(), &gnss, &a);
  CHECK(a.prior_used);
  CHECK(!a.tracked);
  if (a.status == Status::Ok && a.confident) CHECK(gsf_test::pose_ok(a.map_frame_T_scan, q.truth));
  r.loc.reset_drive();
  gnss.x = q.truth.translation().x() + 5000.0;
  r.loc.localize_next(q.view(), Eigen::Isometry3d::Identity(), &gnss, &a);
  CHECK(a.prior_used);
  CHECK(!(a.status == Status::Ok && a.confident));
}

}  // namespace test_localize_next
