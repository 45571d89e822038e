// Answer selection alone (core/include/gsf/detail/answer_selection.h): rarity weights in closed form
// (keep the total, scale by share^-e), and AnswerSelector::choose on hand-made hypotheses over the
// lattice layer (tests/support/lattice_layer.h): the true lattice shift is chosen wherever it stands in
// the list, its near-twin is no rival, the others are, the reports are ranked by verified score, and
// without verification (or without a semantic layer) the first hypothesis is the answer.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>
#include <vector>

#include "arena_buffer.h"
#include "gsf/config.h"
#include "gsf/detail/answer_selection.h"
#include "gsf/detail/pose_hypotheses.h"
#include "lattice_layer.h"
#include "test_cloud.h"

namespace test_answer_selection {

using namespace gsf;
using gsf_test::ArenaBuffer;

TEST_CASE("Rarity weights scale each class by its share^-e and keep the scan's total weight") {
  VoxelConfig vc;
  vc.voxel_size = 0.5f;
  ArenaBuffer buf(VoxelLayer::required_bytes(vc));
  VoxelLayer layer;
  REQUIRE(layer.bind(buf.arena, vc) == Status::Ok);
  gsf_test::Cloud c;  // 90 road voxels and 10 pole voxels, one point each, 1 m apart
  for (int i = 0; i < 100; ++i) c.add(5.0f + float(i % 10), float(i / 10) - 5.0f, 0.2f, i < 90 ? 40u : 80u);
  REQUIRE(layer.build(c.view(), nullptr) == Status::Ok);
  REQUIRE(layer.size() == 100);
  float base[kNumClasses];
  for (int k = 0; k < kNumClasses; ++k) base[k] = 0.5f + 0.01f * k;
  float out[kNumClasses];
  rarity_weights(layer, base, 0.5f, 4096, out);
  // total weight kept: 90 w_road + 10 w_pole = 90 b_road + 10 b_pole
  const double before = 90.0 * base[kRoad] + 10.0 * base[kPole];
  const double after = 90.0 * out[kRoad] + 10.0 * out[kPole];
  CHECK(after == Approx(before).epsilon(1e-6));
  // ratio: (0.1 / 0.9)^-0.5 = 3 times the base ratio
  CHECK(double(out[kPole]) / out[kRoad] == Approx(3.0 * base[kPole] / base[kRoad]).epsilon(1e-5));
  // classes absent from the scan get the normalisation only: road's factor without its 0.9^-0.5
  CHECK(double(out[kCar]) / base[kCar] == Approx(double(out[kRoad]) / base[kRoad] * std::sqrt(0.9)).epsilon(1e-5));
  rarity_weights(layer, base, 0.0f, 4096, out);  // exponent 0: the base weights
  for (int k = 0; k < kNumClasses; ++k) CHECK(out[k] == base[k]);
}

namespace {

// What choose() decided, with each ranked hypothesis read back from the hypotheses (as the localizer
// reports them).
struct RankedReport {
  float x = 0;
  uint32_t clique_size = 0, inliers = 0;
  float verified_score = 0;
  bool fully_verified = false;
};
struct Chosen {
  uint32_t chosen_hypothesis = 0;
  bool verified = false;
  Eigen::Isometry3d map_T_scan = Eigen::Isometry3d::Identity();
  uint32_t clique_size = 0, inliers = 0;
  double score = 0;
  RankedReport hypothesis[AnswerChoice::kMaxRanked];
};

// A bird's-eye pose: translation (x, y, 0) and heading yaw_deg.
Eigen::Isometry3d pose_at(double x, double y, double yaw_deg = 0.0) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(x, y, 0.0);
  return T;
}

double planar_distance(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.translation().head<2>() - b.translation().head<2>()).norm();
}

