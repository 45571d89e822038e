// Fuzz a whole localize() against a small fixed map (the simulator's tiny world, built once): the
// input bytes become a scan (x, y, z, intensity floats and label words, optionally logits). Any scan
// must give a status without crashing, and the localizer must stay usable: a known-good query is
// localized again after every fuzzed one.
#include <cstdint>
#include <cstring>
#include <vector>

#include "gsf/localizer.h"
#include "tiny_world.h"

namespace {
const gsf_test::TinyWorld* g_world = nullptr;
std::vector<uint64_t> g_workspace, g_workspace_off;
gsf::Localizer g_loc, g_loc_off;  // GSF on (the world's config) and off (instance-only)
gsf::LocalizeResult g_reference;
gsf::Status g_ref_status = gsf::Status::NotInitialized;
}  // namespace

// Building the world and its map takes seconds under the sanitizers: do it once here, before fuzzing
// starts, so it never counts against libFuzzer's per-input timeout.
extern "C" int LLVMFuzzerInitialize(int*, char***) {
  g_world = &gsf_test::tiny_world();
  g_workspace.assign(gsf::Localizer::required_bytes(g_world->config) / 8 + 2, 0);
  if (g_loc.init(g_world->config, g_world->map, g_workspace.data(), g_workspace.size() * 8) != gsf::Status::Ok)
    __builtin_trap();
  gsf::LocalizerConfig off = g_world->config;
  off.gsf.enabled = false;
  g_workspace_off.assign(gsf::Localizer::required_bytes(off) / 8 + 2, 0);
  if (g_loc_off.init(off, g_world->map, g_workspace_off.data(), g_workspace_off.size() * 8) != gsf::Status::Ok)
    __builtin_trap();
  g_ref_status = g_loc.localize(g_world->queries[0].view(), &g_reference);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const gsf_test::TinyWorld& world = *g_world;
  gsf::Localizer& loc = g_loc;  // the GSF-on localizer must stay usable after any scan
  const gsf::LocalizeResult& reference = g_reference;
  const gsf::Status ref_status = g_ref_status;
  if (size < 2) return 0;
  const bool with_logits = data[0] & 1;
  const size_t per_point = 16 + 4 + (with_logits ? gsf::kNumClasses * 4 : 0);
  const size_t n = (size - 1) / per_point;
  std::vector<float> pts(n * 4), logits(with_logits ? n * gsf::kNumClasses : 0);
  std::vector<uint32_t> labels(n);
  const uint8_t* p = data + 1;
  for (size_t i = 0; i < n; ++i, p += per_point) {
    std::memcpy(&pts[4 * i], p, 16);
    std::memcpy(&labels[i], p + 16, 4);
    if (with_logits) std::memcpy(&logits[i * gsf::kNumClasses], p + 20, gsf::kNumClasses * 4);
  }
  gsf::ScanView v;
  v.points = pts.data();
  v.labels = labels.data();
  v.logits = with_logits ? logits.data() : nullptr;
  v.logit_dim = with_logits ? gsf::kNumClasses : 0;
  v.count = static_cast<uint32_t>(n);
  gsf::LocalizeResult r;
  ((data[0] & 2) ? g_loc : g_loc_off).localize(v, &r);
  gsf::LocalizeResult again;
  const gsf::Status s = loc.localize(world.queries[0].view(), &again);
  if (s != ref_status || std::memcmp(again.map_T_scan.data(), reference.map_T_scan.data(), sizeof(double) * 16) != 0)
    __builtin_trap();  // state leaked from the fuzzed scan into the next one
  return 0;
}
