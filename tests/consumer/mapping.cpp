// A host map tool on the installed gsf::mapping: builds a small map from synthetic scans (a ring of
// poles around a road), loads it back and initializes a localizer on it.
#include <cmath>
#include <cstdio>
#include <vector>

#include "gsf/localizer.h"
#include "gsf/map_format.h"
#include "mapping/map_builder.h"

int main() {
  gsf::LocalizerConfig cfg;
  gsf::mapping::MapBuildConfig build_config;
  build_config.stages = cfg;
  build_config.frame = "consumer";
  gsf::mapping::MapBuilder builder(build_config);
  std::vector<float> xyzi;
  std::vector<uint32_t> labels;
  for (int pole = 0; pole < 12; ++pole) {  // 12 poles (SemanticKITTI 80), 4 m apart in x, 2 rows
    const float px = 6.0f + 4.0f * (pole % 6) + 0.7f * pole, py = pole < 6 ? 5.0f : -6.0f - 0.3f * pole;
    for (int k = 0; k < 40; ++k) {
      xyzi.insert(xyzi.end(), {px + 0.05f * (k % 3), py + 0.05f * (k % 2), 0.1f * k, 0.5f});
      labels.push_back(80);
    }
  }
  for (int i = 0; i < 400; ++i) {  // road (40)
    xyzi.insert(xyzi.end(), {3.0f + 0.1f * i, -3.0f + 0.015f * i, -1.7f, 0.2f});
    labels.push_back(40);
  }
  gsf::ScanView scan;
  scan.points = xyzi.data();
  scan.labels = labels.data();
  scan.count = static_cast<uint32_t>(labels.size());
  const Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  gsf::Status s = builder.add_scan(scan, pose);
  std::vector<uint64_t> blob;
  size_t bytes = 0;
  gsf::mapping::MapBuildStats stats;
  if (s == gsf::Status::Ok) s = builder.build(&blob, &bytes, &stats);
  gsf::MapView map;
  if (s == gsf::Status::Ok) s = gsf::load_map(blob.data(), bytes, &map);
  std::vector<uint64_t> ws(gsf::Localizer::required_bytes(cfg) / 8 + 2);
  gsf::Localizer loc;
  if (s == gsf::Status::Ok) s = loc.init(cfg, map, ws.data(), ws.size() * 8);
  std::printf("%u instances, %zu bytes %s\n", stats.instances, bytes, gsf::to_string(s));
  return s == gsf::Status::Ok && stats.instances == 12 ? 0 : 1;
}
