// End to end on the simulator's tiny world: success rates against ground truth, GSF vs instance-only in
// the repetitive zone, invariance to a rigid transform of the scan, determinism, hostile input, and the
// same results on x86-64 and ARM64 ([cross-isa]).
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "gsf/class_table.h"
#include "gsf/detail/confidence.h"
#include "gsf/detail/gsf_filter.h"
#include "gsf/detail/triangle_matcher.h"
#include "gsf/localizer.h"
#include "skip.h"
#include "source_stamp.h"
#include "tiny_world.h"

using namespace gsf;
using gsf_test::tiny_world;

namespace {
struct Workspace {
  std::vector<uint64_t> words;
  explicit Workspace(const LocalizerConfig& c) : words(Localizer::required_bytes(c) / 8 + 2) {}
  void* data() { return words.data(); }
  size_t bytes() const { return words.size() * 8; }
};
}  // namespace

TEST_CASE("The tiny world's map loads and holds instances, fields and triangles") {
  const auto& w = tiny_world();
  REQUIRE(w.map.counts.instances > 50);
  CHECK(w.map.counts.triangles > 500);
  CHECK(w.map.counts.road_length_m > 500);
  CHECK(w.queries.size() >= 20);
}

// The GSF filter's own value (the paper's claim) is measured on the paper's pipeline: the maximum
// clique's pose, no hypothesis verification (which lifts both modes, test_lattice_e2e.cpp).
void run_gsf_vs_instance(const LocalizerConfig& cfg, bool paper);

TEST_CASE("GSF localizes most queries and beats instance-only in the repetitive zone") {
  LocalizerConfig cfg = tiny_world().config;
  cfg.verify.enabled = false;
  cfg.hypotheses.max_hypotheses = 1;
  cfg.hypotheses.max_tilt_deg = 0.0f;
  run_gsf_vs_instance(cfg, true);
}

TEST_CASE("With verification both modes localize the repetitive zone; GSF stays at least as good") {
  run_gsf_vs_instance(tiny_world().config, false);
}

void run_gsf_vs_instance(const LocalizerConfig& cfg, bool paper) {
  const auto& w = tiny_world();
  Workspace ws(cfg);
  Localizer loc;  // GSF on (as cfg says), and the same without it (instance-only, Outram)
  REQUIRE(loc.init(cfg, w.map, ws.data(), ws.bytes()) == Status::Ok);
  LocalizerConfig off = cfg;
  off.gsf.enabled = false;
  Workspace ws_off(off);
  Localizer loc_off;
  REQUIRE(loc_off.init(off, w.map, ws_off.data(), ws_off.bytes()) == Status::Ok);
  int ok_gsf = 0, ok_inst = 0, zone = 0, zone_gsf = 0, zone_inst = 0, confident = 0, confident_right = 0;
  for (const auto& q : w.queries) {
    LocalizeResult r;
    loc.localize(q.view(), &r);
    const bool g = r.status == Status::Ok && gsf_test::pose_ok(r.map_T_scan, q.truth);
    if (r.status == Status::Ok && r.confident) {  // the default decision rule
      ++confident;
      confident_right += g;
    }
    loc_off.localize(q.view(), &r);
    const bool i = r.status == Status::Ok && gsf_test::pose_ok(r.map_T_scan, q.truth);
    ok_gsf += g;
    ok_inst += i;
    if (q.in_zone) {
      ++zone;
      zone_gsf += g;
      zone_inst += i;
    }
  }
  const int n = static_cast<int>(w.queries.size());
  INFO("GSF " << ok_gsf << "/" << n << " (zone " << zone_gsf << "/" << zone << "), instance-only " << ok_inst << "/"
              << n << " (zone " << zone_inst << "/" << zone << ")");
  CHECK(ok_gsf >= n * 6 / 10);
  CHECK(zone >= 4);
  CHECK(zone_gsf >= zone * 3 / 4);
  if (paper) {
    CHECK(zone_gsf > zone_inst);
    CHECK(ok_gsf > ok_inst);
  } else {
    CHECK(zone_gsf >= zone_inst);
    CHECK(zone_inst >= zone * 3 / 4);
  }
  if (!cfg.verify.enabled) {
    CHECK(confident == 0);  // without whole-scan verification nothing vouches for an answer
    return;
  }
  // Declining works: answers the library vouches for are right, and most right answers are vouched for.
  CHECK(confident_right == confident);
  CHECK(confident * 10 >= ok_gsf * 9);
}

// A gate that no match passes (omegas are at most 1) leaves only the fill below it (kFillPairs,
// gsf_filter.h): the queries still localize, from tier-0 pairs.
TEST_CASE("Matches below the GSF gate fill a short pair set and still localize") {
  const auto& w = tiny_world();
  LocalizerConfig cfg = w.config;
  cfg.match.min_similarity = 1.0f;  // an omega of 1 needs identical fields
  const size_t n = std::min<size_t>(16, w.queries.size());
  Workspace ws(cfg);
  Localizer loc;
  REQUIRE(loc.init(cfg, w.map, ws.data(), ws.bytes()) == Status::Ok);
  int filled_ok = 0;
  for (size_t k = 0; k < n; ++k) {
    const auto& q = w.queries[k];
    LocalizeResult r;
    loc.localize(q.view(), &r);
    CHECK(r.gsf_survivors == 0);
    CHECK(r.correspondences <= kFillPairs);
    if (r.query_triangles > 0 && r.triangle_matches > r.heading_dropped) CHECK(r.below_gate_matches > 0);
    filled_ok += r.status == Status::Ok && gsf_test::pose_ok(r.map_T_scan, q.truth);
  }
  INFO("with the fill " << filled_ok << " of " << n);
  CHECK(filled_ok * 2 >= int(n));
}

