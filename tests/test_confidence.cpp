// The confidence stage (confidence.h): the paired block statistic in closed form, its invariance to the
// scale of the evidence and to label noise that hits both poses alike, the probability's shape, and on
// whole localizations: a map of another world never gets a confident answer, nor does hostile input.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

#include "arena_buffer.h"
#include "dense_semantic_layer.h"
#include "gsf/detail/confidence.h"
#include "gsf/localizer.h"
#include "gsf/port/logit_synthesis.h"
#include "label_errors/label_errors.h"
#include "tiny_world.h"

namespace test_confidence {

using namespace gsf;

namespace {

// A map semantic layer over [-64, 64)^2 m (1 m cells, 16 m tiles): road everywhere, observed, and
// building cells where set().
struct RoadLayer : gsf_test::DenseSemanticLayer {
  RoadLayer() : DenseSemanticLayer(-4, 4, -4, 4, kCellObserved | class_bit(kRoad)) {}
};

// k scan blocks (4 m squares along x) with four building voxels each, on building cells of the map at
// the identity pose; 40 m further along x the map has road only. first_at_rival: block 0's building is
// in the map 40 m further on instead (that block favours the rival).
struct BuildingBlocks {
  RoadLayer layer;
  std::vector<VerifyPoint> points;
  explicit BuildingBlocks(int k, bool first_at_rival = false) {
    for (int j = 0; j < k; ++j)
      for (float dx : {0.5f, 1.5f})
        for (float dy : {0.5f, 1.5f}) {
          points.push_back(VerifyPoint{4.0f * j + dx, dy, uint32_t(kBuilding)});
          layer.set(4.0f * j + dx + (j == 0 && first_at_rival ? 40.0f : 0.0f), dy, class_bit(kBuilding));
        }
    layer.finish();
  }
};

Eigen::Isometry3d moved(double x, double y) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(x, y, 0.0);
  return T;
}

std::vector<float> unit_weights(float w = 1.0f) { return std::vector<float>(kNumClasses, w); }

ConfidenceEvidence measure(AnswerConfidence& conf, const std::vector<VerifyPoint>& pts, const SemanticGridView& g,
                           const std::vector<float>& w, float lambda, const Eigen::Isometry3d* rivals, uint32_t nr,
                           bool flip_only_if_ahead = false) {
  const Eigen::Isometry3d answer = Eigen::Isometry3d::Identity();
  const AnswerConfidence::Answer a{answer, rivals, nr, 10, 0.5f, flip_only_if_ahead};
  return conf.measure(pts.data(), static_cast<uint32_t>(pts.size()), g, w.data(), lambda, a, 4096);
}

}  // namespace

TEST_CASE("Paired block statistic: k blocks that all favour the answer equally give z = sqrt(k)") {
  // Every sample agrees at the answer (+w) and disagrees at the rival 40 m away (-lambda w): each 4 m
  // block's D_B is 4 (1 + lambda) w, so z = k D / sqrt(k D^2) = sqrt(k), whatever w and lambda are.
  const int k = 6;
  BuildingBlocks scene(k);
  gsf_test::ArenaBuffer buf(AnswerConfidence::required_bytes(4096));
  AnswerConfidence conf;
  REQUIRE(conf.bind(buf.arena, 4096) == Status::Ok);
  const Eigen::Isometry3d rival = moved(40.0, 0.0);
  const ConfidenceEvidence e = measure(conf, scene.points, scene.layer.view, unit_weights(), 3.0f, &rival, 1);
  CHECK(e.rivals == 1);
  CHECK(e.samples == 4u * k);
  CHECK(e.blocks == uint32_t(k));
  CHECK(e.known_share == 1.0f);
  CHECK(e.z_rival == Approx(std::sqrt(double(k))).epsilon(1e-6));
  // Every sample loses (1 + lambda) w at the rival against w at the answer: a margin of 1 + lambda.
  CHECK(e.rival_margin == Approx(4.0).epsilon(1e-6));
  CHECK(e.inliers == 10u);
  CHECK(e.inlier_share == 0.5f);
  // One block that favours the rival instead (its building is 40 m on in the map): D = (k - 1) d - d
  // over k blocks of |d|, so z = (k - 2) / sqrt(k).
  const BuildingBlocks other(k, true);
  const ConfidenceEvidence e2 = measure(conf, other.points, other.layer.view, unit_weights(), 3.0f, &rival, 1);
  CHECK(e2.z_rival == Approx((k - 2) / std::sqrt(double(k))).epsilon(1e-6));
  // Its four samples disagree at the answer (-lambda w) and agree at the rival (+w): the margin is
  // 4 (1 + lambda) w (k - 2) over 4 w (k - 1 + lambda).
  CHECK(e2.rival_margin == Approx(4.0 * (k - 2) / (k - 1 + 3.0)).epsilon(1e-6));
}

