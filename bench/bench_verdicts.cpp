// Why does a pose score what it scores? For one query scan and a few bird's-eye poses (map frame x, y,
// yaw), counts verification's verdicts of the scan's above-ground voxels by class and by height above
// the sensor: agree / on another class's cell / contradicted (the map saw that cell without anything
// above ground) / unknown (a cell the map never observed). A diagnostic for a twin that outscores the
// truth (docs/confidence.md, "Why right answers are declined").
//
//   bench_verdicts --map M --dataset D --query Q --pose x,y,yaw_deg [--pose ...]
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "gsf/detail/arena.h"
#include "gsf/detail/semantic_grid.h"
#include "gsf/detail/voxel_layer.h"
#include "gsf/map_format.h"
#include "gsf/pipeline.h"
#include "gsf/port/mapped_file.h"
#include "gsf/port/scan_buffer.h"

using namespace gsf;

namespace {

constexpr int kHeightBins = 5;
const float kHeightEdges[kHeightBins - 1] = {-1.0f, 1.0f, 3.0f, 5.0f};  // m above the sensor's origin
const char* const kHeightNames[kHeightBins] = {"< -1", "-1..1", "1..3", "3..5", "> 5"};

int height_bin(float z) {
  int b = 0;
  while (b < kHeightBins - 1 && z >= kHeightEdges[b]) ++b;
  return b;
}

// verification's verdict of one voxel (semantic_grid.cpp, verdict_of), from the grid's public lookups.
enum Verdict { kUnknown, kAgree, kOther, kContradicted };
Verdict verdict(const SemanticGridView& grid, const Eigen::Isometry3d& T, const VerifyPoint& v) {
  const Eigen::Vector3d p = T * Eigen::Vector3d(v.x, v.y, 0.0);
  uint32_t hint = 0;
  const uint32_t mask = grid.cell_at(float(p.x()), float(p.y()), &hint);
  const uint32_t bit = class_bit(v.label);
  const bool ground = (bit & kGroundClasses) != 0;
  if (ground ? !(mask & kGroundClasses) : !(mask & kCellObserved)) return kUnknown;
  const uint32_t near = mask | grid.neighbours_at(float(p.x()), float(p.y()));
  if (near & bit) return kAgree;
  const uint32_t above = ~(kGroundClasses | kCellObserved);
  return !ground && (near & above) ? kOther : kContradicted;
}

bool parse_pose(const char* s, Eigen::Isometry3d* T) {
  double x, y, yaw;
  if (std::sscanf(s, "%lf,%lf,%lf", &x, &y, &yaw) != 3) return false;
  *T = Eigen::Isometry3d::Identity();
  T->linear() = Eigen::AngleAxisd(yaw * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  T->translation() = Eigen::Vector3d(x, y, 0.0);
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  std::string map_path, dataset, sequence = "02";
  int query = -1;
  std::vector<Eigen::Isometry3d> poses;
  std::vector<std::string> pose_text;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--map")) map_path = argv[i + 1];
    else if (!std::strcmp(argv[i], "--dataset")) dataset = argv[i + 1];
    else if (!std::strcmp(argv[i], "--sequence")) sequence = argv[i + 1];
    else if (!std::strcmp(argv[i], "--query")) query = std::atoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--pose")) {
      Eigen::Isometry3d T;
      if (!parse_pose(argv[i + 1], &T)) return std::fprintf(stderr, "bad --pose %s\n", argv[i + 1]), 2;
      poses.push_back(T);
      pose_text.push_back(argv[i + 1]);
    }
  }
  if (map_path.empty() || dataset.empty() || query < 0 || poses.empty()) {
    std::fprintf(stderr, "usage: bench_verdicts --map M --dataset D --query Q --pose x,y,yaw_deg [--pose ...]\n");
    return 2;
  }
  port::MappedFile file;  // aligned for load_map (mapped, or read into words)
  MapView map;
  if (file.open(map_path) != Status::Ok || load_map(file.data(), file.size(), &map) != Status::Ok)
    return std::fprintf(stderr, "cannot load map %s\n", map_path.c_str()), 1;
  Status s;
  auto src = cli::open_source(dataset, sequence, &s);
  if (s != Status::Ok || uint32_t(query) >= src->size())
    return std::fprintf(stderr, "cannot open %s\n", dataset.c_str()), 1;
  port::OwnedScanBuffer buf(cli::kMaxScanPoints, true);
  if (cli::read_scan(*src, uint32_t(query), buf.buffer(), cli::LogitMode::Synthetic, 2000000u + src->frame_id(query)) !=
      Status::Ok)
    return std::fprintf(stderr, "cannot read query %d\n", query), 1;

  const LocalizerConfig cfg = cli::default_config();
  std::vector<uint64_t> arena_bytes(VoxelLayer::required_bytes(cfg.voxel) / 8 + 64);
  Arena arena(arena_bytes.data(), arena_bytes.size() * 8);
  VoxelLayer voxels;
  VoxelStats stats;
  if (voxels.bind(arena, cfg.voxel) != Status::Ok || voxels.build(buf.buffer().view(), &stats) != Status::Ok)
    return std::fprintf(stderr, "voxel layer failed\n"), 1;
  const uint32_t n = voxels.size();
  std::vector<VerifyPoint> all(n);
  fill_verify_points(voxels, all.data());
  const SemanticGridView grid = semantic_grid_view(map);

  std::printf("query %d: %u voxels\n", query, n);
  for (size_t p = 0; p < poses.size(); ++p) {
    std::printf("\npose %s\n%-14s %-6s %7s %7s %7s %7s\n", pose_text[p].c_str(), "class", "height", "agree", "other",
                "contra", "unknown");
    uint32_t total[4] = {0, 0, 0, 0};
    for (uint32_t c = 0; c < kNumClasses; ++c) {
      for (int b = 0; b < kHeightBins; ++b) {
        uint32_t count[4] = {0, 0, 0, 0};
        for (uint32_t i = 0; i < n; ++i)
          if (all[i].label == c && height_bin(voxels.voxel(i).centroid[2]) == b)
            ++count[verdict(grid, poses[p], all[i])];
        if (count[0] + count[1] + count[2] + count[3] == 0) continue;
        std::printf("%-14s %-6s %7u %7u %7u %7u\n", class_name(int(c)), kHeightNames[b], count[kAgree], count[kOther],
                    count[kContradicted], count[kUnknown]);
        for (int k = 0; k < 4; ++k) total[k] += count[k];
      }
    }
    std::printf("%-14s %-6s %7u %7u %7u %7u\n", "all", "", total[kAgree], total[kOther], total[kContradicted],
                total[kUnknown]);
  }
  return 0;
}