TEST_CASE("A rigidly transformed scan gives the correspondingly transformed pose") {
  const auto& w = tiny_world();
  Workspace ws(w.config);
  Localizer loc;
  REQUIRE(loc.init(w.config, w.map, ws.data(), ws.bytes()) == Status::Ok);
  int checked = 0;
  for (size_t k = 0; k < w.queries.size() && checked < 3; ++k) {
    const auto& q = w.queries[k];
    LocalizeResult r1;
    // Well-constrained queries only: with few inliers an unrefined pose carries degrees of error.
    if (loc.localize(q.view(), &r1) != Status::Ok || !gsf_test::pose_ok(r1.map_T_scan, q.truth) || r1.inliers < 7)
      continue;
    // Points p' = S p: the same place seen by a sensor moved by S^-1, so the pose becomes T S^-1.
    Eigen::Isometry3d S = Eigen::Isometry3d::Identity();
    S.linear() = Eigen::AngleAxisd(0.8, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    S.translation() = Eigen::Vector3d(3.0, -2.0, 0.0);
    gsf_test::QueryScan moved = q;
    for (size_t i = 0; i < q.labels.size(); ++i) {
      const Eigen::Vector3d p = S * Eigen::Vector3d(q.xyzi[4 * i], q.xyzi[4 * i + 1], q.xyzi[4 * i + 2]);
      for (int d = 0; d < 3; ++d) moved.xyzi[4 * i + d] = static_cast<float>(p[d]);
    }
    LocalizeResult r2;
    REQUIRE(loc.localize(moved.view(), &r2) == Status::Ok);
    const Eigen::Isometry3d expected = r1.map_T_scan * S.inverse();
    INFO("query " << k << " inliers " << r1.inliers << " / " << r2.inliers);
    CHECK((r2.map_T_scan.translation() - expected.translation()).norm() < 1.5);
    CHECK(Eigen::AngleAxisd(r2.map_T_scan.rotation().transpose() * expected.rotation()).angle() < 5.0 * M_PI / 180.0);
    CHECK(gsf_test::pose_ok(r2.map_T_scan, q.truth * S.inverse()));
    ++checked;
  }
  CHECK(checked == 3);
}

// Localizer::score_pose is what the evaluation's diagnostics compare the truth with the hypotheses by
// (truth_verified_score against their verified scores), so it must score a pose exactly as verification
// scores a hypothesis: the same weights and the same disagree weight. Without the pattern search
// (refine_top 0) every fully verified hypothesis was scored at its own reported x, y and heading.
TEST_CASE("score_pose scores a hypothesis' pose as verification scored it") {
  const auto& w = tiny_world();
  LocalizerConfig cfg = w.config;
  cfg.verify.refine_top = 0;
  REQUIRE(cfg.verify.disagree_weight != 1.0f);  // else a dropped disagree weight would go unseen
  Workspace ws(cfg);
  Localizer loc;
  REQUIRE(loc.init(cfg, w.map, ws.data(), ws.bytes()) == Status::Ok);
  int checked = 0, with_disagreement = 0;
  for (size_t q = 0; q < w.queries.size(); ++q) {
    LocalizeResult r;
    if (loc.localize(w.queries[q].view(), &r) != Status::Ok || !r.verified) continue;
    for (uint32_t k = 0; k < std::min(r.hypotheses, kMaxReportedHypotheses); ++k) {
      const HypothesisReport& h = r.hypothesis[k];
      if (!h.fully_verified) continue;
      Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
      T.linear() = Eigen::AngleAxisd(h.yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
      T.translation() = Eigen::Vector3d(h.x, h.y, 0.0);
      const PoseVerification v = loc.score_pose(T);
      INFO("query " << q << " hypothesis " << k);
      // The reported heading is rounded to a float in degrees: a voxel or two may change cells.
      const double tolerance = 0.01 * (h.verified_agree + h.verified_disagree) + 1.0;
      CHECK(std::fabs(v.score - h.verified_score) <= tolerance);
      CHECK(std::fabs(v.disagree - h.verified_disagree) <= tolerance);
      with_disagreement += h.verified_disagree > 0.05f * h.verified_agree;
      ++checked;
    }
  }
  CHECK(checked >= 50);
  CHECK(with_disagreement >= 10);  // the disagree weight shows in these scores
}

// The sparse rematch (TriangleConfig::sparse_side_tolerance): a scan whose triangles find fewer than
// kSparseScanCandidates map candidates is matched at the looser tolerance, which accepts a superset;
// any other scan is answered exactly as without it. The heading votes count the candidates of every
// triangle when the scan has at most match.heading_sample_triangles (an estimate beyond). Thinned scans
// (every k-th point, as a sparser sensor sees) bring the tiny world's queries below the threshold.
TEST_CASE("Only a scan with few candidates is matched at the looser tolerance") {
  const auto& w = tiny_world();
  LocalizerConfig off = w.config;
  off.triangle.sparse_side_tolerance = 0.0f;
  REQUIRE(w.config.triangle.sparse_side_tolerance > w.config.triangle.relative_side_tolerance);
  Workspace ws_on(w.config), ws_off(off);
  Localizer on_loc, off_loc;
  REQUIRE(on_loc.init(w.config, w.map, ws_on.data(), ws_on.bytes()) == Status::Ok);
  REQUIRE(off_loc.init(off, w.map, ws_off.data(), ws_off.bytes()) == Status::Ok);
  int rematched = 0, unchanged = 0;
  for (size_t q = 0; q < w.queries.size(); ++q) {
    for (int keep_every : {1, 6}) {
      gsf_test::QueryScan scan = w.queries[q];
      if (keep_every > 1) {
        gsf_test::QueryScan thin = scan;
        thin.xyzi.clear();
        thin.labels.clear();
        thin.logits.clear();
        const bool logits = !scan.logits.empty();
        for (size_t i = 0; i < scan.labels.size(); i += keep_every) {
          thin.labels.push_back(scan.labels[i]);
          for (int d = 0; d < 4; ++d) thin.xyzi.push_back(scan.xyzi[4 * i + d]);
          for (int c = 0; logits && c < kNumClasses; ++c) thin.logits.push_back(scan.logits[kNumClasses * i + c]);
        }
        scan = thin;
      }
      LocalizeResult a, b;
      on_loc.localize(scan.view(), &a);
      off_loc.localize(scan.view(), &b);
      INFO("query " << q << " keep every " << keep_every << " candidates " << b.match_candidates);
      CHECK_FALSE(b.sparse_rematch);
      if (b.query_instances < 3) continue;
      if (b.query_triangles <= w.config.match.heading_sample_triangles)
        CHECK(a.sparse_rematch == (b.match_candidates < kSparseScanCandidates));
      if (a.sparse_rematch) {
        CHECK(a.match_candidates >= b.match_candidates);  // a looser tolerance accepts a superset
        ++rematched;
      } else {
        CHECK(a.status == b.status);
        CHECK(a.map_T_scan.matrix() == b.map_T_scan.matrix());
        CHECK(a.confidence == b.confidence);
        ++unchanged;
      }
    }
  }
  CHECK(rematched >= 3);
  CHECK(unchanged >= 10);
}

TEST_CASE("Same scan and map give bit-identical results (tiny world and tiny lattice)") {
  // The lattice runs every new path at full tilt: heading votes, shift votes (sorts, bin selection),
  // coarse/full/refined verification; ties anywhere must break the same way every time.
  for (int which = 0; which < 2; ++which) {
    const auto& w = which == 0 ? tiny_world() : gsf_test::tiny_lattice_world();
    Workspace a(w.config), b(w.config);
    Localizer la, lb;
    REQUIRE(la.init(w.config, w.map, a.data(), a.bytes()) == Status::Ok);
    REQUIRE(lb.init(w.config, w.map, b.data(), b.bytes()) == Status::Ok);
    for (size_t k = 0; k < w.queries.size(); k += (which == 0 ? 3 : 2)) {
      LocalizeResult r1, r2, r3;
      la.localize(w.queries[k].view(), &r1);
      lb.localize(w.queries[k].view(), &r2);
      la.localize(w.queries[k].view(), &r3);  // again, after other work on the same localizer
      CHECK(r1.status == r2.status);
      CHECK(std::memcmp(r1.map_T_scan.data(), r2.map_T_scan.data(), sizeof(double) * 16) == 0);
      CHECK(std::memcmp(r1.map_T_scan.data(), r3.map_T_scan.data(), sizeof(double) * 16) == 0);
      CHECK(r1.inliers == r3.inliers);
      CHECK(r1.confidence == r3.confidence);
      CHECK(r1.hypotheses == r3.hypotheses);
      CHECK(r1.chosen_hypothesis == r3.chosen_hypothesis);
      CHECK(std::memcmp(r1.hypothesis, r3.hypothesis, sizeof(r1.hypothesis)) == 0);
    }
  }
}

TEST_CASE("The hypothesis reports name their hypotheses; the answer's report carries its pose") {
  // The reports are ranked by verified score, chosen_hypothesis counts in generation order: each
  // report's index links the two (the lattice has many near-equal hypotheses, so rank != index there).
  const auto& w = gsf_test::tiny_lattice_world();
  Workspace ws(w.config);
  Localizer loc;
  REQUIRE(loc.init(w.config, w.map, ws.data(), ws.bytes()) == Status::Ok);
  int answers = 0, reordered = 0;
  for (size_t k = 0; k < w.queries.size(); k += 2) {
    LocalizeResult r;
    if (loc.localize(w.queries[k].view(), &r) != Status::Ok || !r.verified) continue;
    const uint32_t reported = std::min(r.hypotheses, kMaxReportedHypotheses);
    std::vector<bool> seen(r.hypotheses, false);
    int answer_reports = 0;
    for (uint32_t h = 0; h < reported; ++h) {
      const HypothesisReport& p = r.hypothesis[h];
      REQUIRE(p.index < r.hypotheses);
      CHECK_FALSE(seen[p.index]);  // distinct: a permutation's prefix
      seen[p.index] = true;
      if (p.index != r.chosen_hypothesis) continue;
      ++answer_reports;
      reordered += h != p.index;
      const Eigen::Vector3d t = r.map_T_scan.translation();
      const double yaw = std::atan2(r.map_T_scan.linear()(1, 0), r.map_T_scan.linear()(0, 0)) * 180.0 / M_PI;
      double dyaw = std::fabs(yaw - p.yaw_deg);
      dyaw = std::min(dyaw, 360.0 - dyaw);
      INFO("query " << k << ": answer at " << t.x() << ", " << t.y() << ", report at " << p.x << ", " << p.y);
      CHECK(std::hypot(t.x() - p.x, t.y() - p.y) < 2.0);  // refinement moves it little
      CHECK(dyaw < 3.0);
    }
    CHECK(answer_reports == 1);
    ++answers;
  }
  CHECK(answers >= 10);
  INFO("answers whose report's rank differs from its index: " << reordered);
  CHECK(reordered > 0);  // the case the index is for occurs in the lattice
}

TEST_CASE("Hostile input gets a status and the localizer stays usable") {
  const auto& w = tiny_world();
  LocalizerConfig cfg = w.config;
  cfg.max_scan_points = 50000;
  Workspace ws(cfg);
  Localizer loc;
  LocalizeResult r;
  CHECK(loc.localize(w.queries[0].view(), &r) == Status::NotInitialized);
  REQUIRE(loc.init(cfg, w.map, ws.data(), ws.bytes()) == Status::Ok);
  ScanView empty;
  CHECK(loc.localize(empty, &r) == Status::InvalidInput);
  gsf_test::QueryScan nan_scan = w.queries[0];
  for (float& x : nan_scan.xyzi) x = std::numeric_limits<float>::quiet_NaN();
  CHECK(loc.localize(nan_scan.view(), &r) == Status::InvalidInput);
  gsf_test::QueryScan huge = w.queries[0];
  for (float& x : huge.xyzi) x = 1e30f;
  CHECK(loc.localize(huge.view(), &r) == Status::InvalidInput);
  gsf_test::QueryScan one_voxel = w.queries[0];
  for (size_t i = 0; i < one_voxel.labels.size(); ++i) {
    one_voxel.xyzi[4 * i] = 5.0f;
    one_voxel.xyzi[4 * i + 1] = 5.0f;
    one_voxel.xyzi[4 * i + 2] = 0.1f;
    one_voxel.labels[i] = 80;
  }
  CHECK(loc.localize(one_voxel.view(), &r) == Status::NoSolution);
  gsf_test::QueryScan unknown = w.queries[0];
  for (auto& l : unknown.labels) l = 777;
  CHECK(loc.localize(unknown.view(), &r) == Status::InvalidInput);
  gsf_test::QueryScan big;
  big.xyzi.assign(60000 * 4, 1.0f);
  big.labels.assign(60000, 40);
  big.logits.assign(60000 * kNumClasses, 0.0f);
  CHECK(loc.localize(big.view(), &r) == Status::CapacityExceeded);
  ScanView bad_logits = w.queries[0].view();
  bad_logits.logit_dim = 7;
  CHECK(loc.localize(bad_logits, &r) == Status::InvalidArgument);
  // Still works afterwards.
  int good = 0;
  for (size_t k = 0; k < 6; ++k)
    good += loc.localize(w.queries[k].view(), &r) == Status::Ok && gsf_test::pose_ok(r.map_T_scan, w.queries[k].truth);
  CHECK(good >= 3);
}

TEST_CASE("Init rejects a small buffer, a mismatched map and a bad config") {
  const auto& w = tiny_world();
  Workspace ws(w.config);
  Localizer loc;
  CHECK(loc.init(w.config, w.map, ws.data(), Localizer::required_bytes(w.config) - 1) == Status::BufferTooSmall);
  CHECK_FALSE(loc.initialized());
  LocalizerConfig other = w.config;
  other.field.length_scale *= 2;
  Workspace ws2(other);
  CHECK(loc.init(other, w.map, ws2.data(), ws2.bytes()) == Status::ConfigMismatch);
  LocalizerConfig bad = w.config;
  bad.match.max_correspondences = 1;
  CHECK(loc.init(bad, w.map, ws.data(), ws.bytes()) == Status::InvalidArgument);
  CHECK(Localizer::required_bytes(bad) == 0);
  // A map with zero instances: init fine, every scan NoSolution.
  MapView empty_map = w.map;
  empty_map.counts.instances = 0;
  empty_map.counts.triangles = 0;
  empty_map.counts.index_keys = 0;
  static const uint32_t zero_offsets[1] = {0};
  empty_map.index_offsets = zero_offsets;
  REQUIRE(loc.init(w.config, empty_map, ws.data(), ws.bytes()) == Status::Ok);
  LocalizeResult r;
  CHECK(loc.localize(w.queries[0].view(), &r) == Status::NoSolution);
}

namespace {

// One query's result, against the truth when it is known.
struct QueryOutcome {
  int status = 0;
  bool right = false;  // within 5 m / 10 deg of the simulator's truth
  bool confident = false;
  float confidence = 0.0f;
  double pose[12] = {};  // map_frame_T_scan: rotation (row-major), then translation
  uint32_t inliers = 0, chosen = 0, hypotheses = 0;
  double t_err = 0, r_err_deg = 0;
};

QueryOutcome outcome_of(const LocalizeResult& r, const Eigen::Isometry3d& truth) {
  QueryOutcome o;
  const Eigen::Isometry3d& T = r.map_frame_T_scan;
  o.status = static_cast<int>(r.status);
  o.right = r.status == Status::Ok && gsf_test::pose_ok(T, truth);
  o.confident = r.status == Status::Ok && r.confident;
  o.confidence = r.confidence;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) o.pose[3 * i + j] = T.linear()(i, j);
    o.pose[9 + i] = T.translation()(i);
  }
  o.inliers = r.inliers;
  o.chosen = r.chosen_hypothesis;
  o.hypotheses = r.hypotheses;
  const Eigen::Isometry3d d = T.inverse() * truth;
  o.t_err = d.translation().norm();
  o.r_err_deg = Eigen::AngleAxisd(d.rotation()).angle() * 180.0 / M_PI;
  return o;
}

// The tiny world's queries at its config, localized once per process (the truth test and the
// cross-ISA check read them).
const std::vector<QueryOutcome>& tiny_outcomes() {
  static const std::vector<QueryOutcome> outcomes = [] {
    const auto& w = tiny_world();
    Workspace ws(w.config);
    Localizer loc;
    REQUIRE(loc.init(w.config, w.map, ws.data(), ws.bytes()) == Status::Ok);
    std::vector<QueryOutcome> all;
    for (const auto& q : w.queries) {
      LocalizeResult r;
      loc.localize(q.view(), &r);
      all.push_back(outcome_of(r, q.truth));
    }
    return all;
  }();
  return outcomes;
}

}  // namespace