TEST_CASE("The statistic is self-normalised: the evidence's scale and noise that hits both poses alike drop out") {
  BuildingBlocks scene(6);  // blocks at x < 24 m: 40 m on they are still inside the layer (not unknown)
  gsf_test::ArenaBuffer buf(AnswerConfidence::required_bytes(4096));
  AnswerConfidence conf;
  REQUIRE(conf.bind(buf.arena, 4096) == Status::Ok);
  const Eigen::Isometry3d rivals[2] = {moved(40.0, 0.0), moved(0.0, 30.0)};
  const ConfidenceEvidence base = measure(conf, scene.points, scene.layer.view, unit_weights(), 3.0f, rivals, 2);
  // Heavier class weights scale every D_B alike.
  const ConfidenceEvidence heavy = measure(conf, scene.points, scene.layer.view, unit_weights(2.5f), 3.0f, rivals, 2);
  CHECK(heavy.z_rival == Approx(base.z_rival).epsilon(1e-5));
  CHECK(heavy.z_shift == Approx(base.z_shift).epsilon(1e-5));
  CHECK(heavy.z_turn == Approx(base.z_turn).epsilon(1e-5));
  CHECK(heavy.rival_margin == Approx(base.rival_margin).epsilon(1e-5));
  // Mislabelled voxels (vegetation on the road, in the same blocks) disagree at the answer and at the
  // rivals alike: the agreement share at the answer drops, the comparison does not move.
  std::vector<VerifyPoint> noisy = scene.points;
  for (size_t i = 0; i < scene.points.size(); i += 2)
    noisy.push_back(VerifyPoint{scene.points[i].x + 0.2f, scene.points[i].y + 2.0f, uint32_t(kVegetation)});
  const std::vector<float> w = unit_weights();
  const PoseVerification clean = verify_pose(scene.points.data(), uint32_t(scene.points.size()), scene.layer.view,
                                             Eigen::Isometry3d::Identity(), 4096, w.data(), 3.0f);
  const PoseVerification dirty = verify_pose(noisy.data(), uint32_t(noisy.size()), scene.layer.view,
                                             Eigen::Isometry3d::Identity(), 4096, w.data(), 3.0f);
  CHECK(dirty.agree / (dirty.agree + dirty.disagree) < 0.7f * clean.agree / (clean.agree + clean.disagree));
  const ConfidenceEvidence e = measure(conf, noisy, scene.layer.view, w, 3.0f, rivals, 1);
  CHECK(e.z_rival == Approx(std::sqrt(6.0)).epsilon(1e-6));
}