// The scan of the lattice layer seen from x = 24 (its bush beside the column at x = 24 in the scan) and
// PoseHypotheses holding exactly the given poses, hypothesis h with clique size 10 + h, inliers 20 + h and
// support 30 + h (generated from a clique and shift votes, then overwritten: choose() reads only these).
struct Selection {
  gsf_test::LatticeVerification fixture;
  ArenaBuffer buf;
  PoseHypotheses hyps;
  AnswerSelector selector;
  HypothesisConfig hc;
  VerifyConfig vc;
  Selection() : buf(PoseHypotheses::required_bytes(64, 8) + AnswerSelector::required_bytes(4, 100000, 1024) + 64) {
    REQUIRE(hyps.bind(buf.arena, 64, 8) == Status::Ok);
    REQUIRE(selector.bind(buf.arena, 4, fixture.config.max_voxels, search_sample_points(vc)) == Status::Ok);
    fixture.build(gsf_test::lattice_scan(24.0f, true));
  }
  void set(const std::vector<Eigen::Isometry3d>& poses) {
    std::vector<float> a, b;
    auto add = [&](float qx, float qy, float tx) {
      a.insert(a.end(), {qx, qy, 1.0f});
      b.insert(b.end(), {qx + tx, qy + 50.0f, 1.0f});
    };
    const float clique_pts[8][2] = {{3, 1}, {-7, 4}, {12, -5}, {-2, -14}, {18, 9}, {-15, -3}, {6, 11}, {-11, 7}};
    for (const auto& p : clique_pts) add(p[0], p[1], 100.0f);
    float x = 30.0f;
    for (int k = 1; k <= 6; ++k)
      for (int j = 0; j < 3; ++j, x += 1.7f) add(x, -20.0f + 3.0f * j, 100.0f + 8.0f * k + 1.0f);
    const uint32_t n = static_cast<uint32_t>(a.size() / 3);
    std::vector<float> w(n, 1.0f);
    HypothesisConfig g;
    g.max_peeled = 1;
    g.heading_cliques = 0;
    g.max_hypotheses = static_cast<uint32_t>(poses.size());
    HypothesisStats st;
    REQUIRE(hyps.generate(a.data(), b.data(), w.data(), n, g, &st) == Status::Ok);
    REQUIRE(hyps.size() == poses.size());
    for (uint32_t h = 0; h < hyps.size(); ++h) {
      hyps[h].map_T_scan = poses[h];
      hyps[h].clique_size = 10 + h;
      hyps[h].inliers = 20 + h;
      hyps[h].support = 30.0 + h;
      hyps[h].verification = PoseVerification{};
    }
  }
  Chosen choose(const SemanticGridView& grid) {
    const AnswerChoice c = selector.choose(hyps, fixture.voxels, grid, fixture.weights, hc, vc);
    Chosen out;
    out.chosen_hypothesis = c.index;
    out.verified = c.verified;
    out.map_T_scan = c.answer.map_T_scan;
    out.clique_size = c.answer.clique_size;
    out.inliers = c.answer.inliers;
    out.score = c.answer.support;
    for (uint32_t k = 0; k < c.ranked; ++k) {
      const PoseHypothesis& h = hyps[c.rank[k]];
      out.hypothesis[k] = {static_cast<float>(h.map_T_scan.translation().x()), h.clique_size, h.inliers,
                           h.verification.score, c.fully_verified[k]};
    }
    return out;
  }
  Chosen choose() { return choose(fixture.layer.view); }
};

}  // namespace

TEST_CASE("choose(): the true lattice shift is the answer wherever it stands among the hypotheses") {
  // The truth is x = 24; the other lattice shifts (x = 8, 16, 32, 40) agree on road and columns and miss
  // only the bush (test_semantic_grid.cpp).
  Selection s;
  const double shifts[4] = {8.0, 16.0, 32.0, 40.0};
  for (uint32_t at = 0; at < 5; ++at) {
    std::vector<Eigen::Isometry3d> poses;
    for (int k = 0; k < 4; ++k) poses.push_back(pose_at(shifts[k], 0.0));
    poses.insert(poses.begin() + at, pose_at(24.0, 0.0));
    s.set(poses);
    INFO("truth at position " << at);
    const Chosen out = s.choose();
    CHECK(s.selector.chosen() == at);
    CHECK(out.chosen_hypothesis == at);
    CHECK(out.verified);
    // The answer's fields are its hypothesis's.
    CHECK(std::memcmp(out.map_T_scan.data(), s.hyps[at].map_T_scan.data(), sizeof(double) * 16) == 0);
    CHECK(out.clique_size == 10 + at);
    CHECK(out.inliers == 20 + at);
    CHECK(out.score == 30.0 + at);
    // Reports: every hypothesis (5 <= kMaxReportedHypotheses), ranked by verified score, the answer first,
    // each fully scored (5 <= full_top).
    for (uint32_t k = 0; k < 5; ++k) {
      CHECK(out.hypothesis[k].fully_verified);
      if (k > 0) CHECK(out.hypothesis[k - 1].verified_score >= out.hypothesis[k].verified_score);
    }
    CHECK(out.hypothesis[0].x == 24.0f);
    CHECK(out.hypothesis[0].inliers == 20 + at);
    CHECK(out.hypothesis[0].verified_score == s.hyps[at].verification.score);
    CHECK(out.hypothesis[1].verified_score < out.hypothesis[0].verified_score);
    // The answer's score is the full score at the pose verification settled on (answer_pose), bit for bit.
    const PoseVerification again = verify_pose(s.fixture.voxels, s.fixture.layer.view, s.selector.answer_pose(),
                                               s.vc.max_points, s.selector.verify_weights(), s.vc.disagree_weight);
    CHECK(again.score == s.hyps[at].verification.score);
    CHECK(planar_distance(s.selector.answer_pose(), pose_at(24.0, 0.0)) < 0.5);
  }
  // The verification weights are the rarity weights of the scan's voxels.
  float expect[kNumClasses];
  rarity_weights(s.fixture.voxels, s.fixture.weights, s.vc.rarity_exponent, s.vc.max_points, expect);
  CHECK(std::memcmp(expect, s.selector.verify_weights(), sizeof(expect)) == 0);
}