// The simulator's truth is the oracle (not a file of earlier results): today all 31 queries are within
// 5 m / 10 deg, 0.27 m off at the median, and 30 are answered (confident); the bounds leave room for
// two misses and a few declines, never for a confident wrong answer.
TEST_CASE("The tiny world against the simulator's truth: nearly every query right, every confident answer right") {
  const std::vector<QueryOutcome>& all = tiny_outcomes();
  const int n = static_cast<int>(all.size());
  REQUIRE(n == 31);
  int right = 0, confident = 0, confident_wrong = 0;
  std::vector<double> t_err;
  for (int k = 0; k < n; ++k) {
    const QueryOutcome& o = all[k];
    INFO("query " << k << ": status " << o.status << ", " << o.t_err << " m, " << o.r_err_deg << " deg, confidence "
                  << o.confidence);
    right += o.right;
    confident += o.confident;
    if (o.confident) CHECK(o.right);  // the decision rule never vouches for a wrong pose
    confident_wrong += o.confident && !o.right;
    if (o.right) t_err.push_back(o.t_err);
  }
  std::sort(t_err.begin(), t_err.end());
  const double median = t_err.empty() ? 1e9 : t_err[t_err.size() / 2];
  INFO(right << " of " << n << " right, " << confident << " confident, median error " << median << " m");
  CHECK(right >= n - 2);
  CHECK(confident >= n - 4);
  CHECK(confident_wrong == 0);
  CHECK(median < 0.4);
}

