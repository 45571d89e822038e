// Label sets end to end: a world labelled as nuScenes-lidarseg labels it (no pole, trunk, sign or fence
// class: they are inside static.manmade / static.vegetation) localizes through the label set's class
// table and the geometric pole / trunk instances, in the map builder and the localizer alike.
#include <catch2/catch.hpp>

#include <cstdio>
#include <filesystem>

#include "gsf/class_table.h"
#include "gsf/localizer.h"
#include "gsf/port/logit_synthesis.h"
#include "gsf/port/nuscenes.h"
#include "tiny_world.h"

namespace test_label_sets {

using namespace gsf;

namespace {

struct Tally {
  uint32_t queries = 0, success = 0, with_poles = 0;
};

Tally localize_all(const gsf_test::TinyWorld& w, bool gsf_on) {
  LocalizerConfig cfg = w.config;
  cfg.gsf.enabled = gsf_on;
  std::vector<uint64_t> ws(Localizer::required_bytes(cfg) / 8 + 2);
  Localizer loc;
  REQUIRE(loc.init(cfg, w.map, ws.data(), ws.size() * 8) == Status::Ok);
  Tally t;
  for (const auto& q : w.queries) {
    LocalizeResult r;
    ++t.queries;
    if (loc.localize(q.view(), &r) == Status::Ok && gsf_test::pose_ok(r.map_T_scan, q.truth)) ++t.success;
    t.with_poles += r.pole_instances > 0;
  }
  return t;
}

// The nuScenes-lidarseg table with its hosts demoted to plain stuff: the same labels, no geometry.
ClassTable nuscenes_without_hosts() {
  ClassTable nus, out;
  nuscenes_lidarseg_class_table(&nus);
  for (uint32_t i = 0; i < nus.size(); ++i) {
    const ClassTableEntry& e = nus.entry(i);
    const bool host = e.role == ClassRole::PoleHost || e.role == ClassRole::TrunkHost;
    REQUIRE(out.add(e.raw_id, e.name, e.library_class, e.library_class >= 0 ? nus.stability(e.library_class) : 0.0f,
                    host ? ClassRole::Stuff : e.role) == ClassTableError::None);
  }
  return out;
}

}  // namespace

TEST_CASE("What nuScenes-lidarseg would label: poles, signs and fences are manmade, trunks vegetation") {
  ClassTable nus;
  nuscenes_lidarseg_class_table(&nus);
  for (uint32_t kitti : {50u, 51u, 52u, 80u, 81u})
    CHECK(nus.library_class(port::kitti_to_nuscenes(kitti)) == kBuilding);
  for (uint32_t kitti : {70u, 71u}) CHECK(nus.library_class(port::kitti_to_nuscenes(kitti)) == kVegetation);
  CHECK(nus.library_class(port::kitti_to_nuscenes(10u | (7u << 16))) == kCar);  // instance bits ignored
  CHECK(nus.library_class(port::kitti_to_nuscenes(40)) == kRoad);
  CHECK(nus.library_class(port::kitti_to_nuscenes(72)) == kTerrain);
  for (uint32_t kitti : {0u, 1u, 99u, 12345u})
    CHECK(nus.library_class(port::kitti_to_nuscenes(kitti)) == kIgnoredClass);
  // Every SemanticKITTI id gives a valid lidarseg class (the writer refuses > 31).
  for (uint32_t kitti = 0; kitti < 65536; ++kitti) REQUIRE(port::kitti_to_nuscenes(kitti) <= 31);
}

TEST_CASE("Synthetic logits relabel in the scan's own label set") {
  ClassTable nus;
  nuscenes_lidarseg_class_table(&nus);
  std::vector<uint32_t> labels;
  for (uint32_t k = 0; k < 2000; ++k) labels.push_back(k % 3 == 0 ? 30u : k % 3 == 1 ? 28u : 17u);
  std::vector<float> logits(labels.size() * kNumClasses);
  std::vector<uint32_t> relabel(labels.size());
  port::LogitModel m;
  m.confusion_scale = 3.0f;  // enough confusions to see the relabelling
  port::synthesize_logits(m, 7, labels.data(), static_cast<uint32_t>(labels.size()), logits.data(), relabel.data(),
                          &nus);
  uint32_t changed = 0;
  for (size_t i = 0; i < labels.size(); ++i) {
    const int c = nus.library_class(relabel[i]);
    REQUIRE(c >= 0);  // a lidarseg id of the table, never a SemanticKITTI id
    int best = 0;
    for (int k = 1; k < kNumClasses; ++k)
      if (logits[i * kNumClasses + k] > logits[i * kNumClasses + best]) best = k;
    // The relabelled id is the argmax class wherever the table has an id for it (pole, trunk, sign: none).
    if (best != kPole && best != kTrunk && best != kTrafficSign && best != kFence) CHECK(c == best);
    changed += relabel[i] != labels[i];
  }
  CHECK(changed > 0);
}

TEST_CASE("A nuScenes-labelled world localizes through geometric poles and trunks") {
  const auto& w = gsf_test::tiny_nuscenes_world();
  REQUIRE(w.bytes > 0);
  // The map holds geometric poles / trunks (the labels have none) and records them as instance labels.
  CHECK(w.build_stats.pole_instances > 0);
  CHECK(w.build_stats.instances_by_class[kPole] + w.build_stats.instances_by_class[kTrunk] ==
        w.build_stats.pole_instances);
  CHECK((w.map.params.instance_class_mask & class_bit(kPole)) != 0);
  CHECK((w.map.params.instance_class_mask & class_bit(kTrafficSign)) == 0);

  const Tally with_geometry = localize_all(w, true);
  INFO("GSF with geometric poles: " << with_geometry.success << " of " << with_geometry.queries);
  CHECK(with_geometry.with_poles == with_geometry.queries);
  // x86-64 25 of 31, ARM64 (qemu) 20 of 31: pole extraction's thin / isolated decisions on voxel
  // centroids flip with last-bit float differences (FMA contraction), and this world is small.
  CHECK(with_geometry.success * 10 >= with_geometry.queries * 6);

  // The same labels without geometric instances (hosts demoted to stuff): cars alone, which move
  // between the drives, are far from enough.
  static const ClassTable plain = nuscenes_without_hosts();
  const gsf_test::TinyWorld* bare = gsf_test::build_sim_world(gsf::sim::SimConfig::tiny(), &plain);
  CHECK(bare->build_stats.pole_instances == 0);
  const Tally without = localize_all(*bare, true);
  INFO("GSF without geometric poles: " << without.success << " of " << without.queries);
  CHECK(without.with_poles == 0);
  CHECK(without.success * 2 < with_geometry.success);
  delete bare;
}

TEST_CASE("A map of one label set refuses a localizer of another, and the budget shows the pole stage") {
  const auto& w = gsf_test::tiny_nuscenes_world();
  LocalizerConfig kitti = w.config;
  kitti.classes = nullptr;  // SemanticKITTI: other instance classes than the map's
  std::vector<uint64_t> ws(Localizer::required_bytes(w.config) / 8 + 2);
  Localizer loc;
  CHECK(loc.init(kitti, w.map, ws.data(), ws.size() * 8) == Status::ConfigMismatch);

  // The same roles and instance classes, one stability changed: another label set (its id), refused too.
  ClassTable nus = w.classes, tweaked;
  for (uint32_t i = 0; i < nus.size(); ++i) {
    const ClassTableEntry& e = nus.entry(i);
    const float st = e.library_class < 0 ? 0.0f : e.library_class == kRoad ? 0.9f : nus.stability(e.library_class);
    REQUIRE(tweaked.add(e.raw_id, e.name, e.library_class, st, e.role) == ClassTableError::None);
  }
  REQUIRE(tweaked.id() != nus.id());
  LocalizerConfig other = w.config;
  other.classes = &tweaked;
  CHECK(map_params_from(other).instance_class_mask == w.map.params.instance_class_mask);
  CHECK(w.map.params.class_table_id == nus.id());
  CHECK(loc.init(other, w.map, ws.data(), ws.size() * 8) == Status::ConfigMismatch);

  const Localizer::Budget b = Localizer::budget(w.config);
  CHECK(b.poles > 0);
  CHECK(b.poles >= PoleExtraction::required_bytes(effective_pole_config(w.config), w.config.voxel.max_voxels));
  CHECK(b.total == Localizer::required_bytes(w.config));
  CHECK(b.voxel + b.cluster + b.poles + b.field + b.triangle + b.match + b.gsf_cache + b.correspondence + b.clique +
            b.refine + b.window + b.other ==
        b.total);
  // init copies the table: the localizer keeps working after the caller's table is gone.
  ClassTable* temp = new ClassTable(w.classes);
  LocalizerConfig cfg = w.config;
  cfg.classes = temp;
  REQUIRE(loc.init(cfg, w.map, ws.data(), ws.size() * 8) == Status::Ok);
  std::memset(static_cast<void*>(temp), 0xAB, sizeof(ClassTable));
  delete temp;
  LocalizeResult r;
  CHECK(loc.localize(w.queries[0].view(), &r) == Status::Ok);
  CHECK(r.pole_instances > 0);
  CHECK(loc.config().classes != nullptr);
  CHECK(loc.config().classes->id() == w.classes.id());
}

TEST_CASE("nuScenes-lidarseg writer and reader round trip, raw or mapped labels") {
  const std::string root = (std::filesystem::temp_directory_path() / "gsf_nus_writer_test").string();
  std::filesystem::remove_all(root);
  port::NuScenesLidarsegWriter wr;
  REQUIRE(wr.open(root, "0007") == Status::Ok);
  const float pts[3 * 4] = {5, 0, 0, 10, 0, 6, 1, 20, 1, 2, 8, 255};
  const uint8_t lab[3] = {28, 30, 17};
  REQUIRE(wr.write_scan(0, pts, lab, 3) == Status::Ok);
  const uint8_t bad[3] = {28, 32, 17};
  CHECK(wr.write_scan(1, pts, bad, 3) == Status::InvalidInput);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.translation() << 512345.25, 5412345.5, 12.125;
  REQUIRE(wr.write_poses({pose}) == Status::Ok);
  for (bool raw : {true, false}) {
    port::NuScenesLidarsegSource src;
    port::KittiReadOptions opt;
    opt.raw_labels = raw;
    REQUIRE(src.open(root, "0007", opt) == Status::Ok);
    REQUIRE(src.size() == 1);
    port::OwnedScanBuffer buf(16, false);
    REQUIRE(src.read(0, buf.buffer()) == Status::Ok);
    REQUIRE(buf.buffer().count == 3);
    for (int i = 0; i < 3; ++i) {
      CHECK(buf.buffer().labels[i] == (raw ? lab[i] : port::nuscenes_to_kitti(lab[i])));
      for (int k = 0; k < 4; ++k) CHECK(buf.buffer().points[4 * i + k] == pts[4 * i + k]);
    }
    Eigen::Isometry3d back;
    REQUIRE(src.pose(0, &back) == Status::Ok);
    CHECK(back.translation() == pose.translation());
  }
  std::filesystem::remove_all(root);
}

}  // namespace test_label_sets
