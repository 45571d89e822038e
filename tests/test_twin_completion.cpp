// The missing twin alone (core/include/gsf/detail/twin_completion.h): the proposals a repetitive zone's
// ranked hypotheses imply (a hall's two headings, each a row of twins 10 m apart, with the truth's own
// pose missing), their refusals (no twin, no other heading), and the snap of a proposal onto a lattice
// of map instances (a known pose recovered from 1.5 m and 4 deg off, the pairs it needs).
#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

#include "arena_buffer.h"
#include "gsf/detail/angles.h"
#include "gsf/detail/pose_distance.h"
#include "gsf/detail/twin_completion.h"

namespace test_twin_completion {

using namespace gsf;

namespace {

Eigen::Isometry3d pose_at(double x, double y, double yaw_deg) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(deg_to_rad(yaw_deg), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, y, 1.5);
  return T;
}

PlanarPose planar(double x, double y, double yaw_deg) { return PlanarPose{x, y, deg_to_rad(yaw_deg), 0}; }

bool proposes(const std::vector<PlanarPose>& out, double x, double y, double yaw_deg) {
  for (const auto& q : out)
    if (std::fabs(q.x - x) < 0.01 && std::fabs(q.y - y) < 0.01 &&
        std::fabs(std::remainder(q.yaw - deg_to_rad(yaw_deg), kTwoPi)) < 1e-9)
      return true;
  return false;
}

std::vector<PlanarPose> propose(const std::vector<PlanarPose>& ranked, uint32_t answer) {
  std::vector<PlanarPose> out(TwinLimits::kMaxProposals);
  out.resize(
      propose_twin_poses(ranked.data(), uint32_t(ranked.size()), answer, 2.0f, 5.0f, out.data(), uint32_t(out.size())));
  return out;
}

// A lattice of poles (label 3) every 10 m along x and 8 m along y, with one hedge (label 5) that breaks
// the symmetry.
std::vector<MapInstance> pole_lattice() {
  std::vector<MapInstance> map;
  for (int i = 0; i < 12; ++i)
    for (int j = 0; j < 3; ++j) {
      MapInstance m{};
      m.centroid[0] = float(10 * i), m.centroid[1] = float(8 * j), m.centroid[2] = 2.0f;
      m.label = 3;
      map.push_back(m);
    }
  MapInstance hedge{};
  hedge.centroid[0] = 53.0f, hedge.centroid[1] = 4.0f, hedge.centroid[2] = 0.5f;
  hedge.label = 5;
  map.push_back(hedge);
  return map;
}

}  // namespace

TEST_CASE("The other heading's best hypothesis moved by the answer's periods proposes the missing twin") {
  // A hall: the wrong heading's twins at x = 290, 300, 310, 320 (the answer 290, best first); the right
  // heading's at 340 and 360, the truth at 350 missing.
  const std::vector<PlanarPose> ranked = {planar(290, 104, 92), planar(360, 105, -88), planar(300, 104, 92),
                                          planar(310, 104, 92), planar(340, 105, -88), planar(320, 104, 92)};
  const std::vector<PlanarPose> out = propose(ranked, 0);
  // The heads are 360 (best of the other heading, ranked 1) and 340 (ranked 4); the periods 10, 20 and
  // 30 m along x.
  REQUIRE(proposes(out, 360, 105, -88));
  REQUIRE(proposes(out, 350, 105, -88));  // 360 - 10: the missing twin
  REQUIRE(proposes(out, 330, 105, -88));  // 360 - 30 (or 340 - 10)
  REQUIRE(proposes(out, 390, 105, -88));  // 360 + 30
  REQUIRE(proposes(out, 310, 105, -88));  // 340 - 30: the second head's
  // Nothing of the answer's own heading; each names its head; no proposal twice (350 is 360 - 10 and
  // 340 + 10).
  for (size_t i = 0; i < out.size(); ++i) {
    CHECK(std::fabs(std::remainder(out[i].yaw - deg_to_rad(-88.0), kTwoPi)) < 1e-12);
    CHECK((out[i].from == 1 || out[i].from == 4));
    CHECK(std::fabs(ranked[out[i].from].y - out[i].y) < 1e-12);
    for (size_t j = 0; j < i; ++j) CHECK(std::hypot(out[i].x - out[j].x, out[i].y - out[j].y) > 2.0);
  }
  // Head 360: itself and +-10, +-20, +-30 (7); head 340 adds only 320 and 310.
  CHECK(out.size() == 9);
}

