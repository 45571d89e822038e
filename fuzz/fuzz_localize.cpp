// Fuzz a whole localize() against a small fixed map (the simulator's tiny world, built once): the
// input bytes become a scan (x, y, z, intensity floats and label words, optionally logits). Any scan
// must give a status without crashing, and the localizer must stay usable: a known-good query is
// localized again after every fuzzed one.
#include <cstdint>
#include <cstring>
#include <vector>

#include "gsf/localizer.h"
#include "tiny_world.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const gsf_test::TinyWorld& world = gsf_test::tiny_world();
  static std::vector<uint64_t> ws(gsf::Localizer::required_bytes(world.config) / 8 + 2);
  static gsf::Localizer loc;
  static gsf::Status init = loc.init(world.config, world.map, ws.data(), ws.size() * 8);
  static gsf::LocalizeResult reference;
  static gsf::Status ref_status = loc.localize(world.queries[0].view(), &reference);
  if (init != gsf::Status::Ok) __builtin_trap();
  if (size < 2) return 0;
  const bool with_logits = data[0] & 1;
  loc.set_use_gsf(data[0] & 2);
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
  loc.localize(v, &r);
  loc.set_use_gsf(true);
  gsf::LocalizeResult again;
  const gsf::Status s = loc.localize(world.queries[0].view(), &again);
  if (s != ref_status || std::memcmp(again.map_T_scan.data(), reference.map_T_scan.data(), sizeof(double) * 16) != 0)
    __builtin_trap();  // state leaked from the fuzzed scan into the next one
  return 0;
}