namespace {

// The cross-ISA check's files, both in the writing build's tree and stamped with the sources
// (gsf_test::source_stamp()): the inputs (the tiny world's map blob and query scans with logits and
// truth, binary, ~32 MB) and the results (text, one line per query, every float as a C99 hex float:
// an exact round trip).
const char* isa_name() {
#if defined(__x86_64__)
  return "x86-64";
#elif defined(__aarch64__)
  return "arm64";
#else
  return "other";
#endif
}

std::string inputs_path(const std::string& results_path) {
  return results_path.substr(0, results_path.rfind('.')) + "_inputs.bin";
}

struct Inputs {
  std::string stamp;
  std::vector<uint64_t> blob;  // the map, 8-byte aligned for load_map
  size_t bytes = 0;
  std::vector<gsf_test::QueryScan> queries;
};

template <typename T>
bool put(FILE* f, const T* p, size_t n) {
  return std::fwrite(p, sizeof(T), n, f) == n;
}
template <typename T>
bool get(FILE* f, T* p, size_t n) {
  return std::fread(p, sizeof(T), n, f) == n;
}

[[maybe_unused]] bool write_inputs(const std::string& path, const gsf_test::TinyWorld& w) {
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return false;
  const std::string stamp = gsf_test::source_stamp();
  const uint64_t sizes[3] = {stamp.size(), w.bytes, w.queries.size()};
  bool ok = put(f, "GSFISA1", 8) && put(f, sizes, 3) && put(f, stamp.data(), stamp.size()) &&
            put(f, reinterpret_cast<const char*>(w.blob.data()), w.bytes);
  for (const auto& q : w.queries) {
    const uint64_t n = q.labels.size();
    ok = ok && put(f, &n, 1) && put(f, q.xyzi.data(), 4 * n) && put(f, q.labels.data(), n) &&
         put(f, q.logits.data(), n * kNumClasses) && put(f, q.truth.data(), 16);
  }
  return std::fclose(f) == 0 && ok;
}

bool read_inputs(const std::string& path, Inputs* in) {
  FILE* f = std::fopen(path.c_str(), "rb");
  if (!f) return false;
  char magic[8];
  uint64_t sizes[3];
  bool ok = get(f, magic, 8) && std::memcmp(magic, "GSFISA1", 8) == 0 && get(f, sizes, 3) && sizes[0] < 1000 &&
            sizes[1] < (uint64_t(1) << 32) && sizes[2] < 100000;
  if (ok) {
    in->stamp.resize(sizes[0]);
    in->bytes = sizes[1];
    in->blob.assign(sizes[1] / 8 + 1, 0);
    ok = get(f, &in->stamp[0], sizes[0]) && get(f, reinterpret_cast<char*>(in->blob.data()), sizes[1]);
    in->queries.resize(sizes[2]);
  }
  for (size_t k = 0; ok && k < in->queries.size(); ++k) {
    gsf_test::QueryScan& q = in->queries[k];
    uint64_t n = 0;
    ok = get(f, &n, 1) && n < (uint64_t(1) << 24);
    if (!ok) break;
    q.xyzi.resize(4 * n);
    q.labels.resize(n);
    q.logits.resize(n * kNumClasses);
    ok = get(f, q.xyzi.data(), 4 * n) && get(f, q.labels.data(), n) && get(f, q.logits.data(), n * kNumClasses) &&
         get(f, q.truth.data(), 16);
  }
  std::fclose(f);
  return ok;
}

// Localizes the inputs with the tiny world's config (tiny_world.h).
std::vector<QueryOutcome> localize_inputs(const Inputs& in) {
  LocalizerConfig cfg;
  cfg.max_scan_points = 262144;
  MapView map;
  REQUIRE(load_map(in.blob.data(), in.bytes, &map) == Status::Ok);
  Workspace ws(cfg);
  Localizer loc;
  REQUIRE(loc.init(cfg, map, ws.data(), ws.bytes()) == Status::Ok);
  std::vector<QueryOutcome> all;
  for (const auto& q : in.queries) {
    LocalizeResult r;
    loc.localize(q.view(), &r);
    all.push_back(outcome_of(r, q.truth));
  }
  return all;
}

bool write_results(const std::string& path, const std::vector<QueryOutcome>& all) {
  FILE* f = std::fopen(path.c_str(), "w");
  if (!f) return false;
  std::fprintf(f, "# gsf-loc tiny-world results; source %s; isa %s; queries %zu\n", gsf_test::source_stamp(),
               isa_name(), all.size());
  for (const QueryOutcome& o : all) {
    std::fprintf(f, "%d %d %d %a %u %u %u", o.status, o.right ? 1 : 0, o.confident ? 1 : 0, double(o.confidence),
                 o.inliers, o.chosen, o.hypotheses);
    for (double v : o.pose) std::fprintf(f, " %a", v);
    std::fprintf(f, "\n");
  }
  return std::fclose(f) == 0;
}

// Reads a results file; *stamp gets the header's source stamp. False if absent or malformed.
bool read_results(const std::string& path, std::string* stamp, std::vector<QueryOutcome>* all) {
  FILE* f = std::fopen(path.c_str(), "r");
  if (!f) return false;
  char line[1024];
  bool ok = std::fgets(line, sizeof(line), f) != nullptr;
  if (ok) {
    const std::string h(line);
    const size_t a = h.find("source "), b = h.find(';', a);
    ok = a != std::string::npos && b != std::string::npos;
    if (ok) *stamp = h.substr(a + 7, b - a - 7);
  }
  all->clear();
  while (ok && std::fgets(line, sizeof(line), f)) {
    QueryOutcome o;
    int right = 0, confident = 0, used = 0;
    double confidence = 0;
    ok = std::sscanf(line, "%d %d %d %la %u %u %u%n", &o.status, &right, &confident, &confidence, &o.inliers, &o.chosen,
                     &o.hypotheses, &used) == 7;
    for (double& v : o.pose) {
      int more = 0;
      ok = ok && std::sscanf(line + used, " %la%n", &v, &more) == 1;
      used += more;
    }
    o.right = right != 0;
    o.confident = confident != 0;
    o.confidence = static_cast<float>(confidence);
    all->push_back(o);
  }
  std::fclose(f);
  return ok;
}

bool same_bits(const QueryOutcome& a, const QueryOutcome& b) {
  return a.status == b.status && a.right == b.right && a.confident == b.confident &&
         std::memcmp(&a.confidence, &b.confidence, sizeof(float)) == 0 &&
         std::memcmp(a.pose, b.pose, sizeof(a.pose)) == 0 && a.inliers == b.inliers && a.chosen == b.chosen &&
         a.hypotheses == b.hypotheses;
}

// The largest difference of the rotation entries (first) and of the translation (second).
[[maybe_unused]] std::pair<double, double> pose_difference(const QueryOutcome& a, const QueryOutcome& b) {
  double r = 0, t = 0;
  for (int k = 0; k < 9; ++k) r = std::max(r, std::fabs(a.pose[k] - b.pose[k]));
  for (int k = 9; k < 12; ++k) t = std::max(t, std::fabs(a.pose[k] - b.pose[k]));
  return {r, t};
}

}  // namespace