TEST_CASE("rivals_only compares the rivals as the whole measure does, and skips the probes") {
  BuildingBlocks scene(6, true);
  gsf_test::ArenaBuffer buf(AnswerConfidence::required_bytes(4096));
  AnswerConfidence conf;
  REQUIRE(conf.bind(buf.arena, 4096) == Status::Ok);
  const Eigen::Isometry3d answer = Eigen::Isometry3d::Identity(), rival = moved(40.0, 0.0);
  const std::vector<float> w = unit_weights();
  const uint32_t n = static_cast<uint32_t>(scene.points.size());
  const AnswerConfidence::Answer whole{answer, &rival, 1, 10, 0.5f};
  const AnswerConfidence::Answer only{answer, &rival, 1, 10, 0.5f, false, /*rivals_only=*/true};
  const ConfidenceEvidence a = conf.measure(scene.points.data(), n, scene.layer.view, w.data(), 3.0f, whole, 4096);
  const ConfidenceEvidence b = conf.measure(scene.points.data(), n, scene.layer.view, w.data(), 3.0f, only, 4096);
  REQUIRE(a.z_shift < 10.0f);     // the whole measure's probes read something
  CHECK(b.z_rival == a.z_rival);  // bit for bit
  CHECK(b.rival_margin == a.rival_margin);
  CHECK(b.samples == a.samples);
  CHECK(b.z_shift == 10.0f);  // kZMax: not measured
  CHECK(b.z_shift_far == 10.0f);
  CHECK(b.z_turn == 10.0f);
}

TEST_CASE("Without a rival the closest probe stands in; empty input gives no evidence") {
  BuildingBlocks scene(5);
  gsf_test::ArenaBuffer buf(AnswerConfidence::required_bytes(4096));
  AnswerConfidence conf;
  REQUIRE(conf.bind(buf.arena, 4096) == Status::Ok);
  const ConfidenceEvidence e = measure(conf, scene.points, scene.layer.view, unit_weights(), 3.0f, nullptr, 0);
  CHECK(e.rivals == 0);
  CHECK(e.z_rival == std::min(e.z_shift, e.z_turn));
  const ConfidenceEvidence none = measure(conf, {}, scene.layer.view, unit_weights(), 3.0f, nullptr, 0);
  CHECK(none.samples == 0);
  CHECK(confidence_probability(none) == 0.0);
  CHECK(measure(conf, scene.points, SemanticGridView(), unit_weights(), 3.0f, nullptr, 0).samples == 0);
}

// Blocks of four building voxels 12 m apart on a grid; in the map each block's building runs 2 m further
// along x either way (a wall seen end-on, a uniform street), so shifted 2 m along x the answer ties in
// every block, shifted 8 m it loses.
namespace {
struct LongWalls {
  RoadLayer layer;
  std::vector<VerifyPoint> points;
  LongWalls() {
    for (int i = -4; i <= 4; ++i)
      for (int r = -4; r <= 4; ++r) {
        for (float dx : {0.5f, 1.5f})
          for (float dy : {0.5f, 1.5f})
            points.push_back(VerifyPoint{12.0f * i + dx, 12.0f * r + dy, uint32_t(kBuilding)});
        for (int cx = -2; cx < 4; ++cx)
          for (int cy = 0; cy < 2; ++cy) layer.set(12.0f * i + cx + 0.5f, 12.0f * r + cy + 0.5f, class_bit(kBuilding));
      }
    layer.finish();
  }
};
}  // namespace

TEST_CASE("The 8 m probes are a z of their own: a right answer may be off by less than 5 m") {
  const LongWalls walls;
  gsf_test::ArenaBuffer buf(AnswerConfidence::required_bytes(4096));
  AnswerConfidence conf;
  REQUIRE(conf.bind(buf.arena, 4096) == Status::Ok);
  const Eigen::Isometry3d rival = moved(0.0, 6.0);
  const ConfidenceEvidence e = measure(conf, walls.points, walls.layer.view, unit_weights(), 3.0f, &rival, 1);
  CHECK(e.blocks == 81u);
  CHECK(e.z_shift == 0.0f);  // the 2 m shifts along x tie in every block: no evidence either way
  CHECK(e.z_shift_far > 5.0f);
  CHECK(e.z_shift_far <= 9.0f);  // at most sqrt(81): every block ahead by as much
  // The peak factor reads the 8 m probes: where the 2 m ones tie (a pose within 5 m of the truth is
  // still right), an answer well ahead of its 8 m neighbours is confident; where those tie too, not.
  ConfidenceEvidence a;
  a.samples = e.samples;
  a.known_share = 1.0f;
  a.z_rival = 10.0f;
  a.rival_margin = 1.0f;
  a.inlier_share = 1.0f;
  a.z_turn = 4.0f;  // about a right answer's 10th percentile
  a.z_shift = 0.0f;
  a.z_shift_far = 8.0f;
  CHECK(confidence_probability(a) >= 0.9);
  a.z_shift_far = 0.0f;  // the scene slides 8 m as well: not a peak at that scale
  CHECK(confidence_probability(a) < 0.5);
}