TEST_CASE("No proposal without a twin of the answer or without another heading") {
  // Another heading but the answer has no twin (the only same-heading pose is within same_pose_m).
  CHECK(propose({planar(0, 0, 0), planar(1, 0, 1), planar(30, 0, 180)}, 0).empty());
  // Twins but one heading only.
  CHECK(propose({planar(0, 0, 0), planar(10, 0, 0), planar(20, 0, 2)}, 0).empty());
  // An answer index outside the ranked poses.
  CHECK(propose({planar(0, 0, 0), planar(10, 0, 0), planar(30, 0, 180)}, 3).empty());
  // With both, the proposals keep the other heading.
  const auto out = propose({planar(0, 0, 0), planar(10, 0, 0), planar(30, 0, 180)}, 0);
  REQUIRE(out.size() == 3);  // 30, 40, 20
  CHECK(proposes(out, 20, 0, 180));
  CHECK(out[0].from == 2);
}

TEST_CASE("A proposal a metre and a half and a few degrees off snaps onto the instances' pose") {
  const std::vector<MapInstance> map = pole_lattice();
  const Eigen::Isometry3d truth = pose_at(50, 4, 30);
  // The scan's instances: the map's within 25 m of the truth, seen from it.
  std::vector<float> scan;
  std::vector<uint8_t> labels;
  for (const MapInstance& m : map) {
    const Eigen::Vector3d p(m.centroid[0], m.centroid[1], m.centroid[2]);
    if ((p - truth.translation()).head<2>().norm() > 25.0) continue;
    const Eigen::Vector3d q = truth.inverse() * p;
    for (int k = 0; k < 3; ++k) scan.push_back(float(q[k]));
    labels.push_back(m.label);
  }
  const uint32_t n = uint32_t(labels.size());
  REQUIRE(n >= 10);
  gsf_test::ArenaBuffer buf(InstanceSnap::required_bytes(n));
  InstanceSnap snap;
  REQUIRE(snap.bind(buf.arena, n) == Status::Ok);
  Eigen::Isometry3d start = truth;
  start.translation() += Eigen::Vector3d(1.2, -0.9, 0.0);
  start.linear() = start.linear() * Eigen::AngleAxisd(deg_to_rad(4.0), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  Eigen::Isometry3d snapped = Eigen::Isometry3d::Identity();
  REQUIRE(snap.snap(scan.data(), labels.data(), n, map.data(), uint32_t(map.size()), start, 1.5f, 3, &snapped));
  CHECK((snapped.translation() - truth.translation()).head<2>().norm() < 1e-3);
  CHECK(std::fabs(std::remainder(yaw_of(snapped) - yaw_of(truth), kTwoPi)) < 1e-4);
  // Fewer pairs than asked for: refused, the output untouched.
  Eigen::Isometry3d untouched = pose_at(1, 2, 3);
  CHECK_FALSE(
      snap.snap(scan.data(), labels.data(), n, map.data(), uint32_t(map.size()), start, 1.5f, n + 1, &untouched));
  CHECK(within_pose(untouched, pose_at(1, 2, 3), 0.0, 0.0));
  // A start far from every instance of the labels pairs nothing.
  CHECK_FALSE(snap.snap(scan.data(), labels.data(), n, map.data(), uint32_t(map.size()), pose_at(500, 500, 0), 1.5f, 3,
                        &untouched));
  // Unbound: nothing to pair into.
  InstanceSnap unbound;
  CHECK_FALSE(
      unbound.snap(scan.data(), labels.data(), n, map.data(), uint32_t(map.size()), start, 1.5f, 3, &untouched));
}

}  // namespace test_twin_completion
