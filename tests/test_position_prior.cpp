// The position prior (position_prior.h) on the simulator's tiny world, against the simulator's truth:
// a prior around the truth keeps the right answers and restricts the search; a prior elsewhere never
// gives a confident answer; invalid priors are refused.
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <vector>

#include "gsf/localizer.h"
#include "gsf/port/logit_synthesis.h"
#include "ready_localizer.h"
#include "tiny_world.h"

namespace test_position_prior {

using namespace gsf;
using gsf_test::tiny_world;

namespace {

using Ready = gsf_test::ReadyLocalizer;

// A disc of `radius` whose centre lies `offset` metres from the truth, in a direction that turns with k.
PositionPrior prior_near(const Eigen::Isometry3d& truth, double offset, float radius, uint32_t k) {
  const double a = 0.7 * k + 0.3;
  PositionPrior p;
  p.x = truth.translation().x() + offset * std::cos(a);
  p.y = truth.translation().y() + offset * std::sin(a);
  p.radius_m = radius;
  return p;
}

double yaw_deg(const Eigen::Isometry3d& T) { return std::atan2(T.linear()(1, 0), T.linear()(0, 0)) * 180.0 / M_PI; }

}  // namespace

TEST_CASE("Invalid priors are refused: non-finite centre, radius or heading, radius <= 0, tolerance beyond 180") {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  PositionPrior ok;
  ok.radius_m = 10.0f;
  CHECK(validate(ok) == Status::Ok);
  PositionPrior p = ok;
  p.x = nan;
  CHECK(validate(p) == Status::InvalidArgument);
  p = ok;
  p.y = std::numeric_limits<double>::infinity();
  CHECK(validate(p) == Status::InvalidArgument);
  for (float r : {-1.0f, 0.0f, float(nan), std::numeric_limits<float>::infinity()}) {
    p = ok;
    p.radius_m = r;
    CHECK(validate(p) == Status::InvalidArgument);
  }
  p = ok;
  p.has_heading = true;
  p.heading_deg = float(nan);
  CHECK(validate(p) == Status::InvalidArgument);
  p.heading_deg = 10.0f;
  for (float tol : {-1.0f, 181.0f, float(nan)}) {
    p.heading_tolerance_deg = tol;
    CHECK(validate(p) == Status::InvalidArgument);
  }
  p.heading_tolerance_deg = 180.0f;
  CHECK(validate(p) == Status::Ok);

  // The localizer refuses them before any work, with the status in the result too.
  const auto& w = tiny_world();
  Ready r(w);
  LocalizeResult out;
  out.inliers = 7;
  PositionPrior bad = ok;
  bad.radius_m = -5.0f;
  CHECK(r.loc.localize(w.queries[0].view(), bad, &out) == Status::InvalidArgument);
  CHECK(out.status == Status::InvalidArgument);
  CHECK(out.inliers == 0);
  bad = ok;
  bad.x = nan;
  CHECK(r.loc.localize(w.queries[0].view(), bad, &out) == Status::InvalidArgument);
}

TEST_CASE("A prior region holds poses in its disc and heading tolerance, across the +-180 deg wrap") {
  PositionPrior p;
  p.x = 100.0;
  p.y = -50.0;
  p.radius_m = 20.0f;
  p.has_heading = true;
  p.heading_deg = 175.0f;
  p.heading_tolerance_deg = 10.0f;
  MapGeoreference g = local_georeference();
  g.origin[0] = 90.0;  // map-local = map frame - origin
  g.origin[1] = -40.0;
  const PriorRegion r = prior_region(p, g);
  CHECK(r.cx == 10.0f);
  CHECK(r.cy == -10.0f);
  auto pose = [](double x, double y, double deg) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = Eigen::AngleAxisd(deg * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    T.translation() = Eigen::Vector3d(x, y, 1.0);
    return T;
  };
  CHECK(r.contains(pose(10.0 + 19.0, -10.0, -175.0), 0.0, 0.0));  // 10 deg from 175 across the wrap
  CHECK(!r.contains(pose(10.0 + 21.0, -10.0, 175.0), 0.0, 0.0));  // outside the disc
  CHECK(r.contains(pose(10.0 + 21.0, -10.0, 175.0), 2.0, 0.0));   // ... inside its slack
  CHECK(!r.contains(pose(10.0, -10.0, 150.0), 0.0, 5.0));         // 25 deg off
  CHECK(!r.contains(pose(10.0, -10.0, -5.0), 0.0, 5.0));          // turned round
  // A map point is reachable from inside the disc when within radius + its query range + slack.
  CHECK(r.reaches(10.0f + 20.0f + 30.0f + kPriorVertexSlackM - 0.1f, -10.0f, 30.0f));
  CHECK(!r.reaches(10.0f + 20.0f + 30.0f + kPriorVertexSlackM + 0.1f, -10.0f, 30.0f));
}

TEST_CASE("A 20 m prior around the truth gives the same right answers from fewer candidates") {
  const auto& w = tiny_world();
  Ready r(w);
  uint32_t right_free = 0, right_prior = 0, restricted = 0, fewer = 0;
  for (uint32_t k = 0; k < w.queries.size(); ++k) {
    const auto& q = w.queries[k];
    LocalizeResult free, prior;
    const bool free_ok = r.loc.localize(q.view(), &free) == Status::Ok && gsf_test::pose_ok(free.map_T_scan, q.truth);
    const Status s = r.loc.localize(q.view(), prior_near(q.truth, 12.0, 20.0f, k), &prior);
    const bool prior_ok = s == Status::Ok && gsf_test::pose_ok(prior.map_T_scan, q.truth);
    INFO("query " << k << ": " << to_string(s) << ", confidence " << prior.confidence);
    CHECK(prior.prior_used);
    if (free_ok) CHECK(prior_ok);  // every right one-shot answer stays right
    if (s == Status::Ok && prior.confident) CHECK(prior_ok);
    right_free += free_ok;
    right_prior += prior_ok;
    restricted += prior.prior_outside_matches > 0;
    // A declined answer that one-shot vouched for is one-shot's result, with one-shot's candidates.
    fewer += prior.prior_one_shot_vouched || prior.match_candidates < free.match_candidates;
  }
  CHECK(right_prior >= right_free);
  CHECK(right_free * 10 >= w.queries.size() * 9);
  CHECK(restricted == w.queries.size());  // the search itself was restricted on every scan
  CHECK(fewer == w.queries.size());
}

TEST_CASE("A prior 100 m off never gives a confident answer; one off the map gives none at all") {
  const auto& w = tiny_world();
  Ready r(w);
  uint32_t answered = 0, confident_wrong = 0;
  for (uint32_t k = 0; k < w.queries.size(); ++k) {
    const auto& q = w.queries[k];
    LocalizeResult out;
    const Status s = r.loc.localize(q.view(), prior_near(q.truth, 100.0, 20.0f, k), &out);
    answered += s == Status::Ok;
    if (s == Status::Ok) {
      // Every answer lies in the disc (truth 100 m from its centre): wrong by construction.
      CHECK(!gsf_test::pose_ok(out.map_T_scan, q.truth));
      confident_wrong += out.confident;
    } else {
      CHECK(s == Status::NoSolution);
    }
  }
  INFO(answered << " of " << w.queries.size() << " answered");
  CHECK(confident_wrong == 0);
  // 5 km from the map: no map triangle is within reach, so no candidate at all.
  LocalizeResult out;
  PositionPrior far = prior_near(w.queries[0].truth, 5000.0, 20.0f, 0);
  CHECK(r.loc.localize(w.queries[0].view(), far, &out) == Status::NoSolution);
  CHECK(out.triangle_matches == 0);
  CHECK(out.prior_outside_matches > 0);
}

// A lattice car park of identical columns: a prior away from the truth can hold a copy of the scene, which
// the local probes cannot tell from the truth; a thin margin over the rivals sends the answer to a global
// check, and no answer is confident.
TEST_CASE("On a lattice, priors 30-100 m off never give a confident answer; right ones keep theirs") {
  const auto& w = gsf_test::tiny_lattice_world();
  Ready r(w);
  uint32_t confident_wrong = 0, checked = 0, vouched = 0;
  // The labels as they are, and again through 2x and 5x the network's confusions (seeded).
  for (float confusion : {0.0f, 2.0f, 5.0f}) {
    uint32_t right_free = 0, right_prior = 0;
    for (uint32_t k = 0; k < w.queries.size(); ++k) {
      gsf_test::QueryScan q = w.queries[k];
      if (confusion > 0.0f) {
        port::LogitModel noisy;
        noisy.seed = 77;
        noisy.confusion_scale = confusion;
        port::synthesize_logits(noisy, k, q.labels.data(), uint32_t(q.labels.size()), q.logits.data(), q.labels.data(),
                                w.config.classes);
      }
      LocalizeResult free, near;
      right_free += r.loc.localize(q.view(), &free) == Status::Ok && free.confident &&
                    gsf_test::pose_ok(free.map_T_scan, q.truth);
      const Status s = r.loc.localize(q.view(), prior_near(q.truth, 8.0, 15.0f, k), &near);
      right_prior += s == Status::Ok && near.confident && gsf_test::pose_ok(near.map_T_scan, q.truth);
      if (near.prior_one_shot_vouched) {  // one-shot's own result, with the prior's fields
        ++vouched;
        CHECK(near.prior_used);
        CHECK(near.prior_asked_one_shot);
        CHECK(near.confidence == free.confidence);
        CHECK(near.map_T_scan.isApprox(free.map_T_scan, 0.0));
      }
      confident_wrong += s == Status::Ok && near.confident && !gsf_test::pose_ok(near.map_T_scan, q.truth);
      checked += near.prior_global_check;
      if (confusion > 0.0f) continue;  // the wrong priors under label noise: the next test
      for (double off : {30.0, 45.0, 60.0, 100.0}) {
        LocalizeResult out;
        if (r.loc.localize(q.view(), prior_near(q.truth, off, 15.0f, k), &out) != Status::Ok) continue;
        INFO("query " << k << ", prior " << off << " m off: confidence " << out.confidence);
        CHECK(!out.confident);
        confident_wrong += out.confident;
        checked += out.prior_global_check;
      }
    }
    // The prior's rivals come from inside its disc, so its own confidence is another measurement than
    // the one-shot one: an answer on the rule's edge can fall either side. A declined answer asks
    // one-shot, which vouches for it at the same pose (Localizer::localize with a prior), so a right
    // prior answers every query one-shot answers right.
    INFO("confusion x" << confusion << ": " << right_free << " answered right without a prior, " << right_prior
                       << " with one");
    CHECK(right_prior >= right_free);
  }
  INFO(vouched << " vouched for by one-shot; " << checked << " checked");
  CHECK(confident_wrong == 0);
  CHECK(vouched > 0);  // under label noise (2 of 39 scans on x86-64): the path above is exercised
}

// Under a poor network's labels the truth outside a wrong prior can score a little below the copy of the
// scene inside it: the global check must then still doubt the copy (suite seeds 7 and 10 at label noise
// 0.15 answered 100 m off at 0.90 and 0.997 when only a pose scoring higher counted: CHANGELOG). The
// tiny worlds hold no such near tie (this test passes without that rule too; the suite measures it);
// it guards the wrong-prior property under label noise, which the clean-label tests above do not.
TEST_CASE("Under heavy label noise, priors 30-100 m off never give a confident answer") {
  for (const gsf_test::TinyWorld* w : {&tiny_world(), &gsf_test::tiny_lattice_world()}) {
    Ready r(*w);
    uint32_t checked = 0, answered = 0;
    for (uint32_t k = 0; k < w->queries.size(); ++k) {
      gsf_test::QueryScan q = w->queries[k];  // its labels again through 5x the network's confusions
      port::LogitModel noisy;
      noisy.seed = 77;
      noisy.confusion_scale = 5.0f;
      port::synthesize_logits(noisy, k, q.labels.data(), uint32_t(q.labels.size()), q.logits.data(), q.labels.data(),
                              w->config.classes);
      for (double off : {30.0, 60.0, 100.0}) {
        LocalizeResult out;
        if (r.loc.localize(q.view(), prior_near(q.truth, off, 15.0f, k), &out) != Status::Ok) continue;
        ++answered;
        checked += out.prior_global_check;
        INFO("query " << k << ", prior " << off << " m off: confidence " << out.confidence << ", z_rival "
                      << out.confidence_evidence.z_rival);
        CHECK((!out.confident || gsf_test::pose_ok(out.map_T_scan, q.truth)));
      }
    }
    INFO(answered << " with a pose, " << checked << " checked globally");
    CHECK(answered > 0);
  }
}

// The restricted search's rivals all lie in the disc, so a thin margin over them says nothing about a
// copy of the scene outside it: every confident answer with a prior either beats its rivals by
// Localizer::kPriorGlobalCheckZ, with no hypothesis outside the disc near its inlier count
// (Localizer::kPriorCopyInlierShare), or went through the global check, however well it agrees with the
// map (a gate on the agreement share let a confident answer 110 m off through on a suite world: CHANGELOG).
TEST_CASE("A confident answer with a prior and a thin margin or a copy outside has always been checked globally") {
  uint32_t unchecked = 0, copies_seen = 0;
  for (const gsf_test::TinyWorld* w : {&tiny_world(), &gsf_test::tiny_lattice_world()}) {
    Ready r(*w);
    for (uint32_t k = 0; k < w->queries.size(); ++k)
      for (double off : {0.0, 8.0, 40.0}) {
        LocalizeResult out;
        if (r.loc.localize(w->queries[k].view(), prior_near(w->queries[k].truth, off, 15.0f, k), &out) != Status::Ok)
          continue;
        // A check ran on a confident answer only, and for the reason its trigger read (z_rival before
        // the check could lower it).
        if (out.prior_global_check) {
          CHECK(out.prior_confident_before_check);
          CHECK((out.prior_trigger_z_rival < Localizer::kPriorGlobalCheckZ || out.prior_dropped_best_inliers > 0 ||
                 out.inliers <= w->config.hypotheses.min_inliers));
        }
        // A vouched answer is one-shot's own result: its rivals are one-shot's, not the disc's.
        if (!out.confident || out.prior_global_check || out.prior_one_shot_vouched) continue;
        CHECK(out.prior_confident_before_check);
        CHECK(out.prior_trigger_z_rival == out.confidence_evidence.z_rival);  // unchecked: unchanged
        INFO("query " << k << ", prior " << off << " m off: z_rival " << out.confidence_evidence.z_rival
                      << ", agreement " << out.confidence_evidence.agreement);
        CHECK(out.confidence_evidence.z_rival >= Localizer::kPriorGlobalCheckZ);
        CHECK(out.inliers > 0);  // the answer's hypothesis's TLS inliers
        CHECK(out.prior_dropped_best_inliers < Localizer::kPriorCopyInlierShare * out.inliers);
        unchecked += 1;
        copies_seen += out.prior_dropped_best_inliers > 0;
      }
  }
  INFO(unchecked << " confident answers not checked, " << copies_seen << " with a hypothesis outside the disc");
  CHECK(unchecked > 0);
  CHECK(copies_seen > 0);  // the dropped hypotheses' inliers were counted
}

TEST_CASE("A heading in the prior keeps the right answer; the opposite heading gives no confident one") {
  const auto& w = tiny_world();
  Ready r(w);
  uint32_t checked = 0;
  for (uint32_t k = 0; k < w.queries.size(); k += 3) {
    const auto& q = w.queries[k];
    PositionPrior p = prior_near(q.truth, 5.0, 20.0f, k);
    p.has_heading = true;
    p.heading_deg = float(yaw_deg(q.truth) + 8.0);
    p.heading_tolerance_deg = 15.0f;
    LocalizeResult right, turned;
    REQUIRE(r.loc.localize(q.view(), p, &right) == Status::Ok);
    CHECK(gsf_test::pose_ok(right.map_T_scan, q.truth));
    p.heading_deg = float(yaw_deg(q.truth) + 180.0);
    p.heading_tolerance_deg = 30.0f;
    const Status s = r.loc.localize(q.view(), p, &turned);
    CHECK(!(s == Status::Ok && turned.confident));
    if (s == Status::Ok) CHECK(std::fabs(std::remainder(yaw_deg(turned.map_T_scan) - p.heading_deg, 360.0)) <= 35.0);
    ++checked;
  }
  CHECK(checked >= 5);
}

TEST_CASE("Without a prior nothing changes: localize(scan) and the prior-free fields") {
  const auto& w = tiny_world();
  Ready a(w), b(w);
  for (uint32_t k = 0; k < 4; ++k) {
    LocalizeResult x, y;
    a.loc.localize(w.queries[k].view(), &x);
    // A localizer that ran with a prior before: the region does not stick.
    b.loc.localize(w.queries[k].view(), prior_near(w.queries[k].truth, 100.0, 10.0f, k), &y);
    b.loc.localize(w.queries[k].view(), &y);
    CHECK(x.map_T_scan.matrix() == y.map_T_scan.matrix());
    CHECK(x.confidence == y.confidence);
    CHECK(x.match_candidates == y.match_candidates);
    CHECK(!y.prior_used);
    CHECK(y.prior_outside_matches == 0);
  }
}

TEST_CASE("With a prior the query runs on the scan's labels, without the GSF filter") {
  // The disc narrows the candidates as the filter would, and the softmax of the logits was most of the
  // voxel layer's work: the logits then change nothing, and no field is probed. Without a prior they do
  // (the filter probes the fields), and one-shot is the same after a prior query as before it.
  const auto& w = tiny_world();
  Ready r(w);
  uint32_t probed_without_prior = 0, compared = 0;
  for (uint32_t k = 0; k < 6; ++k) {
    const auto& q = w.queries[k];
    const PositionPrior prior = prior_near(q.truth, 12.0, 20.0f, k);
    ScanView labels_only = q.view();
    REQUIRE(labels_only.logits != nullptr);
    labels_only.logits = nullptr;
    labels_only.logit_dim = 0;
    LocalizeResult with_logits, with_labels, free;
    const Status a = r.loc.localize(q.view(), prior, &with_logits);
    const Status b = r.loc.localize(labels_only, prior, &with_labels);
    r.loc.localize(q.view(), &free);
    probed_without_prior += free.field_probes > 0;
    // A declined answer asks one-shot (Localizer::localize with a prior), which reads the logits.
    if (with_logits.prior_asked_one_shot || with_labels.prior_asked_one_shot) continue;
    ++compared;
    CHECK(a == b);
    CHECK(with_logits.map_T_scan.matrix() == with_labels.map_T_scan.matrix());
    CHECK(with_logits.confidence == with_labels.confidence);
    CHECK(with_logits.field_probes == 0);
    CHECK(with_labels.field_probes == 0);
  }
  CHECK(probed_without_prior == 6);
  CHECK(compared >= 4);
}

}  // namespace test_position_prior