// k blocks of building voxels as BuildingBlocks, and the map's buildings also mirrored through the
// sensor (the scene turned 180 deg, a symmetric hall), except one: missing_mirror drops block 0's mirror
// (the answer is ahead of its flip by one block), missing_own drops block 0 itself (the flip is ahead).
namespace {
struct MirroredBlocks {
  RoadLayer layer;
  std::vector<VerifyPoint> points;
  MirroredBlocks(int k, bool missing_own) {
    for (int j = 0; j < k; ++j)
      for (float dx : {0.5f, 1.5f})
        for (float dy : {0.5f, 1.5f}) {
          const float x = 4.0f * j + dx;
          points.push_back(VerifyPoint{x, dy, uint32_t(kBuilding)});
          if (j != 0 || !missing_own) layer.set(x, dy, class_bit(kBuilding));
          if (j != 0 || missing_own) layer.set(-x, -dy, class_bit(kBuilding));
        }
    layer.finish();
  }
};
}  // namespace

TEST_CASE("The 180-degree probe counts only when it is ahead of the answer if the caller asks (tracking)") {
  gsf_test::ArenaBuffer buf(AnswerConfidence::required_bytes(4096));
  AnswerConfidence conf;
  REQUIRE(conf.bind(buf.arena, 4096) == Status::Ok);
  // The flip disagrees in block 0 only: one block's D_B, so z = D / |D| = 1, the closest turned probe
  // (the +-10 deg probes lose in every block beyond the sensor's own).
  const MirroredBlocks thin(6, false);
  const ConfidenceEvidence all = measure(conf, thin.points, thin.layer.view, unit_weights(), 3.0f, nullptr, 0);
  CHECK(all.z_turn == Approx(1.0).epsilon(1e-6));
  const ConfidenceEvidence ahead = measure(conf, thin.points, thin.layer.view, unit_weights(), 3.0f, nullptr, 0, true);
  CHECK(ahead.z_turn > 1.5f);  // the +-10 deg probes alone
  // The flip is ahead (block 0 agrees there and not at the answer): z = -1 whether or not asked.
  const MirroredBlocks flipped(6, true);
  const ConfidenceEvidence flip = measure(conf, flipped.points, flipped.layer.view, unit_weights(), 3.0f, nullptr, 0);
  CHECK(flip.z_turn == Approx(-1.0).epsilon(1e-6));
  CHECK(measure(conf, flipped.points, flipped.layer.view, unit_weights(), 3.0f, nullptr, 0, true).z_turn ==
        flip.z_turn);
}

