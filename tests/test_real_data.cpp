// Real data end to end. SemanticKITTI revisits: a map built from other frames of the sequence, then one-shot
// localization of the revisiting scan. seq 00: 52/88/850 -> 4501 (same heading, 2.96 m apart);
// seq 08: 720 -> 1500 (opposite direction, 148.5 deg). KITTI's ground truth is itself off by ~0.3 m
// (00) and ~1.15 m (08) at these loops (data README), hence the slack.
#include <catch2/catch.hpp>

#include <filesystem>

#include "gsf/class_table.h"
#include "gsf/localizer.h"
#include "gsf/port/logit_synthesis.h"
#include "gsf/port/nuscenes.h"
#include "gsf/port/semantic_kitti.h"
#include "mapping/map_builder.h"
#include "short_run.h"
#include "skip.h"

namespace test_real_data {

using namespace gsf;

namespace {

struct Outcome {
  Status status = Status::NotInitialized;
  double t_err = 1e9, r_err_deg = 1e9;
  uint32_t inliers = 0;
};

Outcome localize_revisit(const char* seq, std::initializer_list<uint32_t> map_frames, uint32_t query_frame, bool gsf) {
  Outcome o;
  const std::string root = std::string(GSF_DATA_DIR) + "/semantickitti-samples";
  port::SemanticKittiSource src;
  REQUIRE(src.open(root, seq) == Status::Ok);
  LocalizerConfig cfg;
  cfg.gsf.enabled = gsf;
  mapping::MapBuildConfig build_config;
  build_config.stages = cfg;
  mapping::MapBuilder builder(build_config);
  port::OwnedScanBuffer buf(200000, true);
  port::LogitModel model;
  auto read = [&](uint32_t i, uint64_t id) {
    REQUIRE(src.read(i, buf.buffer()) == Status::Ok);
    port::synthesize_logits(model, id, buf.buffer().labels, buf.buffer().count, buf.buffer().logits,
                            buf.buffer().labels);
    buf.buffer().has_logits = true;
  };
  int query_index = -1;
  for (uint32_t i = 0; i < src.size(); ++i) {
    const uint32_t f = src.frame_id(i);
    if (f == query_frame) query_index = static_cast<int>(i);
    if (std::find(map_frames.begin(), map_frames.end(), f) == map_frames.end()) continue;
    Eigen::Isometry3d pose;
    REQUIRE(src.pose(i, &pose) == Status::Ok);
    read(i, 1000000u + f);
    REQUIRE(builder.add_scan(buf.buffer().view(), pose) == Status::Ok);
  }
  REQUIRE(query_index >= 0);
  std::vector<uint64_t> blob;
  size_t bytes = 0;
  REQUIRE(builder.build(&blob, &bytes, nullptr) == Status::Ok);
  MapView map;
  REQUIRE(load_map(blob.data(), bytes, &map) == Status::Ok);
  std::vector<uint64_t> ws(Localizer::required_bytes(cfg) / 8 + 2);
  Localizer loc;
  REQUIRE(loc.init(cfg, map, ws.data(), ws.size() * 8) == Status::Ok);
  read(static_cast<uint32_t>(query_index), 2000000u + query_frame);
  LocalizeResult r;
  o.status = loc.localize(buf.buffer().view(), &r);
  Eigen::Isometry3d truth;
  REQUIRE(src.pose(static_cast<uint32_t>(query_index), &truth) == Status::Ok);
  const Eigen::Isometry3d d = r.map_frame_T_scan.inverse() * truth;  // KITTI's poses are the map's frame
  o.t_err = d.translation().norm();
  o.r_err_deg = Eigen::AngleAxisd(d.rotation()).angle() * 180.0 / M_PI;
  o.inliers = r.inliers;
  return o;
}

}  // namespace

TEST_CASE("Real SemanticKITTI revisits localize one-shot against a map of other frames", "[real-data]") {
  const std::string root = std::string(GSF_DATA_DIR) + "/semantickitti-samples";
  GSF_SKIP_UNLESS(std::filesystem::exists(root), "no real data at " + root);
  for (bool gsf : {false, true}) {
    const Outcome a = localize_revisit("00", {52, 88, 850}, 4501, gsf);
    INFO("seq 00, gsf " << gsf << ": " << a.t_err << " m, " << a.r_err_deg << " deg, " << a.inliers << " inliers");
    CHECK(a.status == Status::Ok);
    CHECK(a.t_err < 1.0);
    CHECK(a.r_err_deg < 3.0);
    const Outcome b = localize_revisit("08", {720}, 1500, gsf);
    INFO("seq 08, gsf " << gsf << ": " << b.t_err << " m, " << b.r_err_deg << " deg, " << b.inliers << " inliers");
    CHECK(b.status == Status::Ok);
    CHECK(b.t_err < 2.0);
    CHECK(b.r_err_deg < 3.0);
  }
}

// nuScenes-lidarseg, the one real map-and-query pair: scene 0004 maps a street, scene 0002 drives it the
// other way; scene 0001 (about 700 m away) is a distractor map. The label set is nuScenes-lidarseg's own
// (raw lidarseg ids; poles and trunks from geometry). Queries "overlap" when their true position is
// within 10 m of a mapping-drive pose. The bounds are today's measured results (bench/real_data.sh,
// docs/results.md), so a regression fails; a wrong answer at the default threshold never passes.
namespace {

struct NuScenesRun {
  uint32_t overlap = 0, correct_pose = 0, answered_right = 0, answered_wrong = 0, queries = 0;
  uint32_t correct_8_to_20 = 0;  // correct poses among query frames 8-20 (the data README's revisit frames)
  // The same drive through localize_sequence (window.scans = 3, odometry from the poses): answers.
  uint32_t window_answered_right = 0, window_answered_wrong = 0;
  // The inlier share's denominator is the scan's instances on the map's observed cells at the answer:
  // never more than all of them (share >= inliers / instances), fewer where the scan sees past the map.
  uint32_t share_below_all = 0, share_over_fewer = 0, recount_below_hypothesis = 0;
};

bool is_right(const LocalizeResult& r, const Eigen::Isometry3d& truth) {
  const Eigen::Isometry3d d = r.map_frame_T_scan.inverse() * truth;  // nuScenes poses are the map's frame
  return d.translation().norm() < 5.0 && Eigen::AngleAxisd(d.rotation()).angle() < 10.0 * M_PI / 180.0;
}

std::vector<uint64_t> build_nuscenes_map(const std::string& root, const char* seq, const LocalizerConfig& cfg,
                                         size_t* bytes) {
  port::NuScenesLidarsegSource src;
  port::KittiReadOptions opt;
  opt.raw_labels = true;
  REQUIRE(src.open(root, seq, opt) == Status::Ok);
  mapping::MapBuildConfig build_config;
  build_config.stages = cfg;
  mapping::MapBuilder builder(build_config);
  port::OwnedScanBuffer buf(60000, true);
  port::LogitModel model;
  for (uint32_t i = 0; i < src.size(); ++i) {
    Eigen::Isometry3d pose;
    REQUIRE(src.pose(i, &pose) == Status::Ok);
    REQUIRE(src.read(i, buf.buffer()) == Status::Ok);
    port::synthesize_logits(model, 1000000u + src.frame_id(i), buf.buffer().labels, buf.buffer().count,
                            buf.buffer().logits, buf.buffer().labels, cfg.classes);
    buf.buffer().has_logits = true;
    REQUIRE(builder.add_scan(buf.buffer().view(), pose) == Status::Ok);
  }
  std::vector<uint64_t> blob;
  REQUIRE(builder.build(&blob, bytes, nullptr) == Status::Ok);
  return blob;
}

NuScenesRun localize_nuscenes(const std::string& root, const char* map_seq, const char* query_seq) {
  ClassTable nus;
  nuscenes_lidarseg_class_table(&nus);
  LocalizerConfig cfg;
  cfg.classes = &nus;
  size_t bytes = 0;
  const std::vector<uint64_t> blob = build_nuscenes_map(root, map_seq, cfg, &bytes);
  MapView map;
  REQUIRE(load_map(blob.data(), bytes, &map) == Status::Ok);
  std::vector<uint64_t> ws(Localizer::required_bytes(cfg) / 8 + 2), window_ws(ws.size());
  Localizer loc, window_loc;
  REQUIRE(loc.init(cfg, map, ws.data(), ws.size() * 8) == Status::Ok);
  REQUIRE(cfg.window.scans == 3);
  REQUIRE(window_loc.init(cfg, map, window_ws.data(), window_ws.size() * 8) == Status::Ok);
  port::NuScenesLidarsegSource map_src, src;
  port::KittiReadOptions opt;
  opt.raw_labels = true;
  REQUIRE(map_src.open(root, map_seq, opt) == Status::Ok);
  REQUIRE(src.open(root, query_seq, opt) == Status::Ok);
  std::vector<Eigen::Vector3d> drive;
  for (uint32_t i = 0; i < map_src.size(); ++i) {
    Eigen::Isometry3d p;
    REQUIRE(map_src.pose(i, &p) == Status::Ok);
    drive.push_back(p.translation());
  }
  port::OwnedScanBuffer buf(60000, true);
  port::LogitModel model;
  NuScenesRun run;
  Eigen::Isometry3d last_truth = Eigen::Isometry3d::Identity();
  for (uint32_t i = 0; i < src.size(); ++i) {
    Eigen::Isometry3d truth;
    REQUIRE(src.pose(i, &truth) == Status::Ok);
    REQUIRE(src.read(i, buf.buffer()) == Status::Ok);
    port::synthesize_logits(model, 2000000u + src.frame_id(i), buf.buffer().labels, buf.buffer().count,
                            buf.buffer().logits, buf.buffer().labels, &nus);
    buf.buffer().has_logits = true;
    LocalizeResult r, w;
    const bool ok = loc.localize(buf.buffer().view(), &r) == Status::Ok;
    const bool right = ok && is_right(r, truth);
    const bool answered = ok && r.confident;  // the default decision rule
    if (ok && r.verified && r.query_instances > 0) {
      // The share's numerator is the answer's inliers recounted at its pose (never below its
      // hypothesis's count), its denominator the instances on the map's observed cells (never above all).
      const uint32_t counted = r.confidence_evidence.inliers;
      const float all = float(counted) / float(r.query_instances), share = r.confidence_evidence.inlier_share;
      run.share_below_all += share < all * (1.0f - 1e-6f) || share > 1.0f;
      run.share_over_fewer += share > all * (1.0f + 1e-6f);
      run.recount_below_hypothesis += counted < r.inliers;
    }
    if (i == 0) window_loc.reset_sequence();
    const Eigen::Isometry3d odometry = i == 0 ? Eigen::Isometry3d::Identity() : last_truth.inverse() * truth;
    last_truth = truth;
    if (window_loc.localize_sequence(buf.buffer().view(), odometry, &w) == Status::Ok && w.confident) {
      run.window_answered_right += is_right(w, truth);
      run.window_answered_wrong += !is_right(w, truth);
    }
    double nearest = 1e9;
    for (const auto& p : drive) nearest = std::min(nearest, (p - truth.translation()).head<2>().norm());
    ++run.queries;
    if (nearest < 10.0) {
      ++run.overlap;
      run.correct_pose += right;
    }
    if (i >= 8 && i <= 20) run.correct_8_to_20 += right;
    run.answered_right += answered && right;
    run.answered_wrong += answered && !right;
  }
  return run;
}

}  // namespace

TEST_CASE("Real nuScenes-lidarseg: the opposite-direction revisit localizes, the distractor map is declined",
          "[real-data]") {
  const std::string root = std::string(GSF_DATA_DIR) + "/nuscenes-lidarseg-samples";
  GSF_SKIP_UNLESS(std::filesystem::exists(root), "no real data at " + root);
  const NuScenesRun fwd = localize_nuscenes(root, "0004", "0002");
  INFO("map 0004, queries 0002: " << fwd.correct_8_to_20 << " of frames 8-20 and " << fwd.correct_pose
                                  << " correct poses of " << fwd.overlap << " overlapping; answered "
                                  << fwd.answered_right << " right, " << fwd.answered_wrong << " wrong of "
                                  << fwd.queries);
  CHECK(fwd.overlap >= 13);
  // 15 of 15 measured since geometric poles may be 1.2 m thick (13 before; 7 of 15 with every map
  // instance a triangle vertex, before MapBuildConfig::triangle_min_detections).
  CHECK(fwd.correct_pose >= 13);
  // The data README's revisit: scene 0002 frames 8-20 pass 6-8.5 m from scene 0004's drive (13 of 13
  // measured; the target is 9).
  CHECK(fwd.correct_8_to_20 >= 11);
  CHECK(fwd.answered_wrong == 0);
  // One scan at a time: 27 answered right measured (the confidence refitted with the spur family,
  // 2026-12-05 evening; 24 with the pattern search of the turned hypotheses before it, 23 with the
  // scan's own other-class weight, 24 before the sparse scans' looser triangle match, 27 with the
  // four-factor confidence model of 2026-12-03 on the same poles).
  CHECK(fwd.answered_right >= 22);
  INFO("shares below the all-instances share: " << fwd.share_below_all
                                                << ", over fewer instances: " << fwd.share_over_fewer);
  CHECK(fwd.share_below_all == 0);
  CHECK(fwd.share_over_fewer >= 10);
  CHECK(fwd.recount_below_hypothesis == 0);
  // Several scans (issue 27): the drive's last three scans tied by its odometry answer what one scan
  // cannot vouch for alone (32 of 40 measured against 27 one-shot; 32-33 against 24 before the refit of
  // 2026-12-05 evening), never wrongly.
  INFO("window of 3: answered " << fwd.window_answered_right << " right, " << fwd.window_answered_wrong << " wrong");
  CHECK(fwd.window_answered_right >= fwd.answered_right + 3);
  CHECK(fwd.window_answered_wrong == 0);
  // In a slow build (ASan, qemu: short_run.h) the forward pair only: each map build and drive costs
  // 10-40x the host's there, and the reverse and distractor runs exercise no other code.
  if (gsf_test::short_run()) return;
  // The reverse: the 0002 map (109 m) covers less of what 0004's first frames see; 13 of 13 measured
  // with the 1.2 m pole diameter (6 of 13 before), 20 answered right one-shot (21 before the pattern
  // search of the turned hypotheses and 23 before the scan's own other-class weight, both 2026-12-05;
  // 20 before the sparse scans' looser triangle match; the target: 18).
  const NuScenesRun rev = localize_nuscenes(root, "0002", "0004");
  INFO("map 0002, queries 0004: " << rev.correct_pose << " correct poses of " << rev.overlap
                                  << " overlapping; answered " << rev.answered_right << " right, " << rev.answered_wrong
                                  << " wrong of " << rev.queries);
  CHECK(rev.overlap >= 13);
  CHECK(rev.correct_pose >= 11);
  CHECK(rev.answered_right >= 18);
  CHECK(rev.answered_wrong == 0);
  // The window: 24 answered measured with exact odometry (one-shot 20; 25 and 23 before 2026-12-05).
  INFO("window of 3: answered " << rev.window_answered_right << " right, " << rev.window_answered_wrong << " wrong");
  CHECK(rev.window_answered_right >= rev.answered_right + 1);
  CHECK(rev.window_answered_wrong == 0);
  const NuScenesRun distractor = localize_nuscenes(root, "0001", "0002");
  INFO("map 0001, queries 0002: answered " << distractor.answered_right + distractor.answered_wrong << " of "
                                           << distractor.queries);
  CHECK(distractor.overlap == 0);
  CHECK(distractor.answered_wrong == 0);
  CHECK(distractor.window_answered_wrong == 0);
}

}  // namespace test_real_data
