// Port layer: SemanticKITTI round trip and rejection of malformed files; real SemanticKITTI and
// nuScenes-lidarseg samples; logit synthesis.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "gsf/port/logit_synthesis.h"
#include "gsf/port/nuscenes.h"
#include "gsf/port/semantic_kitti.h"
#include "skip.h"

namespace test_port {

using namespace gsf;
using namespace gsf::port;
namespace fs = std::filesystem;

namespace {
std::string tmp(const std::string& name) {
  const std::string d = std::string(GSF_TEST_TMP_DIR) + "/" + name;
  fs::remove_all(d);
  return d;
}
void write_bytes(const fs::path& p, const std::string& bytes) {
  std::ofstream f(p, std::ios::binary | std::ios::trunc);
  f << bytes;
}
}  // namespace

TEST_CASE("SemanticKITTI writer -> reader round trip is exact") {
  const std::string root = tmp("roundtrip");
  SemanticKittiWriter w;
  REQUIRE(w.open(root, "05") == Status::Ok);
  const float pts[12] = {1.5f, -2.25f, 0.125f, 0.5f, 10.0f, 20.0f, -1.0f, 0.9f, 3.0f, 4.0f, 5.0f, 0.0f};
  const uint32_t labels[3] = {80u | (7u << 16), 40u, 70u};
  std::vector<float> logits(3 * kNumClasses);
  for (size_t i = 0; i < logits.size(); ++i) logits[i] = 0.1f * float(i);
  REQUIRE(w.write_scan(3, pts, labels, logits.data(), 3) == Status::Ok);
  REQUIRE(w.write_scan(7, pts, labels, nullptr, 2) == Status::Ok);
  std::vector<Eigen::Isometry3d> poses(8, Eigen::Isometry3d::Identity());
  poses[3].linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  poses[3].translation() = Eigen::Vector3d(123.456789, -9.87654321, 0.5);
  REQUIRE(w.write_poses(poses) == Status::Ok);
  SemanticKittiSource src;
  REQUIRE(src.open(root, "05") == Status::Ok);
  REQUIRE(src.size() == 2);
  CHECK(src.frame_id(0) == 3);
  CHECK(src.frame_id(1) == 7);
  OwnedScanBuffer buf(16, true);
  REQUIRE(src.read(0, buf.buffer()) == Status::Ok);
  REQUIRE(buf.buffer().count == 3);
  CHECK(std::memcmp(buf.buffer().points, pts, sizeof(pts)) == 0);
  CHECK(std::memcmp(buf.buffer().labels, labels, sizeof(labels)) == 0);
  REQUIRE(buf.buffer().has_logits);
  CHECK(std::memcmp(buf.buffer().logits, logits.data(), logits.size() * 4) == 0);
  Eigen::Isometry3d p;
  REQUIRE(src.pose(0, &p) == Status::Ok);
  CHECK((p.matrix() - poses[3].matrix()).norm() < 1e-12);
  const ScanView v = buf.buffer().view();
  CHECK(v.count == 3);
  CHECK(v.logit_dim == static_cast<uint32_t>(kNumClasses));
}

// gsf simulate into a directory that held a longer dataset left its extra frames, which joined the new
// sequence without poses (gsf build-map failed: NotFound). A writer now replaces the whole sequence.
TEST_CASE("Writing a shorter sequence over a longer one leaves no stale frames") {
  const std::string root = tmp("rewrite");
  const float pts[8] = {5, 0, 0, 0, 6, 0, 0, 0};
  const uint32_t labels[2] = {40, 40};
  const uint8_t seg[2] = {24, 24};
  const fs::path dir = fs::path(root) / "sequences" / "00";
  {
    SemanticKittiWriter w;
    REQUIRE(w.open(root, "00") == Status::Ok);
    std::vector<float> logits(2 * kNumClasses, 0.5f);
    for (uint32_t f = 0; f < 6; ++f) REQUIRE(w.write_scan(f, pts, labels, logits.data(), 2) == Status::Ok);
    REQUIRE(w.write_poses(std::vector<Eigen::Isometry3d>(6, Eigen::Isometry3d::Identity())) == Status::Ok);
  }
  write_bytes(dir / "velodyne" / "notes.txt", "kept");  // not a frame file: left alone
  SemanticKittiWriter w;
  REQUIRE(w.open(root, "00") == Status::Ok);
  for (uint32_t f = 0; f < 4; ++f) REQUIRE(w.write_scan(f, pts, labels, nullptr, 2) == Status::Ok);
  REQUIRE(w.write_poses(std::vector<Eigen::Isometry3d>(4, Eigen::Isometry3d::Identity())) == Status::Ok);
  SemanticKittiSource src;
  REQUIRE(src.open(root, "00") == Status::Ok);
  CHECK(src.size() == 4);
  Eigen::Isometry3d p;
  for (uint32_t i = 0; i < src.size(); ++i) CHECK(src.pose(i, &p) == Status::Ok);
  CHECK(!fs::exists(dir / "logits" / "000005.bin"));
  CHECK(!fs::exists(dir / "labels" / "000004.label"));
  CHECK(fs::exists(dir / "velodyne" / "notes.txt"));
  // The same for the nuScenes-lidarseg layout.
  {
    NuScenesLidarsegWriter nw;
    REQUIRE(nw.open(root, "01") == Status::Ok);
    for (uint32_t f = 0; f < 5; ++f) REQUIRE(nw.write_scan(f, pts, seg, 2) == Status::Ok);
  }
  NuScenesLidarsegWriter nw;
  REQUIRE(nw.open(root, "01") == Status::Ok);
  REQUIRE(nw.write_scan(0, pts, seg, 2) == Status::Ok);
  CHECK(!fs::exists(fs::path(root) / "sequences" / "01" / "velodyne" / "000004.bin"));
  CHECK(!fs::exists(fs::path(root) / "sequences" / "01" / "lidarseg" / "000004.label"));
}

TEST_CASE("Malformed files give a status, count 0, and the source stays usable") {
  const std::string root = tmp("malformed");
  SemanticKittiWriter w;
  REQUIRE(w.open(root, "00") == Status::Ok);
  const float pts[8] = {5, 0, 0, 0, 6, 0, 0, 0};
  const uint32_t labels[2] = {40, 40};
  for (uint32_t f = 0; f < 6; ++f) REQUIRE(w.write_scan(f, pts, labels, nullptr, 2) == Status::Ok);
  const fs::path dir = fs::path(root) / "sequences" / "00";
  write_bytes(dir / "velodyne" / "000001.bin", std::string(20, '\0'));  // not a multiple of 16
  write_bytes(dir / "labels" / "000002.label", std::string(4, '\0'));   // 1 label for 2 points
  fs::remove(dir / "labels" / "000003.label");                          // missing labels
  const float nan_pts[8] = {5, 0, 0, 0, std::nanf(""), 0, 0, 0};
  REQUIRE(w.write_scan(4, nan_pts, labels, nullptr, 2) == Status::Ok);  // NaN point
  SemanticKittiSource src;
  REQUIRE(src.open(root, "00") == Status::Ok);
  OwnedScanBuffer buf(16, false);
  CHECK(src.read(1, buf.buffer()) == Status::CorruptData);
  CHECK(buf.buffer().count == 0);
  CHECK(src.read(2, buf.buffer()) == Status::CorruptData);
  CHECK(src.read(3, buf.buffer()) == Status::IoError);
  CHECK(src.read(4, buf.buffer()) == Status::InvalidInput);
  CHECK(buf.buffer().count == 0);
  CHECK(src.read(99, buf.buffer()) == Status::NotFound);
  OwnedScanBuffer tiny(1, false);
  CHECK(src.read(0, tiny.buffer()) == Status::CapacityExceeded);
  CHECK(src.read(0, buf.buffer()) == Status::Ok);  // usable again
  CHECK(buf.buffer().count == 2);
  SemanticKittiSource dropping;
  KittiReadOptions opt;
  opt.drop_non_finite = true;
  REQUIRE(dropping.open(root, "00", opt) == Status::Ok);
  REQUIRE(dropping.read(4, buf.buffer()) == Status::Ok);
  CHECK(buf.buffer().count == 1);
  // Logits with a bad header; garbage poses; a missing sequence.
  fs::create_directories(dir / "logits");
  write_bytes(dir / "logits" / "000005.bin", "GSFX0123456789");
  SemanticKittiSource with_logits;
  REQUIRE(with_logits.open(root, "00") == Status::Ok);
  OwnedScanBuffer lb(16, true);
  CHECK(with_logits.read(5, lb.buffer()) == Status::CorruptData);
  write_bytes(dir / "poses.txt", "1 0 0 0 0 1 0 0 0 0 1 zero\n");
  SemanticKittiSource bad_poses;
  CHECK(bad_poses.open(root, "00") == Status::CorruptData);
  SemanticKittiSource missing;
  CHECK(missing.open(root, "42") == Status::IoError);
}

namespace {
// T_a_b (3x4) for `pair_key` from a revisit_pairs.txt, or false.
bool revisit_pair(const std::string& file, uint32_t* fa, uint32_t* fb, std::string* seq, Eigen::Isometry3d* t) {
  std::ifstream f(file);
  std::string line;
  while (std::getline(f, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream s(line);
    std::string kind;
    double dist, yaw, in_gt, in_icp, m[12];
    s >> *seq >> *fa >> *fb >> kind >> dist >> yaw >> in_gt >> in_icp;
    for (double& x : m) s >> x;
    if (!s || kind.find("revisit") == std::string::npos) continue;
    t->setIdentity();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) t->matrix()(r, c) = m[4 * r + c];
    return true;
  }
  return false;
}
}  // namespace

TEST_CASE("Real SemanticKITTI samples: counts, labels and revisit poses", "[real-data]") {
  const std::string root = std::string(GSF_DATA_DIR) + "/semantickitti-samples";
  GSF_SKIP_UNLESS(fs::exists(root), "no real data at " + root);
  OwnedScanBuffer buf(200000, false);
  int scans = 0;
  for (const char* seq : {"00", "07", "08"}) {
    SemanticKittiSource src;
    REQUIRE(src.open(root, seq) == Status::Ok);
    for (uint32_t i = 0; i < src.size(); ++i) {
      REQUIRE(src.read(i, buf.buffer()) == Status::Ok);
      CHECK(buf.buffer().count >= 120067u);
      CHECK(buf.buffer().count <= 126661u);
      for (uint32_t k = 0; k < buf.buffer().count; k += 97)
        CHECK(class_from_kitti(buf.buffer().labels[k]) != kUnknownClass);
      Eigen::Isometry3d p;
      CHECK(src.pose(i, &p) == Status::Ok);
      ++scans;
    }
  }
  CHECK(scans == 10);
  uint32_t fa, fb;
  std::string seq;
  Eigen::Isometry3d t_ab;
  REQUIRE(revisit_pair(root + "/revisit_pairs.txt", &fa, &fb, &seq, &t_ab));
  SemanticKittiSource src;
  REQUIRE(src.open(root, seq) == Status::Ok);
  Eigen::Isometry3d pa, pb;
  for (uint32_t i = 0; i < src.size(); ++i) {
    if (src.frame_id(i) == fa) src.pose(i, &pa);
    if (src.frame_id(i) == fb) src.pose(i, &pb);
  }
  const Eigen::Isometry3d ours = pa.inverse() * pb;
  CHECK((ours.matrix() - t_ab.matrix()).cwiseAbs().maxCoeff() < 1e-3);
}

TEST_CASE("Real nuScenes-lidarseg samples: mapped labels, ego points dropped, revisit poses", "[real-data]") {
  const std::string root = std::string(GSF_DATA_DIR) + "/nuscenes-lidarseg-samples";
  GSF_SKIP_UNLESS(fs::exists(root), "no real data at " + root);
  NuScenesLidarsegSource src;
  REQUIRE(src.open(root, "0002") == Status::Ok);
  REQUIRE(src.size() == 40);
  OwnedScanBuffer buf(60000, false);
  REQUIRE(src.read(0, buf.buffer()) == Status::Ok);
  CHECK(buf.buffer().count > 20000);
  CHECK(buf.buffer().count < 34784);  // ego returns removed
  int road = 0;
  for (uint32_t k = 0; k < buf.buffer().count; ++k) {
    CHECK(class_from_kitti(buf.buffer().labels[k]) != kUnknownClass);
    road += buf.buffer().labels[k] == 40;
  }
  CHECK(road > 2000);
  CHECK(nuscenes_to_kitti(17) == 10);
  CHECK(nuscenes_to_kitti(30) == 70);
  uint32_t fa, fb;
  std::string scenes;
  Eigen::Isometry3d t_ab;
  REQUIRE(revisit_pair(root + "/revisit_pairs.txt", &fa, &fb, &scenes, &t_ab));
  NuScenesLidarsegSource a, b;
  REQUIRE(a.open(root, scenes.substr(0, scenes.find('/'))) == Status::Ok);
  REQUIRE(b.open(root, scenes.substr(scenes.find('/') + 1)) == Status::Ok);
  Eigen::Isometry3d pa, pb;
  REQUIRE(a.pose(fa, &pa) == Status::Ok);
  REQUIRE(b.pose(fb, &pb) == Status::Ok);
  CHECK(((pa.inverse() * pb).matrix() - t_ab.matrix()).cwiseAbs().maxCoeff() < 1e-3);
}

TEST_CASE("Logit synthesis: deterministic, argmax agrees at the documented rate, confusions only to partners") {
  std::vector<uint32_t> labels;
  for (int i = 0; i < 20000; ++i) labels.push_back(i % 2 ? 80u : 70u);  // pole / vegetation
  std::vector<float> a(labels.size() * kNumClasses), b(a.size());
  std::vector<uint32_t> ra(labels.size()), rb(labels.size());
  LogitModel m;
  synthesize_logits(m, 5, labels.data(), static_cast<uint32_t>(labels.size()), a.data(), ra.data());
  synthesize_logits(m, 5, labels.data(), static_cast<uint32_t>(labels.size()), b.data(), rb.data());
  CHECK(a == b);
  synthesize_logits(m, 6, labels.data(), static_cast<uint32_t>(labels.size()), b.data(), rb.data());
  CHECK(a != b);
  int agree_pole = 0, agree_veg = 0;
  for (size_t i = 0; i < labels.size(); ++i) {
    const int truth = class_from_kitti(labels[i]), pred = class_from_kitti(ra[i]);
    if (pred == truth) {
      (truth == kPole ? agree_pole : agree_veg)++;
    } else {
      bool partner = false;
      for (int k = 0; k < confusion_partner_count(truth); ++k) partner = partner || confusion_partner(truth, k) == pred;
      CHECK(partner);
    }
  }
  CHECK(agree_pole / 10000.0 == Approx(1.0 - confusion_probability(kPole)).margin(0.02));
  CHECK(agree_veg / 10000.0 == Approx(1.0 - confusion_probability(kVegetation)).margin(0.02));
}

}  // namespace test_port