TEST_CASE("The probability is a product of rising logistic factors, in [0, 1]") {
  // The fit holds every slope >= 0 (bench/fit_confidence.py): a pasted model that falls with its
  // evidence is a fit of noise.
  const ConfidenceModel& m = kConfidenceModel;
  for (const float slope :
       {m.rival_share_slope, m.peak_far_slope, m.peak_shift_slope, m.peak_turn_slope, m.inlier_slope})
    CHECK(slope >= 0.0f);
  ConfidenceEvidence e;
  e.samples = 1000;
  e.known_share = 1.0f;
  e.z_rival = e.z_shift = e.z_shift_far = e.z_turn = 10.0f;
  e.rival_margin = 1.0f;
  e.inlier_share = 1.0f;
  const double top = confidence_probability(e);
  CHECK(top > 0.99);
  CHECK(top <= 1.0);
  double last = 0.0;
  for (float z = -3.0f; z <= 10.0f; z += 0.5f) {  // each factor rises with its z
    e.z_rival = z;
    const double p = confidence_probability(e);
    CHECK(p >= last);
    last = p;
  }
  last = 0.0;
  for (float share = 0.0f; share <= 1.0f; share += 0.05f) {  // and with the share of instances explained
    e.inlier_share = share;
    const double p = confidence_probability(e);
    CHECK(p >= last);
    last = p;
  }
  // The rival's lead counts in proportion to that share. A wrong map's look-alike crossing (a vehicle
  // off its map: median z_rival 2.4 at an inlier share of 0.26-0.41) is not vouched for; an answer
  // explaining most of the scan is, at the same lead; and one explaining as few as a real scan's right
  // answers do (0.5) is vouched for at a real right answer's lead (z_rival about 6).
  e.z_rival = 2.4f;
  e.inlier_share = 0.35f;
  CHECK(confidence_probability(e) < 0.9);
  e.inlier_share = 0.9f;
  CHECK(confidence_probability(e) >= 0.9);
  e.z_rival = 6.0f;
  e.inlier_share = 0.5f;
  CHECK(confidence_probability(e) >= 0.9);
  e.inlier_share = 1.0f;
  double last_turn = 0.0;
  e.z_rival = 0.0f;  // no separation from the rival, a near-tie: a coin toss at best
  e.rival_margin = 0.02f;
  CHECK(confidence_probability(e) < 0.5);
  e.z_rival = 10.0f;
  e.z_shift = e.z_shift_far = 3.0f;  // clearly ahead of its shifted copies (a right answer's median is about 3)
  e.z_turn = -3.0f;                  // but a turned copy of the scan fits better: not a peak
  CHECK(confidence_probability(e) < 0.01);
  e.z_turn = 5.0f;  // a right answer's 5th percentile
  const double turned_well = confidence_probability(e);
  CHECK(turned_well > 0.9);
  e.z_shift = e.z_shift_far = -3.0f;  // and the other way round: a copy shifted 8 m fits better
  CHECK(confidence_probability(e) < 0.5);
  double last_far = 0.0;
  for (float z = -3.0f; z <= 10.0f; z += 0.5f) {  // the peak factor rises with each z
    e.z_shift = e.z_shift_far = z;
    const double p_shift = confidence_probability(e);
    e.z_shift = 3.0f;
    const double p_far = confidence_probability(e);
    e.z_shift_far = 3.0f;
    e.z_turn = z;
    const double p_turn = confidence_probability(e);
    e.z_turn = 5.0f;
    if (z > -3.0f) {
      CHECK(p_shift >= last);
      CHECK(p_far >= last_far);
      CHECK(p_turn >= last_turn);
    }
    last = p_shift;
    last_far = p_far;
    last_turn = p_turn;
  }
  e.z_shift = e.z_shift_far = 10.0f;
  e.z_turn = 10.0f;
  e.inlier_share = 0.5f;
  const double half = confidence_probability(e);
  e.inlier_share = 0.0f;  // none of the scan's instances explained: a coincidence somewhere else
  CHECK(confidence_probability(e) < 0.05);
  CHECK(confidence_probability(e) < half);
  const ConfidenceModel flat{0, 0, 0, 0, 0, 0, 0, 0};  // every factor (rival, peak, inlier) 1/2
  CHECK(confidence_probability(e, flat) == Approx(0.125));
}

namespace {

// Localizes every tiny-world query against `map`; counts confident answers and the right ones.
struct Tally {
  int with_pose = 0, right = 0, confident = 0, confident_right = 0;
};
Tally localize_all(const MapView& map, const std::vector<gsf_test::QueryScan>& queries, const LocalizerConfig& cfg) {
  std::vector<uint64_t> ws(Localizer::required_bytes(cfg) / 8 + 2);
  Localizer loc;
  REQUIRE(loc.init(cfg, map, ws.data(), ws.size() * 8) == Status::Ok);
  Tally t;
  for (const auto& q : queries) {
    LocalizeResult r;
    const bool ok = loc.localize(q.view(), &r) == Status::Ok;
    const bool right = ok && gsf_test::pose_ok(r.map_T_scan, q.truth);
    CHECK(r.confident == (ok && r.confidence >= cfg.confidence.min_probability));
    t.with_pose += ok;
    t.right += right;
    t.confident += r.confident;
    t.confident_right += r.confident && right;
  }
  return t;
}

}  // namespace

