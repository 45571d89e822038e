// Bird's-eye picture of pole/trunk extraction on one real scan: points coloured by class, extracted
// poles (red) and trunks (orange) circled; on SemanticKITTI (whose poles/trunks are first relabelled
// into their hosts, building/vegetation) the true poles/trunks are marked with black crosses.
//   bench_pole_picture nuscenes <dataset_root> <scene> <frame_index> <out.svg> [half_width_m]
//   bench_pole_picture kitti <dataset_root> <seq> <frame_index> <out.svg> [half_width_m]
// Prints the instances (position, kind, height, tilt, thickness, score) to stdout.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "arena_buffer.h"
#include "gsf/detail/instance_clustering.h"
#include "gsf/detail/pole_extraction.h"
#include "gsf/detail/voxel_layer.h"
#include "gsf/port/nuscenes.h"
#include "gsf/port/semantic_kitti.h"

using namespace gsf;

namespace {

const char* colour(int c) {
  switch (c) {
    case kCar: return "#4a6fe3";
    case kTruck:
    case kOtherVehicle:
    case kBicycle:
    case kMotorcycle: return "#7b8ef0";
    case kPerson:
    case kBicyclist:
    case kMotorcyclist: return "#e040fb";
    case kRoad: return "#c8c8c8";
    case kParking:
    case kOtherGround: return "#d7c8e0";
    case kSidewalk: return "#e8d8c0";
    case kTerrain: return "#d4dca0";
    case kBuilding: return "#6d7f99";
    case kFence: return "#b08860";
    case kVegetation: return "#3e9b3e";
    case kTrunk: return "#7a4a1a";
    case kPole: return "#111111";
    case kTrafficSign: return "#ff0000";
    default: return "#dddddd";
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 6) {
    std::fprintf(stderr, "usage: %s nuscenes|kitti <dataset_root> <scene> <frame_index> <out.svg> [half_width_m]\n",
                 argv[0]);
    return 2;
  }
  const bool kitti = std::strcmp(argv[1], "kitti") == 0;
  const uint32_t index = static_cast<uint32_t>(std::atoi(argv[4]));
  const double half = argc > 6 ? std::atof(argv[6]) : 40.0;
  port::OwnedScanBuffer buf(200000, false);
  port::ScanSource* src = nullptr;
  port::NuScenesLidarsegSource nus;
  port::SemanticKittiSource sk;
  port::KittiReadOptions ro;
  ro.load_logits = false;
  if (kitti) {
    if (sk.open(argv[2], argv[3], ro) != Status::Ok) {
      std::fprintf(stderr, "cannot open %s/%s\n", argv[2], argv[3]);
      return 1;
    }
    src = &sk;
  } else {
    if (nus.open(argv[2], argv[3], ro) != Status::Ok) {
      std::fprintf(stderr, "cannot open %s/%s\n", argv[2], argv[3]);
      return 1;
    }
    src = &nus;
  }
  if (src->read(index, buf.buffer()) != Status::Ok) {
    std::fprintf(stderr, "cannot read frame %u\n", index);
    return 1;
  }
  port::ScanBuffer& b = buf.buffer();
  std::vector<uint32_t> truth(b.labels, b.labels + b.count);
  if (kitti)  // the nuScenes situation: poles inside manmade, trunks inside vegetation
    for (uint32_t i = 0; i < b.count; ++i) {
      const uint32_t id = b.labels[i] & 0xFFFF;
      b.labels[i] = id == 80 ? 50 : id == 71 ? 70 : id;
    }

  VoxelConfig vc;
  PoleConfig pc;
  ClusterConfig gc;
  gc.instance_classes = class_bit(kPole) | class_bit(kTrunk);
  for (int k = 0; k < kNumClasses; ++k) gc.max_extent[k] = 100.0f;
  gc.min_voxels[kPole] = gc.min_voxels[kTrunk] = 2;
  gc.max_instances = 1000;
  gsf_test::ArenaBuffer arena(2 * VoxelLayer::required_bytes(vc) + PoleExtraction::required_bytes(pc, vc.max_voxels) +
                              InstanceClustering::required_bytes(gc, vc.max_voxels));
  VoxelLayer layer, truth_layer;
  PoleExtraction poles;
  InstanceClustering gt;
  if (layer.bind(arena.arena, vc) != Status::Ok || poles.bind(arena.arena, pc, vc.max_voxels) != Status::Ok ||
      truth_layer.bind(arena.arena, vc) != Status::Ok || gt.bind(arena.arena, gc, vc.max_voxels) != Status::Ok)
    return 1;
  if (layer.build(b.view(), nullptr) != Status::Ok) return 1;
  PoleStats ps;
  const Status s = poles.build(layer, &ps);
  if (s != Status::Ok && s != Status::CapacityExceeded) return 1;
  uint32_t gt_count = 0;
  if (kitti) {
    ScanView tv = b.view();
    tv.labels = truth.data();
    if (truth_layer.build(tv, nullptr) != Status::Ok || gt.build(truth_layer, nullptr) != Status::Ok) return 1;
    gt_count = gt.size();
  }

  // SVG: x right, y up (sensor frame), `half` metres around the sensor, 10 px per metre.
  const double px_per_m = 10.0, size = 2 * half * px_per_m;
  auto X = [&](double x) { return (x + half) * px_per_m; };
  auto Y = [&](double y) { return (half - y) * px_per_m; };
  std::string svg;
  char tmp[512];
  std::snprintf(tmp, sizeof(tmp),
                "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\" viewBox=\"0 0 %.0f %.0f\">\n"
                "<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n",
                size, size + 60, size, size + 60);
  svg += tmp;
  // Ground first, then everything else, so structures sit on top; one dot per 0.2 m cell and class
  // (keeps the file small without changing the picture).
  std::vector<std::vector<uint32_t>> drawn(static_cast<size_t>(size / 2) + 1);
  auto first_in_cell = [&](double x, double y, int c) {
    auto& row = drawn[static_cast<size_t>(x / 2)];
    const uint32_t key = (static_cast<uint32_t>(y / 2) << 5) | static_cast<uint32_t>(c);
    for (uint32_t k : row)
      if (k == key) return false;
    row.push_back(key);
    return true;
  };
  for (int pass = 0; pass < 2; ++pass)
    for (uint32_t i = 0; i < b.count; ++i) {
      const float* p = b.points + 4 * size_t(i);
      if (std::fabs(p[0]) > half || std::fabs(p[1]) > half) continue;
      const int c = class_from_kitti(truth[i]);
      if (c < 0) continue;
      const bool flat = c == kRoad || c == kParking || c == kSidewalk || c == kOtherGround || c == kTerrain;
      if (flat != (pass == 0) || !first_in_cell(X(p[0]), Y(p[1]), c)) continue;
      std::snprintf(tmp, sizeof(tmp), "<rect x=\"%.1f\" y=\"%.1f\" width=\"1.6\" height=\"1.6\" fill=\"%s\"/>\n",
                    X(p[0]) - 0.8, Y(p[1]) - 0.8, colour(c));
      svg += tmp;
    }
  for (uint32_t k = 0; k < gt_count; ++k) {
    const Instance& g = gt.instance(k);
    if (std::fabs(g.centroid[0]) > half || std::fabs(g.centroid[1]) > half) continue;
    const double x = X(g.centroid[0]), y = Y(g.centroid[1]);
    std::snprintf(tmp, sizeof(tmp),
                  "<path d=\"M%.1f %.1fL%.1f %.1fM%.1f %.1fL%.1f %.1f\" stroke=\"black\" stroke-width=\"1.5\"/>\n",
                  x - 5, y - 5, x + 5, y + 5, x - 5, y + 5, x + 5, y - 5);
    svg += tmp;
  }
  for (uint32_t k = 0; k < poles.size(); ++k) {
    const Instance& in = poles.instance(k);
    const PoleInfo& info = poles.info(k);
    std::printf("%s (%.2f, %.2f, %.2f) height %.1f m, tilt %.1f deg, thickness %.2f m, score %.2f, %u points\n",
                in.label == kPole ? "pole " : "trunk", in.centroid[0], in.centroid[1], in.centroid[2], info.height,
                info.tilt_deg, info.thickness, info.score, in.point_count);
    if (std::fabs(in.centroid[0]) > half || std::fabs(in.centroid[1]) > half) continue;  // outside the picture
    std::snprintf(tmp, sizeof(tmp),
                  "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"9\" fill=\"none\" stroke=\"%s\" stroke-width=\"2.5\"/>\n",
                  X(in.centroid[0]), Y(in.centroid[1]), in.label == kPole ? "#ff1010" : "#ff9900");
    svg += tmp;
  }
  std::snprintf(tmp, sizeof(tmp),
                "<text x=\"10\" y=\"%.0f\" font-family=\"sans-serif\" font-size=\"15\">%s %s frame %u: %u extracted "
                "(red circle: pole, orange: trunk)%s</text>\n"
                "<text x=\"10\" y=\"%.0f\" font-family=\"sans-serif\" font-size=\"13\" fill=\"#444\">%.0f m square "
                "around the sensor. Blue-grey: %s; green: vegetation; blue: vehicles.</text>\n",
                size + 22, kitti ? "SemanticKITTI" : "nuScenes-lidarseg", argv[3], src->frame_id(index), poles.size(),
                kitti ? "; black x: true pole/trunk" : "", size + 45, 2 * half,
                kitti ? "building (true poles in black)" : "static.manmade");
  svg += tmp;
  svg += "</svg>\n";
  FILE* f = std::fopen(argv[5], "w");
  if (!f) return 1;
  std::fwrite(svg.data(), 1, svg.size(), f);
  std::fclose(f);
  std::printf(
      "%u instances (%u segments, %u wide, %u crowded, %u chains, %u short, %u tilted, %u thick); %u true; wrote %s\n",
      poles.size(), ps.segments, ps.segments_wide, ps.segments_crowded, ps.chains, ps.rejected_short, ps.rejected_tilt,
      ps.rejected_thick, gt_count, argv[5]);
  return 0;
}