// x86-64 against ARM64 on the same inputs, from the same sources. A host build writes the tiny world
// (map blob, query scans with their logits, truth) and its results on it to its own tree (GSF_ISA_RESULTS
// and the _inputs.bin beside it), after checking that the written inputs localize to the same results
// bit for bit. The aarch64 build (under qemu) reads the host release build's files (GSF_ISA_REFERENCE;
// scripts/test.sh runs the release preset first), localizes the same scans against the same map and
// compares. Bit for bit: status, verdict, decision, confidence, inliers, chosen hypothesis and
// hypothesis count. Within 1e-6 m and 1e-7 (rotation matrix entries): the pose, whose double-precision
// last bits follow libm (sin, cos, atan2 round differently on the two ISAs' glibc; measured 2026-12-03:
// every pose differs in its last bits, by at most 1.2e-8 m and 1.1e-9; FMA contraction is off on both,
// -std=c++17).
// The shared inputs are what makes this tight: the simulator's own scans already differ between the
// ISAs (libm again), so the ARM64 build's own world is checked against the truth instead (test above).
// Skipped (ctest: Skipped) when the release files are absent (the aarch64 preset run alone) or from
// other sources.
TEST_CASE("x86-64 and ARM64 give the same results, bit for bit, on the same tiny-world inputs", "[cross-isa]") {
#ifndef GSF_ISA_REFERENCE
  const std::vector<QueryOutcome>& mine = tiny_outcomes();
  REQUIRE(write_inputs(inputs_path(GSF_ISA_RESULTS), tiny_world()));
  REQUIRE(write_results(GSF_ISA_RESULTS, mine));
  Inputs in;
  REQUIRE(read_inputs(inputs_path(GSF_ISA_RESULTS), &in));
  CHECK(in.stamp == gsf_test::source_stamp());
  std::string stamp;
  std::vector<QueryOutcome> back;
  REQUIRE(read_results(GSF_ISA_RESULTS, &stamp, &back));
  CHECK(stamp == gsf_test::source_stamp());
  const std::vector<QueryOutcome> again = localize_inputs(in);
  REQUIRE(back.size() == mine.size());
  REQUIRE(again.size() == mine.size());
  for (size_t k = 0; k < mine.size(); ++k) {
    INFO("query " << k);
    CHECK(same_bits(back[k], mine[k]));   // the results file round-trips exactly
    CHECK(same_bits(again[k], mine[k]));  // and so do the inputs and the config
  }
#else
  Inputs in;
  std::string stamp;
  std::vector<QueryOutcome> ref;
  const std::string reference = GSF_ISA_REFERENCE;
  GSF_SKIP_UNLESS(read_results(reference, &stamp, &ref) && read_inputs(inputs_path(reference), &in),
                  "no release reference at " + reference + " (run the release preset's tests first)");
  GSF_SKIP_UNLESS(stamp == gsf_test::source_stamp() && in.stamp == stamp,
                  "the release reference at " + reference + " is from other sources (" + stamp + "; these are " +
                      gsf_test::source_stamp() + ")");
  const std::vector<QueryOutcome> mine = localize_inputs(in);
  CHECK(write_results(GSF_ISA_RESULTS, mine));  // for a look at what differs
  REQUIRE(ref.size() == mine.size());
  uint32_t same = 0;
  double max_r = 0, max_t = 0;
  for (size_t k = 0; k < mine.size(); ++k) {
    const QueryOutcome &a = mine[k], &b = ref[k];
    INFO("query " << k << ": ARM64 status " << a.status << " confidence " << a.confidence << " at (" << a.pose[9]
                  << ", " << a.pose[10] << "); x86-64 status " << b.status << " confidence " << b.confidence << " at ("
                  << b.pose[9] << ", " << b.pose[10] << ")");
    CHECK(a.status == b.status);
    CHECK(a.right == b.right);
    CHECK(a.confident == b.confident);
    CHECK(std::memcmp(&a.confidence, &b.confidence, sizeof(float)) == 0);
    CHECK(a.inliers == b.inliers);
    CHECK(a.chosen == b.chosen);
    CHECK(a.hypotheses == b.hypotheses);
    const std::pair<double, double> d = pose_difference(a, b);
    CHECK(d.first < 1e-7);
    CHECK(d.second < 1e-6);
    max_r = std::max(max_r, d.first);
    max_t = std::max(max_t, d.second);
    same += same_bits(a, b);
  }
  WARN(same << " of " << mine.size() << " results bit-identical on " << isa_name()
            << " and the release reference; largest pose differences " << max_t << " m, " << max_r
            << " (rotation entries)");
#endif
}