TEST_CASE("choose(): a near-twin of the answer is the same answer; the other places are its rivals, best first") {
  Selection s;
  // Truth, a twin 0.6 m and 2 deg off (within same_pose_m 2 m and same_pose_deg 5 deg), four other shifts.
  s.set({pose_at(16.0, 0.0), pose_at(24.6, 0.2, 2.0), pose_at(40.0, 0.0), pose_at(24.0, 0.0), pose_at(8.0, 0.0),
         pose_at(32.0, 0.0)});
  const Chosen out = s.choose();
  const Eigen::Isometry3d answer = s.hyps[s.selector.chosen()].map_T_scan;
  CHECK(planar_distance(answer, pose_at(24.0, 0.0)) < 1.0);
  CHECK(s.selector.rival_count() == 4);
  float previous = INFINITY;
  for (uint32_t r = 0; r < s.selector.rival_count(); ++r) {
    const Eigen::Isometry3d& rival = s.selector.rival_poses()[r];
    INFO("rival " << r << " at x " << rival.translation().x());
    CHECK(planar_distance(rival, answer) > s.hc.same_pose_m);
    // Best first: each rival scores no better than the one before it.
    const float score = verify_pose(s.fixture.voxels, s.fixture.layer.view, rival, s.vc.max_points,
                                    s.selector.verify_weights(), s.vc.disagree_weight)
                            .score;
    CHECK(score <= previous);
    previous = score;
  }
  CHECK(out.hypothesis[0].verified_score >= out.hypothesis[1].verified_score);
  // Everything within a 100 m "same pose": one answer and no rival.
  s.hc.same_pose_m = 100.0f;
  s.choose();
  CHECK(s.selector.rival_count() == 0);
  // At another heading a hypothesis at the same place is a rival (same_pose_deg).
  s.hc = HypothesisConfig();
  s.set({pose_at(24.0, 0.0), pose_at(24.0, 0.0, 90.0)});
  s.choose();
  CHECK(s.selector.chosen() == 0);
  CHECK(s.selector.rival_count() == 1);
}

TEST_CASE("choose(): without verification or without a semantic layer the first hypothesis is the answer") {
  Selection s;
  const std::vector<Eigen::Isometry3d> poses = {pose_at(8.0, 0.0), pose_at(16.0, 0.0), pose_at(24.0, 0.0)};
  for (int way = 0; way < 2; ++way) {
    s.set(poses);
    s.vc.enabled = way != 0;  // way 0: verification off; way 1: on, but no layer to verify against
    const Chosen out = way == 0 ? s.choose() : s.choose(SemanticGridView{});
    INFO((way == 0 ? "verification off" : "no semantic layer"));
    CHECK(s.selector.chosen() == 0);
    CHECK_FALSE(out.verified);
    CHECK(out.map_T_scan.isApprox(poses[0], 0.0));
    CHECK(s.selector.answer_pose().isApprox(poses[0], 0.0));
    CHECK(s.selector.rival_count() == 0);
    CHECK(s.selector.compact_point_count() == 0);
    // Reports in the order found, nothing fully verified.
    for (uint32_t k = 0; k < 3; ++k) {
      CHECK(out.hypothesis[k].x == float(poses[k].translation().x()));
      CHECK(out.hypothesis[k].clique_size == 10 + k);
      CHECK_FALSE(out.hypothesis[k].fully_verified);
    }
  }
  // With verification the same list gives the truth (x = 24), third in the list.
  s.vc = VerifyConfig();
  s.set(poses);
  CHECK(s.choose().verified);
  CHECK(s.selector.chosen() == 2);
  CHECK(s.selector.compact_point_count() == s.fixture.voxels.size());
}