TEST_CASE("A map of another place never gets a confident answer; the right map does") {
  const gsf_test::TinyWorld& w = gsf_test::tiny_world();
  const Tally own = localize_all(w.map, w.queries, w.config);
  CHECK(own.confident_right == own.confident);
  CHECK(own.confident * 10 >= own.right * 9);
  // The tiny lattice world's map (one city block and a car park of columns, another seed) queried with
  // the tiny world's scans: a vehicle given the wrong map. Every answer is wrong and none may be vouched
  // for. (Worlds of the same generator that share the road grid and the zone are bench/distractors.sh's.)
  const gsf_test::TinyWorld& other = gsf_test::tiny_lattice_world();
  const Tally wrong = localize_all(other.map, w.queries, w.config);
  INFO("poses against the other map: " << wrong.with_pose << " of " << w.queries.size());
  CHECK(wrong.with_pose > 0);  // the test means something: answers are produced, and declined
  CHECK(wrong.right == 0);
  CHECK(wrong.confident == 0);
}

// The scan's instances that land within `radius` (bird's-eye) of a map instance of their own label under
// map_T_scan: what a right answer can explain at best.
uint32_t on_map_instances(const Localizer& loc, const MapView& map, const Eigen::Isometry3d& map_T_scan, float radius) {
  std::vector<float> xyz(3 * 1024);
  std::vector<uint8_t> labels(1024);
  const uint32_t n = std::min(loc.last_instances(xyz.data(), labels.data(), 1024), 1024u);
  uint32_t count = 0;
  for (uint32_t i = 0; i < n; ++i) {
    const Eigen::Vector3d p = map_T_scan * Eigen::Vector3d(xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]);
    for (uint32_t m = 0; m < map.counts.instances; ++m) {
      const float* c = map.instances[m].centroid;
      if (map.instances[m].label == labels[i] && std::hypot(p.x() - c[0], p.y() - c[1]) <= radius) {
        ++count;
        break;
      }
    }
  }
  return count;
}

TEST_CASE("A right answer's inliers are the instances it puts on their map instances, among many no map has") {
  // An unstable segmentation writes patches of wall or hedge as poles and trunks, as many as the scan's
  // real instances (label_errors.h). Counting inliers among the triangle matches' pairs alone read a
  // right answer as explaining about half of what it puts on the map's instances (8 of 17 on the spur
  // family's open roads; 397 of 470 here, before).
  const gsf_test::TinyWorld& w = gsf_test::tiny_world();
  std::vector<uint64_t> ws(Localizer::required_bytes(w.config) / 8 + 2);
  Localizer loc;
  REQUIRE(loc.init(w.config, w.map, ws.data(), ws.size() * 8) == Status::Ok);
  uint32_t right = 0, inliers = 0, on_map = 0;
  for (size_t k = 0; k < w.queries.size(); ++k) {
    gsf_test::QueryScan q = w.queries[k];
    label_errors::apply_spurious_objects(q.xyzi.data(), q.labels.data(), uint32_t(q.labels.size()), 1.0f, 7000 + k);
    port::synthesize_logits(port::LogitModel(), 9000 + k, q.labels.data(), uint32_t(q.labels.size()), q.logits.data(),
                            q.labels.data());
    LocalizeResult r;
    if (loc.localize(q.view(), &r) != Status::Ok || !gsf_test::pose_ok(r.map_T_scan, q.truth)) continue;
    ++right;
    // Every one counts, paired by a triangle or not. (The confidence reads the pose verification scored,
    // which may be a little off the final one: the instances well inside the radius are counted.)
    const uint32_t explained = on_map_instances(loc, w.map, r.map_T_scan, 0.8f * w.config.hypotheses.tls_threshold);
    CHECK(r.confidence_evidence.inlier_share > 0.0f);
    inliers += r.confidence_evidence.inliers;
    on_map += explained;
  }
  INFO(right << " right answers: " << inliers << " inliers, " << on_map << " instances on their map instances");
  REQUIRE(right >= 20);
  CHECK(inliers * 100 >= on_map * 97);
}