TEST_CASE("The per-stage budget is the layout itself: its parts sum to required_bytes, with and without refinement") {
  for (bool refine : {false, true}) {
    LocalizerConfig cfg = tiny_world().config;
    cfg.refine.enabled = refine;
    const Localizer::Budget b = Localizer::budget(cfg);
    const size_t parts = b.voxel + b.cluster + b.poles + b.field + b.triangle + b.match + b.gsf_cache +
                         b.correspondence + b.clique + b.refine + b.window;
    INFO("refine " << refine << ": parts " << parts << ", other " << b.other << ", total " << b.total);
    CHECK(b.total == Localizer::required_bytes(cfg));
    CHECK(parts + b.other == b.total);
    // `other` is only the Impl object (with its copy of the label set, ~11 KB) and its alignment, not a
    // stage's memory gone astray.
    CHECK(b.other < sizeof(ClassTable) + 8192);
    CHECK(b.poles == 0);  // SemanticKITTI has pole and trunk classes: no geometric poles
    for (size_t stage : {b.voxel, b.cluster, b.field, b.triangle, b.match, b.gsf_cache, b.correspondence, b.clique})
      CHECK(stage > 0);
    CHECK((b.refine > 0) == (refine || cfg.track.refine));  // tracking's ICP shares the refiner
    LocalizerConfig no_track = cfg;
    no_track.track.refine = false;
    CHECK((Localizer::budget(no_track).refine > 0) == refine);
    // Growing one stage's capacity grows that stage's part and nothing else.
    // The graph's capacity grows the clique stage; the selection holds the shift votes' pairs, which
    // are more than the graph's, so it grows with those.
    LocalizerConfig more = cfg;
    more.match.max_correspondences *= 2;
    REQUIRE(more.hypotheses.shift_vote_pairs > more.match.max_correspondences);
    const Localizer::Budget m = Localizer::budget(more);
    CHECK(m.correspondence == b.correspondence);
    CHECK(m.clique > b.clique);
    CHECK(m.voxel == b.voxel);
    CHECK(m.total == Localizer::required_bytes(more));
    LocalizerConfig votes = cfg;
    votes.hypotheses.shift_vote_pairs *= 2;
    const Localizer::Budget v = Localizer::budget(votes);
    CHECK(v.correspondence > b.correspondence);
    CHECK(v.clique > b.clique);
    CHECK(v.voxel == b.voxel);
    CHECK(v.total == Localizer::required_bytes(votes));
  }
  LocalizerConfig bad;
  bad.match.max_correspondences = 1;
  CHECK(Localizer::budget(bad).total == 0);
}

