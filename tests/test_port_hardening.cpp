// Port layer, beyond tests/test_port.cpp: every logits-header defect, alignment under
// drop_non_finite, calibration/poses conventions with known answers, strict frame names, the writer's
// argument checks, nuScenes rejection paths, all real revisit pairs and every real label, the log
// helpers, and the logit model over every class.
#include <catch2/catch.hpp>

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "gsf/port/log.h"
#include "gsf/port/logit_synthesis.h"
#include "gsf/port/nuscenes.h"
#include "gsf/port/semantic_kitti.h"
#include "skip.h"

namespace test_port_hardening {

using namespace gsf;
using namespace gsf::port;
namespace fs = std::filesystem;

namespace {

std::string fresh_dir(const std::string& name) {
  const std::string d = std::string(GSF_TEST_TMP_DIR) + "/port_hardening_" + name;
  fs::remove_all(d);
  return d;
}

void write_bytes(const fs::path& p, const void* data, size_t n) {
  std::ofstream f(p, std::ios::binary | std::ios::trunc);
  f.write(static_cast<const char*>(data), static_cast<std::streamsize>(n));
}

std::vector<char> read_bytes(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return std::vector<char>((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
}

struct Pair {
  std::string seq, kind;
  uint32_t a = 0, b = 0;
  Eigen::Isometry3d t_gt = Eigen::Isometry3d::Identity();
};

std::vector<Pair> read_pairs(const std::string& file) {
  std::vector<Pair> out;
  std::ifstream f(file);
  std::string line;
  while (std::getline(f, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream s(line);
    Pair p;
    double dist, yaw, m[12];
    std::string in_gt, in_icp;  // "nan" on negative pairs, which operator>> for double rejects
    s >> p.seq >> p.a >> p.b >> p.kind >> dist >> yaw >> in_gt >> in_icp;
    for (double& x : m) s >> x;
    if (!s) continue;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) p.t_gt.matrix()(r, c) = m[4 * r + c];
    out.push_back(p);
  }
  return out;
}

template <class Source>
bool pose_of_frame(const Source& src, uint32_t frame, Eigen::Isometry3d* pose) {
  for (uint32_t i = 0; i < src.size(); ++i)
    if (src.frame_id(i) == frame) return src.pose(i, pose) == Status::Ok;
  return false;
}

const float kTwoPoints[8] = {1.0f, 2.0f, 3.0f, 0.5f, 4.0f, 5.0f, 6.0f, 0.25f};
const uint32_t kTwoLabels[2] = {40, 70};

}  // namespace

TEST_CASE("Every logits defect is CorruptData (or InvalidInput for NaN), count 0, next read fine") {
  const std::string root = fresh_dir("logits");
  SemanticKittiWriter w;
  REQUIRE(w.open(root, "00") == Status::Ok);
  std::vector<float> logits(2 * kNumClasses);
  for (size_t i = 0; i < logits.size(); ++i) logits[i] = float(i) * 0.25f - 1.0f;
  REQUIRE(w.write_scan(0, kTwoPoints, kTwoLabels, logits.data(), 2) == Status::Ok);
  REQUIRE(w.write_scan(1, kTwoPoints, kTwoLabels, logits.data(), 2) == Status::Ok);  // stays valid
  const fs::path file = fs::path(root) / "sequences/00/logits/000000.bin";
  const std::vector<char> good = read_bytes(file);
  REQUIRE(good.size() == 12 + logits.size() * 4);

  struct Case {
    const char* what;
    std::vector<char> bytes;
    Status expected;
  };
  std::vector<Case> cases;
  cases.push_back({"empty file", {}, Status::CorruptData});
  cases.push_back({"truncated header", std::vector<char>(good.begin(), good.begin() + 8), Status::CorruptData});
  cases.push_back({"header only", std::vector<char>(good.begin(), good.begin() + 12), Status::CorruptData});
  auto patched = [&](size_t at, char v) {
    std::vector<char> b = good;
    b[at] = v;
    return b;
  };
  cases.push_back({"bad magic", patched(3, 'X'), Status::CorruptData});
  cases.push_back({"version 2", patched(4, 2), Status::CorruptData});
  cases.push_back({"D = 18", patched(6, 18), Status::CorruptData});
  cases.push_back({"count = 3", patched(8, 3), Status::CorruptData});
  std::vector<char> short_payload = good;
  short_payload.pop_back();
  cases.push_back({"short payload", short_payload, Status::CorruptData});
  std::vector<char> long_payload = good;
  long_payload.push_back(0);
  cases.push_back({"trailing byte", long_payload, Status::CorruptData});
  std::vector<char> nan_logit = good;
  const float nan = std::nanf("");
  std::memcpy(nan_logit.data() + 12 + 4 * 5, &nan, 4);
  cases.push_back({"NaN logit", nan_logit, Status::InvalidInput});

  SemanticKittiSource src;
  OwnedScanBuffer buf(16, true);
  for (const Case& c : cases) {
    INFO(c.what);
    write_bytes(file, c.bytes.data(), c.bytes.size());
    REQUIRE(src.open(root, "00") == Status::Ok);
    buf.buffer().count = 99;
    CHECK(src.read(0, buf.buffer()) == c.expected);
    CHECK(buf.buffer().count == 0);
    CHECK_FALSE(buf.buffer().has_logits);
    REQUIRE(src.read(1, buf.buffer()) == Status::Ok);
    CHECK(buf.buffer().count == 2);
    CHECK(buf.buffer().has_logits);
  }
  // The same defects through the in-memory parser the fuzzer drives.
  for (const Case& c : cases) {
    INFO("parse_scan: " << c.what);
    const char dummy = 0;
    CHECK(parse_scan(kTwoPoints, sizeof(kTwoPoints), kTwoLabels, sizeof(kTwoLabels),
                     c.bytes.empty() ? &dummy : c.bytes.data(), c.bytes.size(), KittiReadOptions{},
                     buf.buffer()) == c.expected);
    CHECK(buf.buffer().count == 0);
  }
  // A NaN logit is a non-finite point: drop_non_finite removes that point only.
  write_bytes(file, nan_logit.data(), nan_logit.size());
  KittiReadOptions drop;
  drop.drop_non_finite = true;
  REQUIRE(src.open(root, "00", drop) == Status::Ok);
  REQUIRE(src.read(0, buf.buffer()) == Status::Ok);
  REQUIRE(buf.buffer().count == 1);
  CHECK(buf.buffer().labels[0] == 70u);
  CHECK(std::memcmp(buf.buffer().logits, logits.data() + kNumClasses, kNumClasses * 4) == 0);
}

TEST_CASE("drop_non_finite keeps points, labels and logits aligned; without it the scan is rejected") {
  const std::string root = fresh_dir("drop");
  SemanticKittiWriter w;
  REQUIRE(w.open(root, "00") == Status::Ok);
  const float inf = std::numeric_limits<float>::infinity();
  const float pts[20] = {1, 0, 0, 0.1f, std::nanf(""), 0, 0, 0.2f, 3, 0, 0, 0.3f, 4, 0, 0, inf, 5, 0, 0, 0.5f};
  const uint32_t labels[5] = {10, 20, 30, 40, 50};
  std::vector<float> logits(5 * kNumClasses);
  for (size_t i = 0; i < logits.size(); ++i) logits[i] = float(i);
  REQUIRE(w.write_scan(7, pts, labels, logits.data(), 5) == Status::Ok);
  OwnedScanBuffer buf(8, true);
  SemanticKittiSource strict;
  REQUIRE(strict.open(root, "00") == Status::Ok);
  CHECK(strict.read(0, buf.buffer()) == Status::InvalidInput);  // NaN coordinate and Inf intensity
  CHECK(buf.buffer().count == 0);
  KittiReadOptions opt;
  opt.drop_non_finite = true;
  SemanticKittiSource dropping;
  REQUIRE(dropping.open(root, "00", opt) == Status::Ok);
  REQUIRE(dropping.read(0, buf.buffer()) == Status::Ok);
  REQUIRE(buf.buffer().count == 3);
  const uint32_t kept[3] = {0, 2, 4};
  for (int k = 0; k < 3; ++k) {
    CHECK(buf.buffer().points[4 * k] == pts[4 * kept[k]]);
    CHECK(buf.buffer().points[4 * k + 3] == pts[4 * kept[k] + 3]);
    CHECK(buf.buffer().labels[k] == labels[kept[k]]);
    CHECK(buf.buffer().logits[size_t(k) * kNumClasses + 3] == logits[size_t(kept[k]) * kNumClasses + 3]);
  }
}

TEST_CASE("Logits are optional per frame and per buffer; labels optional when not required") {
  const std::string root = fresh_dir("optional");
  SemanticKittiWriter w;
  REQUIRE(w.open(root, "00") == Status::Ok);
  std::vector<float> logits(2 * kNumClasses, 0.5f);
  REQUIRE(w.write_scan(0, kTwoPoints, kTwoLabels, logits.data(), 2) == Status::Ok);
  REQUIRE(w.write_scan(1, kTwoPoints, kTwoLabels, nullptr, 2) == Status::Ok);  // no logits file
  fs::remove(fs::path(root) / "sequences/00/labels/000001.label");
  SemanticKittiSource src;
  REQUIRE(src.open(root, "00") == Status::Ok);
  REQUIRE(src.has_logits());
  OwnedScanBuffer with(4, true), without(4, false);
  REQUIRE(src.read(0, with.buffer()) == Status::Ok);
  CHECK(with.buffer().has_logits);
  CHECK(with.buffer().view().logit_dim == static_cast<uint32_t>(kNumClasses));
  REQUIRE(src.read(0, without.buffer()) == Status::Ok);  // buffer has no logit storage: ignored
  CHECK_FALSE(without.buffer().has_logits);
  CHECK(without.buffer().view().logits == nullptr);
  CHECK(src.read(1, with.buffer()) == Status::IoError);  // labels required by default
  KittiReadOptions lax;
  lax.require_labels = false;
  lax.load_logits = false;
  SemanticKittiSource unlabelled;
  REQUIRE(unlabelled.open(root, "00", lax) == Status::Ok);
  CHECK_FALSE(unlabelled.has_logits());
  with.buffer().labels[0] = 77;
  REQUIRE(unlabelled.read(1, with.buffer()) == Status::Ok);
  CHECK(with.buffer().count == 2);
  CHECK_FALSE(with.buffer().has_logits);
  CHECK(with.buffer().labels[0] == 0u);
  CHECK(with.buffer().labels[1] == 0u);
}

TEST_CASE("Poses: Tr^-1 P Tr with a non-identity Tr, 13-number lines, sparse frames, missing files") {
  const std::string root = fresh_dir("poses");
  SemanticKittiWriter w;
  REQUIRE(w.open(root, "00") == Status::Ok);
  for (uint32_t f : {0u, 2u, 5u}) REQUIRE(w.write_scan(f, kTwoPoints, kTwoLabels, nullptr, 2) == Status::Ok);
  const fs::path dir = fs::path(root) / "sequences/00";
  // Tr: velodyne -> camera as in KITTI (x_cam = -y_velo, y_cam = -z_velo, z_cam = x_velo), plus an offset.
  Eigen::Isometry3d tr = Eigen::Isometry3d::Identity();
  tr.linear() << 0, -1, 0, 0, 0, -1, 1, 0, 0;
  tr.translation() = Eigen::Vector3d(0.1, -0.2, 0.3);
  // Camera poses: frame 0 identity, frame 1 moves 2 m forward along camera z, frame 2 turns 90 deg about camera y.
  Eigen::Isometry3d cam[3];
  for (auto& c : cam) c.setIdentity();
  cam[1].translation() = Eigen::Vector3d(0, 0, 2);
  cam[2].linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix();
  cam[2].translation() = Eigen::Vector3d(1, 0, 4);
  std::ostringstream poses, calib;
  poses.precision(17);
  calib.precision(17);
  for (int i = 0; i < 3; ++i) {
    if (i == 1) poses << "0.1036 ";  // a leading timestamp (13 numbers) is skipped
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) poses << cam[i].matrix()(r, c) << ((r == 2 && c == 3) ? "\n" : " ");
  }
  calib << "P0: 1 0 0 0 0 1 0 0 0 0 1 0\nTr:";
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) calib << " " << tr.matrix()(r, c);
  calib << "\n";
  std::ofstream(dir / "poses.txt") << poses.str();
  std::ofstream(dir / "calib.txt") << calib.str();
  SemanticKittiSource src;
  REQUIRE(src.open(root, "00") == Status::Ok);
  REQUIRE(src.size() == 3);
  Eigen::Isometry3d p;
  REQUIRE(src.pose(0, &p) == Status::Ok);  // frame 0
  CHECK(p.isApprox(Eigen::Isometry3d::Identity(), 1e-12));
  REQUIRE(src.pose(1, &p) == Status::Ok);  // frame 2
  CHECK(p.isApprox(tr.inverse() * cam[2] * tr, 1e-12));
  CHECK(src.pose(2, &p) == Status::NotFound);  // frame 5 has no line
  // Known answer: 2 m along camera z is 2 m along velodyne x (forward), with no rotation.
  Eigen::Isometry3d p1;
  std::vector<Eigen::Isometry3d> direct;
  REQUIRE(parse_poses("1 0 0 0 0 1 0 0 0 0 1 2\n", tr, &direct) == Status::Ok);
  CHECK((direct[0].translation() - Eigen::Vector3d(2, 0, 0)).norm() < 1e-12);
  CHECK(direct[0].linear().isIdentity(1e-12));
  // Missing calib.txt -> identity; missing poses.txt -> open Ok, every pose NotFound.
  fs::remove(dir / "calib.txt");
  REQUIRE(src.open(root, "00") == Status::Ok);
  REQUIRE(src.pose(0, &p1) == Status::Ok);
  CHECK(p1.isApprox(Eigen::Isometry3d::Identity(), 1e-12));
  fs::remove(dir / "poses.txt");
  REQUIRE(src.open(root, "00") == Status::Ok);
  CHECK(src.size() == 3);
  CHECK(src.pose(0, &p1) == Status::NotFound);
  // Malformed Tr, and garbage poses: open fails and leaves an empty source.
  std::ofstream(dir / "calib.txt") << "Tr: 1 0 0 0 0 1 0 0 0 0 1\n";
  CHECK(src.open(root, "00") == Status::CorruptData);
  CHECK(src.size() == 0);
  fs::remove(dir / "calib.txt");
  for (const char* bad : {"1 0 0 0 0 1 0 0 0 0 1 zero\n", "1 0 0 0 0 1 0 0 0 0 1\n", "1 0 0 0 0 1 0 0 0 0 1 0 0 0\n",
                          "1 0 0 nan 0 1 0 0 0 0 1 0\n", "1 0 0 1e999 0 1 0 0 0 0 1 0\n"}) {
    INFO(bad);
    std::ofstream(dir / "poses.txt") << bad;
    CHECK(src.open(root, "00") == Status::CorruptData);
    CHECK(src.size() == 0);
    OwnedScanBuffer buf(4, false);
    CHECK(src.read(0, buf.buffer()) == Status::NotFound);
  }
}

TEST_CASE("Only six-digit frame names are frames; writer checks its arguments and round-trips poses exactly") {
  const std::string root = fresh_dir("names");
  SemanticKittiWriter unopened;
  CHECK(unopened.write_scan(0, kTwoPoints, kTwoLabels, nullptr, 2) == Status::NotInitialized);
  CHECK(unopened.write_poses({}) == Status::NotInitialized);
  SemanticKittiWriter w;
  REQUIRE(w.open(root, "00") == Status::Ok);
  CHECK(w.write_scan(1000000, kTwoPoints, kTwoLabels, nullptr, 2) == Status::InvalidInput);
  CHECK(w.write_scan(0, nullptr, kTwoLabels, nullptr, 2) == Status::InvalidInput);
  CHECK(w.write_scan(0, kTwoPoints, nullptr, nullptr, 2) == Status::InvalidInput);
  REQUIRE(w.write_scan(52, kTwoPoints, kTwoLabels, nullptr, 2) == Status::Ok);
  REQUIRE(w.write_scan(999999, kTwoPoints, kTwoLabels, nullptr, 2) == Status::Ok);
  REQUIRE(w.write_scan(3, nullptr, nullptr, nullptr, 0) == Status::Ok);  // an empty scan is a valid file
  const fs::path velo = fs::path(root) / "sequences/00/velodyne";
  for (const char* junk : {"zzzzzz.bin", "52.bin", "0000052.bin", "000052.bin.bak", "00005x.bin", "000052.BIN"})
    write_bytes(velo / junk, kTwoPoints, 16);
  fs::create_directories(velo / "000077.bin");  // a directory named like a frame: listed, unreadable
  SemanticKittiSource src;
  REQUIRE(src.open(root, "00") == Status::Ok);
  REQUIRE(src.size() == 4);
  CHECK(src.frame_id(0) == 3);
  CHECK(src.frame_id(1) == 52);
  CHECK(src.frame_id(2) == 77);
  CHECK(src.frame_id(3) == 999999);
  OwnedScanBuffer buf(4, false);
  REQUIRE(src.read(0, buf.buffer()) == Status::Ok);
  CHECK(buf.buffer().count == 0);
  CHECK(src.read(2, buf.buffer()) == Status::IoError);
  REQUIRE(src.read(3, buf.buffer()) == Status::Ok);
  CHECK(buf.buffer().count == 2);
  // Poses survive the text round trip bit for bit (%.17g).
  std::vector<Eigen::Isometry3d> poses(2, Eigen::Isometry3d::Identity());
  poses[1].linear() = Eigen::AngleAxisd(2.5, Eigen::Vector3d(-0.3, 0.9, 0.1).normalized()).toRotationMatrix();
  poses[1].translation() = Eigen::Vector3d(1.0 / 3.0, -123456.789012345, 1e-9);
  Eigen::Isometry3d bad = poses[1];
  bad.translation().x() = std::nan("");
  CHECK(w.write_poses({bad}) == Status::InvalidInput);
  REQUIRE(w.write_poses(poses) == Status::Ok);
  std::ifstream in(fs::path(root) / "sequences/00/poses.txt");
  std::stringstream ss;
  ss << in.rdbuf();
  std::vector<Eigen::Isometry3d> back;
  REQUIRE(parse_poses(ss.str(), Eigen::Isometry3d::Identity(), &back) == Status::Ok);
  REQUIRE(back.size() == 2);
  CHECK(back[1].matrix() == poses[1].matrix());
}

TEST_CASE("Missing sequence or velodyne folder is IoError") {
  const std::string root = fresh_dir("missing");
  SemanticKittiSource kitti;
  CHECK(kitti.open(root, "00") == Status::IoError);
  CHECK(kitti.size() == 0);
  NuScenesLidarsegSource nus;
  CHECK(nus.open(root, "0001") == Status::IoError);
  fs::create_directories(fs::path(root) / "sequences/0001/velodyne");
  CHECK(nus.open(root, "0001") == Status::IoError);  // no lidarseg/ while labels are required
  KittiReadOptions lax;
  lax.require_labels = false;
  CHECK(nus.open(root, "0001", lax) == Status::Ok);
  CHECK(nus.size() == 0);
}

TEST_CASE("nuScenes: mapping, ego drop, capacity after the drop, and every rejection path") {
  const std::string root = fresh_dir("nus");
  const fs::path dir = fs::path(root) / "sequences/x";
  fs::create_directories(dir / "velodyne");
  fs::create_directories(dir / "lidarseg");
  // 600 points (more than one read chunk): classes cycle 0..31, class 31 is the ego vehicle.
  const uint32_t n = 600;
  std::vector<float> pts(n * 4);
  std::vector<uint8_t> lab(n);
  for (uint32_t i = 0; i < n; ++i) {
    pts[4 * i] = 10.0f + float(i);
    pts[4 * i + 1] = -float(i);
    pts[4 * i + 2] = 0.5f;
    pts[4 * i + 3] = float(i % 256);
    lab[i] = static_cast<uint8_t>(i % 32);
  }
  auto put = [&](uint32_t frame, const std::vector<float>& p, const std::vector<uint8_t>& l) {
    char name[32];
    std::snprintf(name, sizeof(name), "%06u", frame);
    write_bytes(dir / "velodyne" / (std::string(name) + ".bin"), p.data(), p.size() * 4);
    write_bytes(dir / "lidarseg" / (std::string(name) + ".label"), l.data(), l.size());
  };
  put(0, pts, lab);
  std::vector<uint8_t> bad_class = lab;
  bad_class[599] = 32;
  put(1, pts, bad_class);
  put(2, pts, std::vector<uint8_t>(lab.begin(), lab.end() - 1));
  std::vector<float> nan_intensity = pts;
  nan_intensity[4 * 100 + 3] = std::nanf("");  // point 100: class 4 (pedestrian), not ego
  put(3, nan_intensity, lab);
  put(4, std::vector<float>(pts.begin(), pts.end() - 1), lab);
  write_bytes(dir / "velodyne" / "zzzzzz.bin", pts.data(), 16);
  std::ofstream(dir / "poses.txt") << "1 0 0 10 0 1 0 20 0 0 1 30\n";

  NuScenesLidarsegSource src;
  REQUIRE(src.open(root, "x") == Status::Ok);
  REQUIRE(src.size() == 5);  // zzzzzz.bin is not a frame
  const uint32_t ego = static_cast<uint32_t>(std::count(lab.begin(), lab.end(), uint8_t(31)));
  REQUIRE(ego == 18);
  OwnedScanBuffer buf(n - ego, false);  // exactly the points left after the ego drop
  REQUIRE(src.read(0, buf.buffer()) == Status::Ok);
  REQUIRE(buf.buffer().count == n - ego);
  uint32_t k = 0;
  for (uint32_t i = 0; i < n; ++i) {
    if (lab[i] == 31) continue;
    REQUIRE(buf.buffer().points[4 * k] == pts[4 * i]);
    REQUIRE(buf.buffer().labels[k] == nuscenes_to_kitti(lab[i]));
    ++k;
  }
  Eigen::Isometry3d p;
  REQUIRE(src.pose(0, &p) == Status::Ok);
  CHECK(p.translation() == Eigen::Vector3d(10, 20, 30));
  CHECK(src.pose(1, &p) == Status::NotFound);
  OwnedScanBuffer small(n - ego - 1, false);
  CHECK(src.read(0, small.buffer()) == Status::CapacityExceeded);
  CHECK(small.buffer().count == 0);
  CHECK(src.read(1, buf.buffer()) == Status::CorruptData);  // class 32, in the last chunk
  CHECK(buf.buffer().count == 0);
  CHECK(src.read(2, buf.buffer()) == Status::CorruptData);   // one label short
  CHECK(src.read(3, buf.buffer()) == Status::InvalidInput);  // NaN intensity
  CHECK(buf.buffer().count == 0);
  CHECK(src.read(4, buf.buffer()) == Status::CorruptData);  // .bin not a multiple of 16
  CHECK(src.read(5, buf.buffer()) == Status::NotFound);
  REQUIRE(src.read(0, buf.buffer()) == Status::Ok);  // still usable
  CHECK(buf.buffer().count == n - ego);
  KittiReadOptions drop;
  drop.drop_non_finite = true;
  NuScenesLidarsegSource dropping;
  REQUIRE(dropping.open(root, "x", drop) == Status::Ok);
  REQUIRE(dropping.read(3, buf.buffer()) == Status::Ok);
  REQUIRE(buf.buffer().count == n - ego - 1);
  k = 0;
  for (uint32_t i = 0; i < n; ++i) {  // point 100 gone, the rest in order
    if (lab[i] == 31 || i == 100) continue;
    REQUIRE(buf.buffer().points[4 * k] == pts[4 * i]);
    ++k;
  }
  // Mapping spot checks against the data README.
  CHECK(nuscenes_to_kitti(9) == 51);
  CHECK(nuscenes_to_kitti(24) == 40);
  CHECK(nuscenes_to_kitti(28) == 50);
  CHECK(nuscenes_to_kitti(31) == 0);
  for (int c = 0; c <= 31; ++c) CHECK(class_from_kitti(nuscenes_to_kitti(uint8_t(c))) != kUnknownClass);
}

TEST_CASE("Real SemanticKITTI: every revisit and negative pair's T_gt, every label a known class", "[real-data]") {
  const std::string root = std::string(GSF_DATA_DIR) + "/semantickitti-samples";
  GSF_SKIP_UNLESS(fs::exists(root), "no real data at " + root);
  const std::vector<Pair> pairs = read_pairs(root + "/revisit_pairs.txt");
  REQUIRE(pairs.size() >= 3);
  int revisits = 0;
  for (const Pair& pr : pairs) {
    INFO(pr.seq << " " << pr.a << " " << pr.b << " " << pr.kind);
    SemanticKittiSource src;
    REQUIRE(src.open(root, pr.seq) == Status::Ok);
    Eigen::Isometry3d pa, pb;
    REQUIRE(pose_of_frame(src, pr.a, &pa));
    REQUIRE(pose_of_frame(src, pr.b, &pb));
    CHECK(((pa.inverse() * pb).matrix() - pr.t_gt.matrix()).cwiseAbs().maxCoeff() < 1e-3);
    revisits += pr.kind == "revisit";
  }
  CHECK(revisits == 2);
  OwnedScanBuffer buf(130000, false);
  uint64_t points = 0, unknown = 0;
  for (const char* seq : {"00", "07", "08"}) {
    SemanticKittiSource src;
    REQUIRE(src.open(root, seq) == Status::Ok);
    for (uint32_t i = 0; i < src.size(); ++i) {
      REQUIRE(src.read(i, buf.buffer()) == Status::Ok);
      for (uint32_t k = 0; k < buf.buffer().count; ++k)
        unknown += class_from_kitti(buf.buffer().labels[k]) == kUnknownClass;
      points += buf.buffer().count;
    }
  }
  CHECK(unknown == 0);
  CHECK(points == 1232087u);  // sum of the ten sample scans
}

TEST_CASE("Real nuScenes: every pair's T_gt, ego points gone (count = raw - class 31, nothing within 1 m)",
          "[real-data]") {
  const std::string root = std::string(GSF_DATA_DIR) + "/nuscenes-lidarseg-samples";
  GSF_SKIP_UNLESS(fs::exists(root), "no real data at " + root);
  const std::vector<Pair> pairs = read_pairs(root + "/revisit_pairs.txt");
  REQUIRE(!pairs.empty());
  for (const Pair& pr : pairs) {
    INFO(pr.seq << " " << pr.a << " " << pr.b << " " << pr.kind);
    const size_t slash = pr.seq.find('/');
    REQUIRE(slash != std::string::npos);
    NuScenesLidarsegSource a, b;
    REQUIRE(a.open(root, pr.seq.substr(0, slash)) == Status::Ok);
    REQUIRE(b.open(root, pr.seq.substr(slash + 1)) == Status::Ok);
    Eigen::Isometry3d pa, pb;
    REQUIRE(pose_of_frame(a, pr.a, &pa));
    REQUIRE(pose_of_frame(b, pr.b, &pb));
    CHECK(((pa.inverse() * pb).matrix() - pr.t_gt.matrix()).cwiseAbs().maxCoeff() < 1e-3);
  }
  NuScenesLidarsegSource src;
  REQUIRE(src.open(root, "0002") == Status::Ok);
  OwnedScanBuffer buf(40000, false);
  double min_range = 1e9;
  for (uint32_t i = 0; i < src.size(); ++i) {
    REQUIRE(src.read(i, buf.buffer()) == Status::Ok);
    for (uint32_t k = 0; k < buf.buffer().count; ++k) {
      const float* q = buf.buffer().points + 4 * size_t(k);
      min_range = std::min(min_range, std::sqrt(double(q[0]) * q[0] + double(q[1]) * q[1] + double(q[2]) * q[2]));
    }
  }
  CHECK(min_range > 1.0);  // measured 1.21 m; the ego returns reach out to ~2.1 m
  char name[64];
  std::snprintf(name, sizeof(name), "/sequences/0002/lidarseg/%06u.label", src.frame_id(0));
  const std::vector<char> raw = read_bytes(root + name);
  const size_t ego = static_cast<size_t>(std::count(raw.begin(), raw.end(), char(31)));
  REQUIRE(src.read(0, buf.buffer()) == Status::Ok);
  CHECK(ego > 1000);
  CHECK(buf.buffer().count == raw.size() - ego);
}

namespace {
struct CaptureSink final : LogSink {
  std::string last;
  LogLevel level = LogLevel::Debug;
  void write(LogLevel l, const char* m) override {
    level = l;
    last = m;
  }
};

// Runs `fn` with stderr redirected to a file and returns what was written.
template <class Fn>
std::string capture_stderr(Fn fn) {
  const std::string path = std::string(GSF_TEST_TMP_DIR) + "/port_hardening_stderr.txt";
  std::fflush(stderr);
  const int saved = ::dup(2);
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  ::dup2(fd, 2);
  ::close(fd);
  fn();
  std::fflush(stderr);
  ::dup2(saved, 2);
  ::close(saved);
  const std::vector<char> bytes = read_bytes(path);
  return std::string(bytes.begin(), bytes.end());
}
}  // namespace

TEST_CASE("logf formats into a fixed buffer and marks truncation; StderrLogSink filters by level") {
  CaptureSink sink;
  logf(sink, LogLevel::Warn, "scan %u: %d points, %.2f m", 52u, -3, 1.005);
  CHECK(sink.last == "scan 52: -3 points, 1.00 m");
  CHECK(sink.level == LogLevel::Warn);
  const std::string fits(511, 'a');
  logf(sink, LogLevel::Info, "%s", fits.c_str());
  CHECK(sink.last == fits);
  const std::string big(2000, 'b');
  logf(sink, LogLevel::Info, "%s", big.c_str());
  CHECK(sink.last.size() == 511);
  CHECK(sink.last.substr(508) == "...");
  CHECK(sink.last.substr(0, 508) == big.substr(0, 508));
  const std::string out = capture_stderr([] {
    StderrLogSink warn_and_up(LogLevel::Warn);
    logf(warn_and_up, LogLevel::Debug, "hidden-debug");
    logf(warn_and_up, LogLevel::Info, "hidden-info");
    logf(warn_and_up, LogLevel::Warn, "shown-%d", 1);
    logf(warn_and_up, LogLevel::Error, "shown-%d", 2);
  });
  CHECK(out.find("hidden") == std::string::npos);
  CHECK(out.find("shown-1") != std::string::npos);
  CHECK(out.find("shown-2") != std::string::npos);
  CHECK(out.find("warn") != std::string::npos);
  CHECK(out.find("error") != std::string::npos);
}

TEST_CASE("Logit model: per-class agreement at 1 - p, partners only, order independent, flat for ignored") {
  const uint32_t ids[] = {10, 11, 15, 18, 20, 30, 31, 32, 40, 44, 48, 49, 50, 51, 70, 71, 72, 80, 81};
  const uint32_t n = 6000;  // binomial sd of the agreement rate <= 0.0065
  std::vector<uint32_t> labels(n), relabel(n);
  std::vector<float> logits(size_t(n) * kNumClasses);
  LogitModel model;
  for (uint32_t id : ids) {
    const int c = class_from_kitti(id);
    REQUIRE(c >= 0);
    INFO("kitti id " << id << " dense " << c);
    std::fill(labels.begin(), labels.end(), id | (5u << 16));
    synthesize_logits(model, 100 + id, labels.data(), n, logits.data(), relabel.data());
    uint32_t agree = 0, foreign = 0;
    for (uint32_t i = 0; i < n; ++i) {
      CHECK((relabel[i] >> 16) == 5u);  // instance bits kept
      const int pred = class_from_kitti(relabel[i] & 0xFFFFu);
      int best = 0;
      for (int k = 1; k < kNumClasses; ++k)
        if (logits[size_t(i) * kNumClasses + k] > logits[size_t(i) * kNumClasses + best]) best = k;
      REQUIRE(pred == best);  // relabel is the argmax
      if (pred == c) {
        ++agree;
        continue;
      }
      bool partner = false;
      for (int k = 0; k < confusion_partner_count(c); ++k) partner = partner || confusion_partner(c, k) == pred;
      foreign += !partner;
    }
    CHECK(foreign == 0);
    CHECK(agree / double(n) == Approx(1.0 - confusion_probability(c)).margin(0.016));  // ~4 sd
  }
  // Every documented confusion pair from the brief exists.
  auto confuses = [](int a, int b) {
    for (int k = 0; k < confusion_partner_count(a); ++k)
      if (confusion_partner(a, k) == b) return true;
    return false;
  };
  CHECK(confuses(kVegetation, kTerrain));
  CHECK(confuses(kTerrain, kVegetation));
  CHECK(confuses(kPole, kTrunk));
  CHECK(confuses(kTrunk, kPole));
  CHECK(confuses(kPole, kTrafficSign));
  CHECK(confuses(kTrafficSign, kPole));
  CHECK(confuses(kCar, kTruck));
  CHECK(confuses(kCar, kOtherVehicle));
  CHECK(confuses(kRoad, kParking));
  CHECK(confuses(kParking, kRoad));
  CHECK(confuses(kSidewalk, kTerrain));
  CHECK(confuses(kSidewalk, kParking));
  CHECK(confuses(kBuilding, kFence));
  CHECK(confuses(kFence, kBuilding));
  // confusion_scale 0: argmax is always the label; 2: twice the confusion rate.
  std::fill(labels.begin(), labels.end(), 80u);
  LogitModel none = model;
  none.confusion_scale = 0.0f;
  synthesize_logits(none, 1, labels.data(), n, logits.data(), relabel.data());
  CHECK(std::count(relabel.begin(), relabel.end(), 80u) == std::ptrdiff_t(n));
  LogitModel twice = model;
  twice.confusion_scale = 2.0f;
  synthesize_logits(twice, 1, labels.data(), n, logits.data(), relabel.data());
  CHECK(1.0 - std::count(relabel.begin(), relabel.end(), 80u) / double(n) ==
        Approx(2.0 * confusion_probability(kPole)).margin(0.025));
  // Order independence: scan 7 then 8 gives the same as 8 then 7.
  std::vector<uint32_t> mixed(n);
  for (uint32_t i = 0; i < n; ++i) mixed[i] = ids[i % 19];
  std::vector<float> a7(logits.size()), a8(logits.size()), b7(logits.size()), b8(logits.size());
  synthesize_logits(model, 7, mixed.data(), n, a7.data(), nullptr);
  synthesize_logits(model, 8, mixed.data(), n, a8.data(), nullptr);
  synthesize_logits(model, 8, mixed.data(), n, b8.data(), nullptr);
  synthesize_logits(model, 7, mixed.data(), n, b7.data(), nullptr);
  CHECK(a7 == b7);
  CHECK(a8 == b8);
  CHECK(a7 != a8);
  // Ignored (0, 1, 52, 99) and unknown ids: noise only, label passed through.
  const uint32_t ignored[] = {0, 1, 52, 99, 1234, 65535};
  for (uint32_t id : ignored) {
    std::fill(labels.begin(), labels.end(), id);
    synthesize_logits(model, 3, labels.data(), n, logits.data(), relabel.data());
    CHECK(std::count(relabel.begin(), relabel.end(), id) == std::ptrdiff_t(n));
    const float max_logit = *std::max_element(logits.begin(), logits.end());
    CHECK(max_logit < 6.0f * model.noise_sigma);  // no margin anywhere: 114,000 draws stay below 6 sigma
    CHECK(max_logit > 3.0f * model.noise_sigma);  // ... but it is noise, not zeros
    double sum = 0;
    for (float v : logits) sum += v;
    CHECK(std::fabs(sum / double(logits.size())) < 0.01);
  }
}

}  // namespace test_port_hardening