TEST_CASE("Hostile scans and a map without a semantic layer: a status or a confidence near 0, never confident") {
  const gsf_test::TinyWorld& w = gsf_test::tiny_world();
  std::vector<uint64_t> ws(Localizer::required_bytes(w.config) / 8 + 2);
  Localizer loc;
  REQUIRE(loc.init(w.config, w.map, ws.data(), ws.size() * 8) == Status::Ok);
  const gsf_test::QueryScan& q = w.queries[3];
  const uint32_t unlabelled = 0, road = 40, pole = 80;
  for (uint32_t label : {unlabelled, road, pole}) {  // all unlabelled, one ground class, one instance class
    gsf_test::QueryScan s = q;
    for (uint32_t& l : s.labels) l = label;
    ScanView v = s.view();
    v.logits = nullptr;  // the labels alone (logits would carry the original classes)
    v.logit_dim = 0;
    LocalizeResult r;
    loc.localize(v, &r);
    INFO("every point labelled " << label << ": " << to_string(r.status) << ", confidence " << r.confidence);
    CHECK(!r.confident);
    CHECK(r.confidence < 0.5);
  }
  gsf_test::QueryScan sky = q;  // a scan of the sky: no returns at all
  sky.xyzi.clear();
  sky.labels.clear();
  sky.logits.clear();
  LocalizeResult r;
  CHECK(loc.localize(sky.view(), &r) != Status::Ok);
  CHECK(r.confidence == 0.0);
  CHECK(!r.confident);
  // The localizer stays usable, and a map without its semantic layer answers without vouching.
  REQUIRE(loc.localize(q.view(), &r) == Status::Ok);
  CHECK(r.confident);
  MapView bare = w.map;
  bare.counts.semantic_tiles = 0;
  Localizer plain;
  std::vector<uint64_t> ws2(Localizer::required_bytes(w.config) / 8 + 2);
  REQUIRE(plain.init(w.config, bare, ws2.data(), ws2.size() * 8) == Status::Ok);
  REQUIRE(plain.localize(q.view(), &r) == Status::Ok);
  CHECK(!r.verified);
  CHECK(r.confidence == 0.0);
  CHECK(!r.confident);
}

TEST_CASE("An answer checked on less than a third of its scan is never vouched for, whatever its factors") {
  ConfidenceEvidence e;
  e.samples = 1000;
  e.z_rival = e.z_shift = e.z_shift_far = e.z_turn = 10.0f;
  e.rival_margin = 1.0f;
  e.inlier_share = 1.0f;
  e.known_share = 1.0f;
  const double whole = confidence_probability(e);
  REQUIRE(whole > 0.99);
  e.known_share = kMinKnownShare;  // a third of the samples on the map's observed cells: the factors decide
  CHECK(confidence_probability(e) == whole);
  e.known_share = std::nextafter(kMinKnownShare, 0.0f);  // just below: capped
  CHECK(confidence_probability(e) == kPartlyMappedConfidence);
  CHECK(confidence_probability(e) < 0.9);  // below the default rule (confidence.min_probability)
  e.known_share = 0.0f;
  CHECK(confidence_probability(e) == kPartlyMappedConfidence);
  // The cap only lowers: a weak answer keeps its own probability.
  e.z_rival = 0.0f;
  e.rival_margin = 0.02f;
  const double weak = confidence_probability(e);
  e.known_share = 1.0f;
  CHECK(weak == confidence_probability(e));
  CHECK(weak < kPartlyMappedConfidence);
}

}  // namespace test_confidence