// A scan with more voxels than voxel.max_voxels is still localized on the first max_voxels voxels
// (scan order), and the result says it was truncated; within the capacity it is not.
TEST_CASE("A scan beyond voxel.max_voxels is truncated, reported, and still answered") {
  const auto& w = tiny_world();
  LocalizerConfig cfg = w.config;
  Workspace full_ws(cfg);
  Localizer full;
  REQUIRE(full.init(cfg, w.map, full_ws.data(), full_ws.bytes()) == Status::Ok);
  LocalizeResult r;
  REQUIRE(full.localize(w.queries[0].view(), &r) == Status::Ok);
  const uint32_t voxels = r.scan_voxels;
  REQUIRE(voxels > 1000);
  REQUIRE(voxels < cfg.voxel.max_voxels);
  cfg.voxel.max_voxels = voxels - 500;
  Workspace small_ws(cfg);
  CHECK(Localizer::required_bytes(cfg) < Localizer::required_bytes(w.config));
  Localizer small;
  REQUIRE(small.init(cfg, w.map, small_ws.data(), small_ws.bytes()) == Status::Ok);
  LocalizeResult t;
  const Status s = small.localize(w.queries[0].view(), &t);
  CHECK((s == Status::Ok || s == Status::NoSolution));
  CHECK(t.scan_voxels == cfg.voxel.max_voxels);
  CHECK(t.capacity_truncated);
}

