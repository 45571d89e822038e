// Bird's-eye picture of pole/trunk extraction on one real scan: points coloured by class, extracted
// poles (red) and trunks (orange) circled; on SemanticKITTI (whose poles/trunks are first relabelled
// into their hosts, building/vegetation) the true poles/trunks are marked with black crosses. Legend and
// scale bar included; the SVG's viewBox fits its content (tools/gsf/svg.h). For a PNG:
// `rsvg-convert -o out.png out.svg` (Debian's librsvg2-bin).
//   bench_pole_picture nuscenes <dataset_root> <scene> <frame_index> <out.svg> [half_width_m]
//   bench_pole_picture kitti <dataset_root> <seq> <frame_index> <out.svg> [half_width_m]
// Prints the instances (position, kind, height, tilt, thickness, score) to stdout.
#include <algorithm>
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
#include "gsf/svg.h"

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

const char* const kPoleRing = "#ff1010";
const char* const kTrunkRing = "#ff9900";

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
  const Status s = poles.build(layer, &ps, LayerFrame::Sensor);  // one scan, as the localizer sees it
  if (s != Status::Ok && s != Status::CapacityExceeded) return 1;
  uint32_t gt_count = 0;
  if (kitti) {
    ScanView tv = b.view();
    tv.labels = truth.data();
    if (truth_layer.build(tv, nullptr) != Status::Ok || gt.build(truth_layer, nullptr) != Status::Ok) return 1;
    gt_count = gt.size();
  }

  // The picture: x right, y up (sensor frame, bird's-eye), `half` metres around the sensor, 10 px per
  // metre; its viewBox fits what is drawn (svg.h), legend and scale bar included.
  cli::MapProjection proj;
  proj.x0 = -half;
  proj.y0 = half;
  proj.scale = 10.0;
  const double size = 2 * half * proj.scale;
  cli::SvgPicture svg;
  svg.rect(0, 0, size, size, "#ffffff", 1.0, "#bbbbbb");
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
  std::vector<uint32_t> shown(kNumClasses, 0);
  for (int pass = 0; pass < 2; ++pass)
    for (uint32_t i = 0; i < b.count; ++i) {
      const float* p = b.points + 4 * size_t(i);
      if (std::fabs(p[0]) > half || std::fabs(p[1]) > half) continue;
      const int c = class_from_kitti(truth[i]);
      if (c < 0) continue;
      const bool flat = c == kRoad || c == kParking || c == kSidewalk || c == kOtherGround || c == kTerrain;
      if (flat != (pass == 0) || !first_in_cell(proj.px(p[0]), proj.py(p[1]), c)) continue;
      ++shown[c];
      svg.rect(proj.px(p[0]) - 0.8, proj.py(p[1]) - 0.8, 1.6, 1.6, colour(c));
    }
  uint32_t true_shown = 0, extracted_shown[2] = {0, 0};
  for (uint32_t k = 0; k < gt_count; ++k) {
    const Instance& g = gt.instance(k);
    if (std::fabs(g.centroid[0]) > half || std::fabs(g.centroid[1]) > half) continue;
    const double x = proj.px(g.centroid[0]), y = proj.py(g.centroid[1]);
    svg.line(x - 5, y - 5, x + 5, y + 5, "#000000", 1.5);
    svg.line(x - 5, y + 5, x + 5, y - 5, "#000000", 1.5);
    ++true_shown;
  }
  for (uint32_t k = 0; k < poles.size(); ++k) {
    const Instance& in = poles.instance(k);
    const PoleInfo& info = poles.info(k);
    std::printf("%s (%.2f, %.2f, %.2f) height %.1f m, tilt %.1f deg, thickness %.2f m, score %.2f, %u points\n",
                in.label == kPole ? "pole " : "trunk", in.centroid[0], in.centroid[1], in.centroid[2], info.height,
                info.tilt_deg, info.thickness, info.score, in.point_count);
    if (std::fabs(in.centroid[0]) > half || std::fabs(in.centroid[1]) > half) continue;  // outside the picture
    ++extracted_shown[in.label == kPole ? 0 : 1];
    svg.circle(proj.px(in.centroid[0]), proj.py(in.centroid[1]), 9, "none", 1.0,
               in.label == kPole ? kPoleRing : kTrunkRing, 2.5);
  }
  // The sensor, facing +x.
  svg.polygon({{proj.px(1.5), proj.py(0)}, {proj.px(-1), proj.py(1)}, {proj.px(-1), proj.py(-1)}}, "#000000");

  char title[200], sub[300];
  std::snprintf(title, sizeof(title), "%s %s frame %u: %u poles/trunks extracted from geometry (%u in the picture)",
                kitti ? "SemanticKITTI" : "nuScenes-lidarseg", argv[3], src->frame_id(index), poles.size(),
                extracted_shown[0] + extracted_shown[1]);
  std::snprintf(sub, sizeof(sub), "bird's-eye, %.0f m square around the sensor, points by label; %s", 2 * half,
                kitti
                    ? "the extraction saw pole points as building and trunk points as vegetation, as on nuScenes"
                    : "nuScenes has no pole or trunk class: they are inside static.manmade (building) and vegetation");
  svg.text(0, -32, title, 16, "start", 0, "#222", true);
  svg.text(0, -12, sub, 12, "start", 0, "#444");
  std::vector<cli::LegendEntry> classes;  // one row per colour, naming its classes in the picture
  std::vector<std::string> colours;
  for (int c = 0; c < kNumClasses; ++c) {
    if (shown[c] == 0) continue;
    const auto at = std::find(colours.begin(), colours.end(), colour(c));
    if (at != colours.end()) {
      classes[size_t(at - colours.begin())].label += std::string(", ") + class_name(c);
      continue;
    }
    colours.push_back(colour(c));
    classes.push_back(cli::legend_square(colour(c), 7, class_name(c)));
  }
  const double y = cli::draw_legend(svg, size + 16, 0, classes, "points by class").max_y;
  std::vector<cli::LegendEntry> marks = {
      cli::legend_ring(kPoleRing, 7, "extracted pole (" + std::to_string(extracted_shown[0]) + ")", 2.5),
      cli::legend_ring(kTrunkRing, 7, "extracted trunk (" + std::to_string(extracted_shown[1]) + ")", 2.5),
      {[](cli::SvgPicture& s, double cx, double cy) {
         s.polygon({{cx + 7, cy}, {cx - 5, cy - 6}, {cx - 5, cy + 6}}, "#000000");
       },
       "sensor (x forward)"}};
  if (kitti) marks.push_back(cli::legend_cross("#000000", 5, "true pole/trunk (" + std::to_string(true_shown) + ")"));
  cli::draw_legend(svg, size + 16, y + 12, marks, "instances");
  cli::draw_scale_bar(svg, 0, size + 14, proj.scale);
  if (!svg.save(argv[5])) return 1;
  std::printf(
      "%u instances (%u segments, %u wide, %u crowded, %u chains, %u short, %u tilted, %u thick, %u in beam-column "
      "rows); %u true; wrote %s\n",
      poles.size(), ps.segments, ps.segments_wide, ps.segments_crowded, ps.chains, ps.rejected_short, ps.rejected_tilt,
      ps.rejected_thick, ps.rejected_row, gt_count, argv[5]);
  return 0;
}
