// Two Localizers, each with its own workspace, share one loaded MapView (and the same scans) read-only
// on two threads; every result equals the single-threaded one bit for bit. Run under ThreadSanitizer by
// the tsan preset (scripts/test.sh), where any unsynchronised write to shared state is reported.
#include <catch2/catch.hpp>

#include <cstring>
#include <thread>
#include <vector>

#include "gsf/gsf.h"
#include "gsf/localizer.h"
#include "tiny_world.h"

using namespace gsf;
using gsf_test::tiny_world;

namespace {

struct Workspace {
  std::vector<uint64_t> words;  // 16-byte aligned (operator new), as the C API wants
  explicit Workspace(size_t bytes) : words(bytes / 8 + 2) {}
  void* data() { return words.data(); }
  size_t bytes() const { return words.size() * 8; }
};

bool bits_equal(double a, double b) { return std::memcmp(&a, &b, sizeof(double)) == 0; }

bool same(const LocalizeResult& a, const LocalizeResult& b) {
  return a.status == b.status && std::memcmp(a.map_T_scan.data(), b.map_T_scan.data(), sizeof(double) * 16) == 0 &&
         a.inliers == b.inliers && a.clique_size == b.clique_size && bits_equal(a.score, b.score) &&
         bits_equal(a.confidence, b.confidence) && a.query_instances == b.query_instances &&
         a.query_triangles == b.query_triangles && a.triangle_matches == b.triangle_matches &&
         a.gsf_survivors == b.gsf_survivors && a.correspondences == b.correspondences &&
         a.clique_nodes == b.clique_nodes && a.field_probes == b.field_probes &&
         a.field_comparisons == b.field_comparisons && a.refined == b.refined &&
         a.budget_exhausted == b.budget_exhausted && a.capacity_truncated == b.capacity_truncated;
}

// Query order per thread: forward on one, backward on the other, so the two work on different scans
// and different map regions at the same moment (and on the same ones in the middle).
std::vector<size_t> order(size_t n, bool reverse) {
  std::vector<size_t> o(n);
  for (size_t i = 0; i < n; ++i) o[i] = reverse ? n - 1 - i : i;
  return o;
}

}  // namespace

TEST_CASE("Two localizers on two threads share one map and give the single-threaded results bit for bit") {
  const auto& w = tiny_world();
  const size_t n = w.queries.size();
  REQUIRE(n >= 20);
  std::vector<LocalizeResult> reference(n);
  {
    Workspace ws(Localizer::required_bytes(w.config));
    Localizer solo;
    REQUIRE(solo.init(w.config, w.map, ws.data(), ws.bytes()) == Status::Ok);
    for (size_t k = 0; k < n; ++k) solo.localize(w.queries[k].view(), &reference[k]);
  }

  Workspace wa(Localizer::required_bytes(w.config)), wb(Localizer::required_bytes(w.config));
  Localizer la, lb;
  REQUIRE(la.init(w.config, w.map, wa.data(), wa.bytes()) == Status::Ok);
  REQUIRE(lb.init(w.config, w.map, wb.data(), wb.bytes()) == Status::Ok);
  std::vector<LocalizeResult> ra(n), rb(n);
  auto run = [&](Localizer* loc, std::vector<LocalizeResult>* out, bool reverse) {
    for (size_t k : order(n, reverse)) loc->localize(w.queries[k].view(), &(*out)[k]);
  };
  std::thread ta(run, &la, &ra, false);
  std::thread tb(run, &lb, &rb, true);
  ta.join();
  tb.join();

  int ok = 0;
  for (size_t k = 0; k < n; ++k) {
    INFO("query " << k);
    CHECK(same(ra[k], reference[k]));
    CHECK(same(rb[k], reference[k]));
    ok += reference[k].status == Status::Ok;
  }
  CHECK(ok * 10 >= static_cast<int>(n) * 6);  // the calls did real work
}

// The C layer adds no shared state of its own; every third query keeps the tsan run short.
TEST_CASE("The C API: two handles over one gsf_map on two threads match the single-threaded results") {
  const auto& w = tiny_world();
  std::vector<size_t> subset;
  for (size_t k = 0; k < w.queries.size(); k += 3) subset.push_back(k);
  const size_t n = subset.size();
  gsf_map map;
  REQUIRE(gsf_map_load(w.blob.data(), w.bytes, &map) == GSF_STATUS_OK);
  gsf_config cfg;
  gsf_config_default(&cfg);
  const size_t wbytes = gsf_workspace_bytes(&cfg), sbytes = gsf_localizer_storage_bytes();
  Workspace s0(sbytes), s1(sbytes), s2(sbytes), w0(wbytes), w1(wbytes), w2(wbytes);
  gsf_localizer *solo = nullptr, *a = nullptr, *b = nullptr;
  REQUIRE(gsf_localizer_init(s0.data(), sbytes, &cfg, &map, w0.data(), wbytes, &solo) == GSF_STATUS_OK);
  REQUIRE(gsf_localizer_init(s1.data(), sbytes, &cfg, &map, w1.data(), wbytes, &a) == GSF_STATUS_OK);
  REQUIRE(gsf_localizer_init(s2.data(), sbytes, &cfg, &map, w2.data(), wbytes, &b) == GSF_STATUS_OK);
  auto localize = [&](gsf_localizer* loc, size_t i, gsf_result* r) {
    const gsf_test::QueryScan& q = w.queries[subset[i]];
    gsf_localize(loc, q.xyzi.data(), 4, static_cast<uint32_t>(q.labels.size()), q.labels.data(), q.logits.data(),
                 GSF_NUM_CLASSES, r);
  };
  std::vector<gsf_result> reference(n), ra(n), rb(n);
  for (size_t i = 0; i < n; ++i) localize(solo, i, &reference[i]);
  auto run = [&](gsf_localizer* loc, std::vector<gsf_result>* out, bool reverse) {
    for (size_t i : order(n, reverse)) localize(loc, i, &(*out)[i]);
  };
  std::thread ta(run, a, &ra, false);
  std::thread tb(run, b, &rb, true);
  ta.join();
  tb.join();
  int ok = 0;
  for (size_t i = 0; i < n; ++i) {
    INFO("query " << subset[i]);
    CHECK(std::memcmp(&ra[i], &reference[i], sizeof(gsf_result)) == 0);  // no padding: whole struct
    CHECK(std::memcmp(&rb[i], &reference[i], sizeof(gsf_result)) == 0);
    ok += reference[i].status == GSF_STATUS_OK;
  }
  CHECK(ok * 10 >= static_cast<int>(n) * 6);
}
