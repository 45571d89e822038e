// Fuzz the vehicle modes against the simulator's tiny world (docs/vehicle-modes.md): a position prior,
// a predicted pose for track() and the odometry of localize_sequence() come from the input bytes (any
// doubles and floats: NaN, Inf, huge, a rotation that is not one), applied either to a known-good query
// scan or to a fuzzed scan. Every call must return a status without crashing; a non-finite prior,
// prediction or odometry must be refused (InvalidArgument); and the localizer must stay usable: after
// every input a known-good query is localized one-shot again, bit for bit as before fuzzing.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "gsf/localizer.h"
#include "tiny_world.h"

namespace {

const gsf_test::TinyWorld* g_world = nullptr;
std::vector<uint64_t> g_workspace;
gsf::Localizer g_loc;
gsf::LocalizeResult g_reference;
gsf::Status g_ref_status = gsf::Status::NotInitialized;

// The input's head: which mode, which scan, and the mode's argument.
struct Head {
  uint8_t flags = 0;  // bits 0-1: mode (0 prior, 1 track, 2 sequence, 3 sequence after a reset); bit 2: fuzzed scan
  double pose[12] = {};
  double prior_xy[2] = {};
  float prior_f[3] = {};  // radius, heading, tolerance
  uint8_t has_heading = 0;
};
constexpr size_t kHeadBytes = 1 + sizeof(double) * 14 + sizeof(float) * 3 + 1;

bool all_finite(const double* v, int n) {
  for (int i = 0; i < n; ++i)
    if (!std::isfinite(v[i])) return false;
  return true;
}

Eigen::Isometry3d pose_from(const double rows[12]) {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 4; ++col) pose.matrix()(row, col) = rows[row * 4 + col];
  return pose;
}

// The rest of the input as a scan (x, y, z, intensity and a label word per point, no logits).
gsf::ScanView fuzzed_scan(const uint8_t* p, size_t size, std::vector<float>* pts, std::vector<uint32_t>* labels) {
  const size_t n = size / 20;
  pts->resize(n * 4);
  labels->resize(n);
  for (size_t i = 0; i < n; ++i, p += 20) {
    std::memcpy(&(*pts)[4 * i], p, 16);
    std::memcpy(&(*labels)[i], p + 16, 4);
  }
  gsf::ScanView v;
  v.points = pts->data();
  v.labels = labels->data();
  v.count = static_cast<uint32_t>(n);
  return v;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  g_world = &gsf_test::tiny_world();
  g_workspace.assign(gsf::Localizer::required_bytes(g_world->config) / 8 + 2, 0);
  if (g_loc.init(g_world->config, g_world->map, g_workspace.data(), g_workspace.size() * 8) != gsf::Status::Ok)
    __builtin_trap();
  g_ref_status = g_loc.localize(g_world->queries[0].view(), &g_reference);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < kHeadBytes) return 0;
  Head h;
  const uint8_t* p = data;
  h.flags = *p++;
  std::memcpy(h.pose, p, sizeof(h.pose));
  p += sizeof(h.pose);
  std::memcpy(h.prior_xy, p, sizeof(h.prior_xy));
  p += sizeof(h.prior_xy);
  std::memcpy(h.prior_f, p, sizeof(h.prior_f));
  p += sizeof(h.prior_f);
  h.has_heading = *p++;
  std::vector<float> pts;
  std::vector<uint32_t> labels;
  const gsf::ScanView scan = (h.flags & 4) ? fuzzed_scan(p, size - kHeadBytes, &pts, &labels)
                                           : g_world->queries[h.has_heading % g_world->queries.size()].view();
  gsf::LocalizeResult r;
  gsf::Status s = gsf::Status::Ok;
  bool finite = all_finite(h.pose, 12);
  switch (h.flags & 3) {
    case 0: {
      gsf::PositionPrior prior;
      prior.x = h.prior_xy[0];
      prior.y = h.prior_xy[1];
      prior.radius_m = h.prior_f[0];
      prior.has_heading = h.has_heading & 1;
      prior.heading_deg = h.prior_f[1];
      prior.heading_tolerance_deg = h.prior_f[2];
      finite = all_finite(h.prior_xy, 2) && std::isfinite(h.prior_f[0]) &&
               (!prior.has_heading || (std::isfinite(h.prior_f[1]) && std::isfinite(h.prior_f[2])));
      s = g_loc.localize(scan, prior, &r);
      break;
    }
    case 1: s = g_loc.track(scan, pose_from(h.pose), &r); break;
    default:
      if ((h.flags & 3) == 3) g_loc.reset_sequence();
      s = g_loc.localize_sequence(scan, pose_from(h.pose), &r);
      break;
  }
  if (s != r.status) __builtin_trap();                    // the returned status is the result's
  if (!finite && s == gsf::Status::Ok) __builtin_trap();  // a non-finite argument must be refused
  if (s == gsf::Status::Ok && !r.map_T_scan.matrix().allFinite()) __builtin_trap();
  gsf::LocalizeResult again;
  const gsf::Status a = g_loc.localize(g_world->queries[0].view(), &again);
  if (a != g_ref_status ||
      std::memcmp(again.map_T_scan.data(), g_reference.map_T_scan.data(), sizeof(double) * 16) != 0)
    __builtin_trap();  // state leaked from the fuzzed call into the next one-shot query
  return 0;
}