TEST_CASE("An answer from fewer than min_inliers + 2 instances is never vouched for") {
  // Tiny-world scans with their instance-class points kept only within r metres of the sensor, so
  // that 3 or 4 instances remain: any hypothesis explains its own clique's 3, so such an answer has
  // at most one instance of evidence, and its confidence is capped (Localizer::kFewInstancesConfidence).
  const auto& w = tiny_world();
  ClassTable table;
  semantic_kitti_class_table(&table);
  Workspace ws(w.config);
  Localizer loc;
  REQUIRE(loc.init(w.config, w.map, ws.data(), ws.bytes()) == Status::Ok);
  const uint32_t few = w.config.hypotheses.min_inliers + 2;
  int capped = 0, held_down = 0;
  for (size_t q = 0; q < w.queries.size(); ++q) {
    for (float r : {6.0f, 9.0f, 12.0f, 16.0f}) {
      const gsf_test::QueryScan& scan = w.queries[q];
      gsf_test::QueryScan near = scan;
      near.xyzi.clear();
      near.labels.clear();
      near.logits.clear();
      for (size_t i = 0; i < scan.labels.size(); ++i) {
        const int c = table.library_class(scan.labels[i]);
        const float* p = &scan.xyzi[4 * i];
        const bool instance = c >= 0 && c < kNumClasses && (kDefaultInstanceClasses & class_bit(c));
        if (instance && p[0] * p[0] + p[1] * p[1] > r * r) continue;
        near.labels.push_back(scan.labels[i]);
        near.xyzi.insert(near.xyzi.end(), p, p + 4);
        near.logits.insert(near.logits.end(), scan.logits.begin() + kNumClasses * i,
                           scan.logits.begin() + kNumClasses * (i + 1));
      }
      LocalizeResult out;
      if (loc.localize(near.view(), &out) != Status::Ok || !out.verified || out.query_instances >= few) continue;
      INFO("query " << q << " r " << r << ": " << out.query_instances << " instances, confidence " << out.confidence);
      const double uncapped = confidence_probability(out.confidence_evidence);
      CHECK(out.confidence == std::min(uncapped, Localizer::kFewInstancesConfidence));
      CHECK_FALSE(out.confident);
      ++capped;
      held_down += uncapped > Localizer::kFewInstancesConfidence;
    }
  }
  INFO(capped << " answers from fewer than " << few << " instances, " << held_down << " of them held down");
  CHECK(capped >= 3);
  CHECK(held_down >= 1);
}

TEST_CASE("The confidence's probes read confidence.probe_points voxels, whatever verification samples") {
  // The probes' sample is the one the model is fitted at (core/src/confidence.cpp): a scan of at most
  // confidence.probe_points voxels is read whole, however few verification scores a hypothesis on, and a
  // smaller setting strides it as verification does (n voxels at stride ceil(n / max): ceil(n / stride)).
  const auto& w = tiny_world();
  auto samples_at = [](uint32_t n, uint32_t max_points) {
    const uint32_t stride = (n + max_points - 1) / max_points;
    return (n + stride - 1) / stride;
  };
  struct Setting {
    uint32_t verify_points, probe_points;
  };
  for (const Setting& s :
       {Setting{1000, w.config.confidence.probe_points}, Setting{w.config.verify.max_points, 1000}}) {
    LocalizerConfig config = w.config;
    config.verify.max_points = s.verify_points;
    config.confidence.probe_points = s.probe_points;
    Workspace ws(config);
    Localizer loc;
    REQUIRE(loc.init(config, w.map, ws.data(), ws.bytes()) == Status::Ok);
    int checked = 0;
    for (size_t q = 0; q < w.queries.size() && checked < 3; ++q) {
      LocalizeResult out;
      if (loc.localize(w.queries[q].view(), &out) != Status::Ok || !out.verified) continue;
      INFO("verify " << s.verify_points << ", probes " << s.probe_points << ", query " << q << ": " << out.scan_voxels
                     << " voxels");
      REQUIRE(out.scan_voxels > 2000u);  // so that 1000 strides it
      REQUIRE(out.scan_voxels <= w.config.confidence.probe_points);
      CHECK(out.confidence_evidence.samples == samples_at(out.scan_voxels, s.probe_points));
      if (s.probe_points == w.config.confidence.probe_points) CHECK(out.confidence_evidence.samples == out.scan_voxels);
      ++checked;
    }
    CHECK(checked == 3);
  }
}
