// The firmware-facing half of the port layer does not touch the heap after open(): ScanSource::read
// (success and every error path), logf, and logit synthesis. open() itself may allocate.
#include <catch2/catch.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "alloc_counter.h"
#include "gsf/port/log.h"
#include "gsf/port/logit_synthesis.h"
#include "gsf/port/nuscenes.h"
#include "gsf/port/semantic_kitti.h"
#include "skip.h"

using namespace gsf;
using namespace gsf::port;
using gsf_test::AllocationScope;
namespace fs = std::filesystem;

namespace {
struct FixedSink final : LogSink {
  char last[600] = {};
  void write(LogLevel, const char* m) override { std::snprintf(last, sizeof(last), "%s", m); }
};
}  // namespace

TEST_CASE("SemanticKittiSource::read allocates nothing, on success and on every error") {
  const std::string root = std::string(GSF_TEST_TMP_DIR) + "/port_noheap_kitti";
  fs::remove_all(root);
  SemanticKittiWriter w;
  REQUIRE(w.open(root, "00") == Status::Ok);
  std::vector<float> pts(300 * 4);
  std::vector<uint32_t> labels(300, 40);
  std::vector<float> logits(300 * kNumClasses, 0.25f);
  for (size_t i = 0; i < pts.size(); ++i) pts[i] = float(i);
  REQUIRE(w.write_scan(0, pts.data(), labels.data(), logits.data(), 300) == Status::Ok);
  REQUIRE(w.write_scan(1, pts.data(), labels.data(), logits.data(), 300) == Status::Ok);
  REQUIRE(w.write_scan(2, pts.data(), labels.data(), logits.data(), 300) == Status::Ok);
  const fs::path dir = fs::path(root) / "sequences/00";
  std::ofstream(dir / "logits/000001.bin", std::ios::trunc) << "GSFL";  // truncated header
  fs::remove(dir / "labels/000002.label");
  SemanticKittiSource src;
  REQUIRE(src.open(root, "00") == Status::Ok);
  OwnedScanBuffer buf(400, true), tiny(10, true);
  Status s[5];
  uint32_t count0 = 0;
  {
    AllocationScope scope;
    s[0] = src.read(0, buf.buffer());
    count0 = buf.buffer().count;
    s[1] = src.read(1, buf.buffer());
    s[2] = src.read(2, buf.buffer());
    s[3] = src.read(0, tiny.buffer());
    s[4] = src.read(9, buf.buffer());
    CHECK(scope.allocations() == 0);
  }
  CHECK(s[0] == Status::Ok);
  CHECK(count0 == 300);
  CHECK(s[1] == Status::CorruptData);
  CHECK(s[2] == Status::IoError);
  CHECK(s[3] == Status::CapacityExceeded);
  CHECK(s[4] == Status::NotFound);
}

TEST_CASE("SemanticKittiSource::read of a real scan allocates nothing", "[real-data]") {
  const std::string real = std::string(GSF_DATA_DIR) + "/semantickitti-samples";
  GSF_SKIP_UNLESS(fs::exists(real), "no real data at " + real);
  SemanticKittiSource r;
  REQUIRE(r.open(real, "08") == Status::Ok);
  OwnedScanBuffer big(130000, false);
  AllocationScope scope;
  const Status st = r.read(0, big.buffer());
  const uint64_t allocations = scope.allocations();
  CHECK(st == Status::Ok);
  CHECK(allocations == 0);
}

TEST_CASE("NuScenesLidarsegSource::read allocates nothing", "[real-data]") {
  const std::string root = std::string(GSF_DATA_DIR) + "/nuscenes-lidarseg-samples";
  GSF_SKIP_UNLESS(fs::exists(root), "no real data at " + root);
  NuScenesLidarsegSource src;
  REQUIRE(src.open(root, "0004") == Status::Ok);
  OwnedScanBuffer buf(40000, false), tiny(100, false);
  Status ok, small, past;
  {
    AllocationScope scope;
    ok = src.read(3, buf.buffer());
    small = src.read(3, tiny.buffer());
    past = src.read(40, buf.buffer());
    CHECK(scope.allocations() == 0);
  }
  CHECK(ok == Status::Ok);
  CHECK(small == Status::CapacityExceeded);
  CHECK(past == Status::NotFound);
}

TEST_CASE("logf and synthesize_logits allocate nothing") {
  FixedSink sink;
  const std::string big(1000, 'z');
  std::vector<uint32_t> labels(1000, 70), relabel(1000);
  std::vector<float> logits(1000 * kNumClasses);
  {
    AllocationScope scope;
    logf(sink, LogLevel::Info, "%s %d %.3f", big.c_str(), 7, 2.5);
    synthesize_logits(LogitModel{}, 3, labels.data(), 1000, logits.data(), relabel.data());
    CHECK(scope.allocations() == 0);
  }
  CHECK(std::string(sink.last).size() == 511);
}
