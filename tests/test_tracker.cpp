// Tracking (detail/tracker.h) on the simulator's tiny world, against the simulator's truth: from a
// prediction 1 m / 3 deg off, the pose within 0.3 m / 1 deg and confident, and from one 2.5 m off too
// (within the search's reach); from one 30 m off or turned 180 deg, a loss (not confident); bad
// predictions refused; the same call gives the same bits.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "gsf/detail/tracker.h"
#include "gsf/localizer.h"
#include "ready_localizer.h"
#include "tiny_world.h"

namespace test_tracker {

using namespace gsf;
using gsf_test::tiny_world;

namespace {

using Ready = gsf_test::ReadyLocalizer;

// The truth moved `metres` in a direction that turns with k and turned by +-`deg` (sign alternating).
Eigen::Isometry3d perturbed(const Eigen::Isometry3d& truth, double metres, double deg, uint32_t k) {
  const double a = 1.1 * k + 0.4;
  Eigen::Isometry3d p = truth;
  p.translation() += Eigen::Vector3d(metres * std::cos(a), metres * std::sin(a), 0.0);
  const double turn = (k % 2 ? -deg : deg) * M_PI / 180.0;
  p.linear() = Eigen::AngleAxisd(turn, Eigen::Vector3d::UnitZ()).toRotationMatrix() * truth.linear();
  return p;
}

void errors(const Eigen::Isometry3d& est, const Eigen::Isometry3d& truth, double* metres, double* deg) {
  const Eigen::Isometry3d d = est.inverse() * truth;
  *metres = d.translation().norm();
  *deg = Eigen::AngleAxisd(d.rotation()).angle() * 180.0 / M_PI;
}

}  // namespace

TEST_CASE(
    "Tracking from a prediction 1 m / 3 deg off returns the pose within 0.5 m / 1 deg, 90% within 0.3 m, confident") {
  const auto& w = tiny_world();
  Ready r(w, w.config);
  uint32_t within = 0, confident = 0, refined = 0;
  double worst_m = 0, worst_deg = 0;
  for (uint32_t k = 0; k < w.queries.size(); ++k) {
    const auto& q = w.queries[k];
    LocalizeResult out;
    REQUIRE(r.loc.track(q.view(), perturbed(q.truth, 1.0, 3.0, k), &out) == Status::Ok);
    CHECK(out.tracked);
    CHECK(out.query_instances == 0);  // no global search ran
    double m, deg;
    errors(out.map_T_scan, q.truth, &m, &deg);
    INFO("query " << k << ": " << m << " m, " << deg << " deg, confidence " << out.confidence);
    // ICP's last decimetres differ between ISAs (GCC fuses multiply-adds on ARM64): one tiny-world query
    // ends 0.45 m off there (under 0.3 m on x86-64). Every pose within 0.5 m; 0.3 m for 90% of them.
    CHECK(m < 0.5);
    CHECK(deg < 1.0);
    within += m < 0.3 && deg < 1.0;
    confident += out.confident;
    refined += out.refined;
    worst_m = std::max(worst_m, m);
    worst_deg = std::max(worst_deg, deg);
  }
  INFO("worst " << worst_m << " m, " << worst_deg << " deg; " << confident << " confident");
  CHECK(within * 10 >= w.queries.size() * 9);
  CHECK(confident * 10 >= w.queries.size() * 9);
  CHECK(refined == w.queries.size());
}

TEST_CASE("Tracking from a prediction 2.5 m off, within the search's reach of 3.75 m, finds the pose and vouches") {
  // The reach rule (tracker.cpp) makes a result farther than the pattern search can reach from the
  // prediction a loss. The search moves up to two steps a round along each axis (3.75 m by default);
  // the rule once counted one (1.875 m), so every right pose from a prediction 2.5 m off was a loss.
  const auto& w = tiny_world();
  Ready r(w, w.config);
  uint32_t confident = 0, confident_wrong = 0;
  for (uint32_t k = 0; k < w.queries.size(); ++k) {
    const auto& q = w.queries[k];
    LocalizeResult out;
    REQUIRE(r.loc.track(q.view(), perturbed(q.truth, 2.5, 3.0, k), &out) == Status::Ok);
    double m, deg;
    errors(out.map_T_scan, q.truth, &m, &deg);
    INFO("query " << k << ": " << m << " m, " << deg << " deg, confidence " << out.confidence);
    confident += out.confident && m < 0.5 && deg < 1.0;
    confident_wrong += out.confident && !gsf_test::pose_ok(out.map_T_scan, q.truth);
  }
  INFO(confident << " of " << w.queries.size() << " confident within 0.5 m / 1 deg");
  CHECK(confident * 10 >= w.queries.size() * 8);
  CHECK(confident_wrong == 0);
}

TEST_CASE("Tracking from a prediction 30 m off or turned 180 deg reports a loss: never a confident pose") {
  // 180 deg: the tracker's 180-degree probe counts only where it scores above the result (tracker.h);
  // from a flipped prediction the result is the flip, and the truth, its flip, is ahead. (The tiny
  // world is not symmetric, so its other probes see it too; test_confidence checks the rule itself.)
  const auto& w = tiny_world();
  Ready r(w, w.config);
  for (const auto& [metres, deg] : {std::pair<double, double>{30.0, 3.0}, {0.0, 180.0}}) {
    for (uint32_t k = 0; k < w.queries.size(); ++k) {
      const auto& q = w.queries[k];
      LocalizeResult out;
      const Status s = r.loc.track(q.view(), perturbed(q.truth, metres, deg, k), &out);
      double m, d;
      errors(out.map_T_scan, q.truth, &m, &d);
      INFO(metres << " m, " << deg << " deg off, query " << k << ": " << to_string(s) << ", confidence "
                  << out.confidence << " (z_shift " << out.confidence_evidence.z_shift << ", z_turn "
                  << out.confidence_evidence.z_turn << "), " << m << " m / " << d << " deg from the truth");
      CHECK(s == Status::Ok);
      CHECK(!out.confident);
      CHECK(!gsf_test::pose_ok(out.map_T_scan, q.truth));  // bounded: the search stays near the prediction
    }
  }
}

TEST_CASE("The tracking model vouches for a peak under label noise, on a real drive, and not for a non-peak") {
  // Evidence of attempts the model was fitted and judged on (docs/vehicle-modes.md, *The search's whole
  // reach, and a tracking model fitted on tracking*). A tracked pose has no rivals: z_rival is the closest
  // probe's z.
  auto evidence = [](float z_shift, float z_turn) {
    ConfidenceEvidence e;
    e.z_shift = z_shift;
    e.z_turn = z_turn;
    e.z_rival = std::min(z_shift, z_turn);
    e.samples = 2500;
    return e;
  };
  // Right poses under label noise 0.15 that the one-shot model of 2026-11 declined (z_turn 3.5-3.9).
  CHECK(tracking_probability(evidence(2.25f, 3.57f)) >= 0.9);
  CHECK(tracking_probability(evidence(3.0f, 3.7f)) >= 0.9);
  // A right tracked pose of the real nuScenes drive 0002 -> 0004: a weaker shift peak than simulated ones.
  CHECK(tracking_probability(evidence(1.46f, 5.22f)) >= 0.9);
  // A peak in position that turning does not lose: not vouched for.
  CHECK(tracking_probability(evidence(4.0f, 2.5f)) < 0.9);
  // No peak: a knocked-off prediction's search stopping short (z of the closest shift about 0).
  CHECK(tracking_probability(evidence(0.2f, 1.0f)) < 0.1);
  CHECK(tracking_probability(evidence(-0.5f, 6.0f)) < 0.1);
  // Monotone in each z, and nothing compared is no confidence.
  for (float z = -3.0f; z < 10.0f; z += 0.5f) {
    CHECK(tracking_probability(evidence(z + 0.5f, 4.0f)) >= tracking_probability(evidence(z, 4.0f)));
    CHECK(tracking_probability(evidence(4.0f, z + 0.5f)) >= tracking_probability(evidence(4.0f, z)));
  }
  ConfidenceEvidence none = evidence(5.0f, 5.0f);
  none.samples = 0;
  CHECK(tracking_probability(none) == 0.0);
}

TEST_CASE("Tracking without ICP (track.refine off) still finds the pose near the prediction") {
  const auto& w = tiny_world();
  LocalizerConfig c = w.config;
  c.track.refine = false;
  CHECK(Localizer::required_bytes(c) < Localizer::required_bytes(w.config));  // no refiner bound
  Ready r(w, c);
  std::vector<double> metres, degrees;
  for (uint32_t k = 0; k < w.queries.size(); k += 2) {
    const auto& q = w.queries[k];
    LocalizeResult out;
    REQUIRE(r.loc.track(q.view(), perturbed(q.truth, 1.0, 3.0, k), &out) == Status::Ok);
    CHECK(!out.refined);
    double m, deg;
    errors(out.map_T_scan, q.truth, &m, &deg);
    INFO("query " << k << ": " << m << " m, " << deg << " deg");
    CHECK(m < 1.5);  // never far beyond the prediction's own 1 m / 3 deg
    CHECK(deg < 3.0);
    metres.push_back(m);
    degrees.push_back(deg);
  }
  // The verification score is flat within about a semantic cell: that is what the search alone is good to.
  std::sort(metres.begin(), metres.end());
  std::sort(degrees.begin(), degrees.end());
  CHECK(metres[metres.size() / 2] < 0.5);
  CHECK(degrees[degrees.size() / 2] < 1.0);
}

TEST_CASE("Tracking refuses a prediction that is not a rigid pose and repeats itself bit for bit") {
  const auto& w = tiny_world();
  Ready r(w, w.config);
  Eigen::Isometry3d bad = w.queries[0].truth;
  bad.translation().x() = std::numeric_limits<double>::quiet_NaN();
  LocalizeResult out;
  CHECK(r.loc.track(w.queries[0].view(), bad, &out) == Status::InvalidArgument);
  CHECK(out.status == Status::InvalidArgument);
  CHECK(!out.confident);
  // Finite but not computable: 1e142 m away (fuzz_vehicle_modes: it reached a float-to-int conversion in
  // ICP), 2000 km away, a scaled rotation, a reflection.
  Eigen::Isometry3d far = w.queries[0].truth;
  far.translation().y() = 1e142;
  CHECK(r.loc.track(w.queries[0].view(), far, &out) == Status::InvalidArgument);
  far.translation().y() = 2e6;
  CHECK(r.loc.track(w.queries[0].view(), far, &out) == Status::InvalidArgument);
  Eigen::Isometry3d scaled = w.queries[0].truth;
  scaled.linear() *= 1.01;
  CHECK(r.loc.track(w.queries[0].view(), scaled, &out) == Status::InvalidArgument);
  Eigen::Isometry3d mirrored = w.queries[0].truth;
  mirrored.linear().col(2) *= -1.0;
  CHECK(r.loc.track(w.queries[0].view(), mirrored, &out) == Status::InvalidArgument);
  LocalizeResult a, b;
  const Eigen::Isometry3d p = perturbed(w.queries[3].truth, 1.0, 3.0, 3);
  r.loc.track(w.queries[3].view(), p, &a);
  r.loc.localize(w.queries[4].view(), &b);  // a one-shot call between leaves nothing behind
  r.loc.track(w.queries[3].view(), p, &b);
  CHECK(a.map_T_scan.matrix() == b.map_T_scan.matrix());
  CHECK(a.confidence == b.confidence);
  Localizer idle;
  CHECK(idle.track(w.queries[0].view(), p, &out) == Status::NotInitialized);
}

}  // namespace test_tracker