TEST_CASE("choose(): full_top and refine_top cap what is fully scored and pattern-refined") {
  Selection s;
  const std::vector<Eigen::Isometry3d> poses = {pose_at(8.0, 0.0), pose_at(16.0, 0.0), pose_at(24.6, 0.2, 2.5),
                                                pose_at(32.0, 0.0), pose_at(40.0, 0.0)};
  // Only the best 2 by the coarse score are fully scored; the answer is among them.
  s.vc.full_top = 2;
  s.set(poses);
  Chosen out = s.choose();
  uint32_t full = 0;
  for (uint32_t k = 0; k < 5; ++k) full += out.hypothesis[k].fully_verified;
  CHECK(full == 2);
  CHECK(out.hypothesis[0].fully_verified);
  CHECK(s.selector.chosen() == 2);
  // No refinement rounds: the answer is scored where it stands (answer_pose is its own pose).
  s.vc = VerifyConfig();
  s.vc.refine_rounds = 0;
  s.set(poses);
  out = s.choose();
  CHECK(s.selector.chosen() == 2);
  CHECK(s.selector.answer_pose().isApprox(poses[2], 0.0));
  const PoseVerification at = verify_pose(s.fixture.voxels, s.fixture.layer.view, poses[2], s.vc.max_points,
                                          s.selector.verify_weights(), s.vc.disagree_weight);
  CHECK(out.hypothesis[0].verified_score == at.score);
  // With refinement the answer 2.5 deg off is scored at the pose the pattern search found, a better one.
  s.vc = VerifyConfig();
  s.set(poses);
  out = s.choose();
  CHECK(s.selector.chosen() == 2);
  CHECK(out.hypothesis[0].verified_score > at.score);
  CHECK_FALSE(s.selector.answer_pose().isApprox(poses[2], 1e-6));  // the search moved it
  const PoseVerification moved = verify_pose(s.fixture.voxels, s.fixture.layer.view, s.selector.answer_pose(),
                                             s.vc.max_points, s.selector.verify_weights(), s.vc.disagree_weight);
  CHECK(moved.score == out.hypothesis[0].verified_score);
  CHECK(planar_distance(s.selector.answer_pose(), pose_at(24.0, 0.0)) <= planar_distance(poses[2], pose_at(24.0, 0.0)));
  // The same input twice: the same choice and scores, bit for bit.
  s.set(poses);
  const Chosen again = s.choose();
  for (uint32_t k = 0; k < AnswerChoice::kMaxRanked; ++k) {
    CHECK(out.hypothesis[k].x == again.hypothesis[k].x);
    CHECK(out.hypothesis[k].verified_score == again.hypothesis[k].verified_score);
    CHECK(out.hypothesis[k].fully_verified == again.hypothesis[k].fully_verified);
  }
}

TEST_CASE("choose(): the best hypothesis turned more than 90 deg from the leader is pattern-searched too") {
  // A 180-degree twin (x = 33: the columns line up again, the bush lands on road) leads before any
  // search; the truth's clique pose is 1.4 m and 5 deg off, so it scores below the twin until searched.
  Selection s;
  const std::vector<Eigen::Isometry3d> poses = {pose_at(33.0, 0.0, 180.0), pose_at(25.3, 0.7, 5.0),
                                                pose_at(17.0, 0.0, 180.0)};
  s.vc.refine_top = 1;
  s.vc.refine_turned = 0;
  s.set(poses);
  Chosen out = s.choose();
  CHECK(s.selector.chosen() == 0);  // the twin, searched alone
  s.vc.refine_turned = 1;
  s.set(poses);
  out = s.choose();
  CHECK(s.selector.chosen() == 1);  // the truth, once searched
  CHECK(planar_distance(s.selector.answer_pose(), pose_at(24.0, 0.0)) < planar_distance(poses[1], pose_at(24.0, 0.0)));
}

}  // namespace test_answer_selection
