// Fuzz geometric pole extraction (detail/pole_extraction.h) on arbitrary scans: the input bytes become
// points (x, y, z as int16 centimetres, so they land in the voxel grid) with a host, non-host or unknown
// label each, extracted in the sensor frame (the beam-column row step) or the world frame, with a
// normal and a tiny instance capacity. Checks what build() promises: a status, never more than
// max_instances instances, each of a pole or trunk label, the voxel -> instance map in range and
// consistent with the instances' voxel counts; and that the extractor stays usable (a known scene
// gives its one pole after every fuzzed input).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "arena_buffer.h"
#include "gsf/detail/pole_extraction.h"
#include "gsf/detail/voxel_layer.h"

namespace {

using namespace gsf;

struct Extractor {
  VoxelConfig vc;
  PoleConfig pc, tiny;
  gsf_test::ArenaBuffer buf;
  VoxelLayer layer;
  PoleExtraction poles, small;
  Extractor() : buf(64 + VoxelLayer::required_bytes(vc) + 2 * PoleExtraction::required_bytes(pc, vc.max_voxels)) {
    vc.min_range = 0.0f;
    tiny.max_instances = 2;
    if (layer.bind(buf.arena, vc) != Status::Ok || poles.bind(buf.arena, pc, vc.max_voxels) != Status::Ok ||
        small.bind(buf.arena, tiny, vc.max_voxels) != Status::Ok)
      __builtin_trap();
  }
};

Extractor* g_ex = nullptr;

void check(const PoleExtraction& p, const VoxelLayer& layer, uint32_t max_instances, Status s) {
  if (s != Status::Ok && s != Status::CapacityExceeded && s != Status::InvalidArgument) __builtin_trap();
  if (p.size() > max_instances) __builtin_trap();
  std::vector<uint32_t> voxels(p.size(), 0);
  for (uint32_t v = 0; v < layer.size(); ++v) {
    const uint32_t k = p.voxel_instance()[v];
    if (k == UINT32_MAX) continue;
    if (k >= p.size()) __builtin_trap();
    ++voxels[k];
  }
  for (uint32_t k = 0; k < p.size(); ++k) {
    const Instance& in = p.instance(k);
    if (in.label != kPole && in.label != kTrunk) __builtin_trap();
    if (voxels[k] != in.voxel_count) __builtin_trap();
    if (!std::isfinite(in.centroid[0]) || !std::isfinite(in.centroid[1]) || !std::isfinite(in.centroid[2]))
      __builtin_trap();
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  static Extractor ex;
  g_ex = &ex;
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  Extractor& ex = *g_ex;
  if (size < 1) return 0;
  const LayerFrame frame = (data[0] & 1) ? LayerFrame::Sensor : LayerFrame::World;
  const size_t n = std::min<size_t>((size - 1) / 7, 20000);
  static const uint32_t kLabels[8] = {50, 50, 50, 70, 70, 40, 0, 12345};  // building, vegetation, road, none, unknown
  std::vector<float> pts(4 * n);
  std::vector<uint32_t> labels(n);
  const uint8_t* p = data + 1;
  for (size_t i = 0; i < n; ++i, p += 7) {
    int16_t c[3];
    std::memcpy(c, p, 6);
    for (int k = 0; k < 3; ++k) pts[4 * i + k] = c[k] * 0.01f;
    pts[4 * i + 3] = 0.0f;
    labels[i] = kLabels[p[6] & 7];
  }
  ScanView v;
  v.points = pts.data();
  v.labels = labels.data();
  v.count = static_cast<uint32_t>(n);
  if (ex.layer.build(v, nullptr) == Status::Ok) {
    check(ex.poles, ex.layer, ex.pc.max_instances, ex.poles.build(ex.layer, nullptr, frame));
    check(ex.small, ex.layer, ex.tiny.max_instances, ex.small.build(ex.layer, nullptr, frame));
  }
  // Still usable: one pole, 5 m tall, 10 m in front of the sensor.
  std::vector<float> pole;
  std::vector<uint32_t> pole_labels;
  for (float z = -1.7f; z <= 3.3f; z += 0.05f)
    for (int k = 0; k < 8; ++k) {
      pole.insert(pole.end(), {10.0f + 0.1f * std::cos(k * 0.785f), 0.1f * std::sin(k * 0.785f), z, 0.0f});
      pole_labels.push_back(50);
    }
  ScanView pv;
  pv.points = pole.data();
  pv.labels = pole_labels.data();
  pv.count = static_cast<uint32_t>(pole_labels.size());
  if (ex.layer.build(pv, nullptr) != Status::Ok || ex.poles.build(ex.layer, nullptr, frame) != Status::Ok ||
      ex.poles.size() != 1)
    __builtin_trap();
  return 0;
}
