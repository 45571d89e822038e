// Cost model of one query: the floor (read the points once and bucket them into voxel keys with a
// simple open-addressing table) and every stage of Localizer::localize, on the same scans in the same
// run, each as a ratio to the floor. Modes run interleaved per scan (floor, GSF off, GSF on, GSF on +
// refinement; the order rotates per repetition), so they share machine conditions.
//
//   bench_stages --map MAP --dataset DIR [--sequence 01] [--first K] [--limit N] [--repeat R]
//       timing table (median over scans of each stage's fastest of R repetitions)
//   bench_stages --map MAP --dataset DIR --count MODE [--first K] [--limit N]
//       MODE = floor | instance | gsf | gsf+refine: runs only the floor and that mode, once per scan,
//       without a clock. Meant for `valgrind --tool=callgrind` (bench/stages.sh --counts): the
//       inclusive instruction counts of the stage functions are the per-stage instruction counts.
//   --first K starts at the K-th scan (e.g. a world's repetitive zone: meta.json's query_in_repetitive_zone).
//
//   bench_stages ... --set name=value,...   config overrides of `gsf evaluate --set` for every mode
//
//   bench_stages ... --icount-file PATH   (under qemu-aarch64 with bench/qemu_icount_plugin.c)
//       the stage clock reads the guest instruction count from the plugin instead of the time: the
//       table's "us" columns are then thousands of instructions (bench/stages.sh --arm64-counts).
//
// Every run also prints a digest per mode (FNV-1a over every result field except the times), so a
// speed change can be checked for bit-identical results on the whole query set, not just the golden
// test's tiny world.
#include <algorithm>
#include <chrono>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include <fcntl.h>
#include <unistd.h>

#include "gsf/evaluation.h"
#include "gsf/localizer.h"
#include "gsf/map_format.h"
#include "gsf/pipeline.h"
#include "gsf/port/clock.h"
#include "gsf/port/scan_buffer.h"

using namespace gsf;

namespace {

// ---- the floor ------------------------------------------------------------------------------------
// One pass over the points: voxel key (floor of x, y, z over the voxel size, packed to 63 bits), a
// multiplicative hash, linear probing into a table of (key, count) slots sized to the scan (the smallest
// power of two >= 2 x points, so the load stays <= 0.5), cleared after use through the list of touched
// slots. No range filter, no labels, no logits: the least any voxelisation of the scan has to do.
struct FloorTable {
  struct Slot {
    uint64_t key;
    uint32_t count;
    uint32_t used;
  };
  std::vector<Slot> slots;
  std::vector<uint32_t> touched;
  explicit FloorTable(uint32_t max_points) {
    uint32_t n = 16;
    while (n < 2u * max_points) n <<= 1;
    slots.assign(n, Slot{0, 0, 0});
    touched.resize(max_points);
  }
};

__attribute__((noinline)) uint32_t bench_floor_bucket(const ScanView& scan, float voxel_size, FloorTable& t) {
  const float inv = 1.0f / voxel_size;
  uint32_t mask = 15;
  while (mask + 1 < 2u * scan.count) mask = mask * 2 + 1;
  uint32_t n = 0;
  for (uint32_t i = 0; i < scan.count; ++i) {
    const float* p = scan.points + size_t(i) * scan.stride;
    const int32_t x = static_cast<int32_t>(std::floor(p[0] * inv)), y = static_cast<int32_t>(std::floor(p[1] * inv)),
                  z = static_cast<int32_t>(std::floor(p[2] * inv));
    const uint64_t key = (uint64_t(uint32_t(x + (1 << 20))) << 42) | (uint64_t(uint32_t(y + (1 << 20))) << 21) |
                         uint64_t(uint32_t(z + (1 << 20)));
    uint32_t s = static_cast<uint32_t>((key * 0x9E3779B97F4A7C15ULL) >> 40) & mask;
    while (t.slots[s].used && t.slots[s].key != key) s = (s + 1) & mask;
    FloorTable::Slot& slot = t.slots[s];
    if (!slot.used) {
      slot.used = 1;
      slot.key = key;
      slot.count = 0;
      t.touched[n++] = s;
    }
    ++slot.count;
  }
  for (uint32_t k = 0; k < n; ++k) t.slots[t.touched[k]].used = 0;
  return n;
}

// ---- instruction-count clock (qemu plugin) --------------------------------------------------------
// now_ns() reads 8 bytes at a magic offset of a file; bench/qemu_icount_plugin.c writes the guest's
// instruction count there when it sees exactly that pread64. Without the plugin it reads nothing (0).
constexpr off_t kIcountMagic = 0x47534600;  // must match bench/qemu_icount_plugin.c
class IcountClock final : public Clock {
 public:
  explicit IcountClock(int fd) : fd_(fd) {}
  uint64_t now_ns() override {
    uint64_t v = 0;
    if (pread(fd_, &v, sizeof v, kIcountMagic) != static_cast<ssize_t>(sizeof v)) v = 0;
    return v;
  }

 private:
  int fd_;
};

// ---- result digest ---------------------------------------------------------------------------------
struct Fnv {
  uint64_t h = 1469598103934665603ULL;
  void bytes(const void* p, size_t n) {
    const uint8_t* b = static_cast<const uint8_t*>(p);
    for (size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 1099511628211ULL;
  }
  template <class T>
  void add(const T& v) {
    bytes(&v, sizeof v);
  }
};

void digest(Fnv& f, const LocalizeResult& r) {
  f.add(static_cast<int>(r.status));
  f.bytes(r.map_T_scan.matrix().data(), sizeof(double) * 16);
  f.add(r.inliers);
  f.add(r.clique_size);
  f.add(r.score);
  f.add(r.confidence);
  f.add(r.query_instances);
  f.add(r.query_triangles);
  f.add(r.triangle_matches);
  f.add(r.gsf_survivors);
  f.add(r.correspondences);
  f.add(r.match_candidates);
  f.add(r.match_dropped);
  f.add(r.tie_ordered_triangles);
  f.add(r.headings_kept);
  f.add(r.heading_dropped);
  f.add(r.candidate_pairs);
  f.add(r.below_gate_matches);
  f.add(r.candidate_pairs_dropped);
  f.add(r.correspondences_dropped);
  f.add(r.clique_searches);
  f.add(r.hypotheses);
  f.add(r.chosen_hypothesis);
  f.add(r.height_votes);
  f.add(r.verified);
  f.add(r.clique_nodes);
  f.add(r.field_probes);
  f.add(r.field_comparisons);
  f.add(r.refined);
  f.add(r.budget_exhausted);
  f.add(r.capacity_truncated);
  for (uint32_t k = 0; k < kMaxReportedHypotheses; ++k) {
    const HypothesisReport& h = r.hypothesis[k];
    f.add(h.x);
    f.add(h.y);
    f.add(h.yaw_deg);
    f.add(h.clique_size);
    f.add(h.inliers);
    f.add(h.support);
    f.add(h.verified_score);
    f.add(h.verified_voxels);
  }
}

// ---- stages ----------------------------------------------------------------------------------------
constexpr int kStages = 13;  // floor, the ten stage times, unattributed, total
const char* const kStageNames[kStages] = {"floor",      "voxel layer",  "clustering", "query fields", "triangles",
                                          "matching",   "GSF filter",   "hypotheses", "verification", "confidence",
                                          "refinement", "unattributed", "total query"};

void stage_ns(const StageTimes& t, double out[kStages]) {
  const uint64_t parts[10] = {t.voxel, t.cluster, t.field, t.triangle,   t.match,
                              t.gsf,   t.clique,  t.pose,  t.confidence, t.refine};
  uint64_t sum = 0;
  for (int k = 0; k < 10; ++k) {
    out[1 + k] = double(parts[k]);
    sum += parts[k];
  }
  out[11] = double(t.total > sum ? t.total - sum : 0);
  out[12] = double(t.total);
}

double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

struct Mode {
  const char* name;
  bool gsf, refine;
  LocalizerConfig cfg;
  std::vector<uint64_t> workspace;
  Localizer loc;
  Fnv digest;
  std::vector<double> per_scan[kStages];  // fastest of the repetitions, ns
  uint32_t ok = 0;
};

const char* arg(int argc, char** argv, const char* name, const char* fallback) {
  for (int i = 1; i + 1 < argc; ++i)
    if (std::strcmp(argv[i], name) == 0) return argv[i + 1];
  return fallback;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string map_path = arg(argc, argv, "--map", "");
  const std::string dataset = arg(argc, argv, "--dataset", "");
  const std::string sequence = arg(argc, argv, "--sequence", "01");
  const uint32_t limit = static_cast<uint32_t>(std::atoi(arg(argc, argv, "--limit", "0")));
  const uint32_t repeat = std::max(1, std::atoi(arg(argc, argv, "--repeat", "3")));
  const std::string count_mode = arg(argc, argv, "--count", "");
  if (map_path.empty() || dataset.empty()) {
    std::fprintf(stderr,
                 "usage: bench_stages --map MAP --dataset DIR [--sequence 01] [--first K] [--limit N] [--repeat R] "
                 "[--count floor|instance|gsf|gsf+refine]\n");
    return 2;
  }
  std::vector<uint64_t> blob;  // 16-byte aligned (vector of uint64_t from operator new)
  size_t blob_bytes = 0;
  if (FILE* fp = std::fopen(map_path.c_str(), "rb")) {
    std::fseek(fp, 0, SEEK_END);
    blob_bytes = static_cast<size_t>(std::ftell(fp));
    std::fseek(fp, 0, SEEK_SET);
    blob.assign(blob_bytes / 8 + 1, 0);
    if (std::fread(blob.data(), 1, blob_bytes, fp) != blob_bytes) blob_bytes = 0;
    std::fclose(fp);
  }
  MapView map;
  if (blob_bytes == 0 || load_map(blob.data(), blob_bytes, &map) != Status::Ok) {
    std::fprintf(stderr, "cannot read or load map '%s'\n", map_path.c_str());
    return 1;
  }
  Status s;
  auto src = cli::open_source(dataset, sequence, &s);
  if (s != Status::Ok || src->size() == 0) {
    std::fprintf(stderr, "cannot open %s seq %s\n", dataset.c_str(), sequence.c_str());
    return 1;
  }
  const uint32_t first = std::min<uint32_t>(static_cast<uint32_t>(std::atoi(arg(argc, argv, "--first", "0"))),
                                            static_cast<uint32_t>(src->size()));
  const uint32_t nq = limit ? std::min<uint32_t>(first + limit, src->size()) : src->size();

  const bool counting = !count_mode.empty();
  port::SteadyClock steady;
  const std::string icount_file = arg(argc, argv, "--icount-file", "");
  const int icount_fd = icount_file.empty() ? -1 : open(icount_file.c_str(), O_RDONLY);
  if (!icount_file.empty() && icount_fd < 0) {
    std::fprintf(stderr, "cannot open %s\n", icount_file.c_str());
    return 1;
  }
  IcountClock icount(icount_fd);
  Clock& clock = icount_fd >= 0 ? static_cast<Clock&>(icount) : static_cast<Clock&>(steady);
  Mode modes[3] = {{"instance", false, false, {}, {}, {}, {}, {}, 0},
                   {"gsf", true, false, {}, {}, {}, {}, {}, 0},
                   {"gsf+refine", true, true, {}, {}, {}, {}, {}, 0}};
  bool active[3] = {true, true, true};
  if (counting)
    for (int m = 0; m < 3; ++m) active[m] = count_mode == modes[m].name;
  if (counting && count_mode != "floor" && !active[0] && !active[1] && !active[2]) {
    std::fprintf(stderr, "unknown --count mode '%s'\n", count_mode.c_str());
    return 2;
  }
  const std::string overrides = arg(argc, argv, "--set", "");
  for (int m = 0; m < 3; ++m) {
    if (!active[m]) continue;
    Mode& md = modes[m];
    md.cfg = cli::default_config();
    std::string error;
    if (!cli::apply_overrides(&md.cfg, overrides, &error)) {
      std::fprintf(stderr, "--set: %s\n", error.c_str());
      return 2;
    }
    md.cfg.gsf.enabled = md.gsf;
    md.cfg.refine.enabled = md.refine;
    md.workspace.assign(Localizer::required_bytes(md.cfg) / 8 + 2, 0);
    s = md.loc.init(md.cfg, map, md.workspace.data(), md.workspace.size() * 8, counting ? nullptr : &clock);
    if (s != Status::Ok) {
      std::fprintf(stderr, "init %s: %s\n", md.name, to_string(s));
      return 1;
    }
  }
  const LocalizerConfig base = cli::default_config();
  FloorTable floor_table(cli::kMaxScanPoints);
  std::vector<double> floor_ns;
  std::vector<double> points, voxels;
  Fnv floor_digest;
  port::OwnedScanBuffer buf(cli::kMaxScanPoints, true);

  for (uint32_t q = first; q < nq; ++q) {
    if (cli::read_scan(*src, q, buf.buffer(), cli::LogitMode::Synthetic, 2000000u + src->frame_id(q)) != Status::Ok)
      continue;
    const ScanView view = buf.buffer().view();
    points.push_back(view.count);
    double best_floor = 1e300;
    double best[3][kStages];
    for (auto& row : best)
      for (double& x : row) x = 1e300;
    const uint32_t reps = counting ? 1 : repeat;
    for (uint32_t r = 0; r < reps; ++r) {
      for (int step = 0; step < 4; ++step) {
        const int which = (step + int(r) + int(q)) % 4;  // rotate so no mode always runs first
        if (which == 3) {
          if (counting && count_mode != "floor" && r > 0) continue;
          const uint64_t t0 = clock.now_ns();
          const uint32_t nv = bench_floor_bucket(view, base.voxel.voxel_size, floor_table);
          const double ns = double(clock.now_ns() - t0);
          best_floor = std::min(best_floor, ns);
          if (r == 0) {
            voxels.push_back(nv);
            floor_digest.add(nv);
          }
          continue;
        }
        if (!active[which]) continue;
        Mode& md = modes[which];
        LocalizeResult res;
        md.loc.localize(view, &res);
        if (r == 0) {
          digest(md.digest, res);
          if (res.status == Status::Ok) ++md.ok;
        }
        double st[kStages];
        stage_ns(res.times, st);
        for (int k = 1; k < kStages; ++k) best[which][k] = std::min(best[which][k], st[k]);
      }
    }
    floor_ns.push_back(best_floor);
    for (int m = 0; m < 3; ++m)
      if (active[m])
        for (int k = 1; k < kStages; ++k) modes[m].per_scan[k].push_back(best[m][k]);
    if (q % 20 == 0 || q + 1 == nq) std::fprintf(stderr, "\r  bench_stages: %u / %u scans", q + 1, nq);
  }
  std::fprintf(stderr, "\n");

  std::printf("scans: %zu (%s, sequence %s), points per scan median %.0f, floor voxels median %.0f\n", floor_ns.size(),
              dataset.c_str(), sequence.c_str(), median(points), median(voxels));
  std::printf("digest floor %016" PRIx64, floor_digest.h);
  for (int m = 0; m < 3; ++m)
    if (active[m]) std::printf("  %s %016" PRIx64 " (%u ok)", modes[m].name, modes[m].digest.h, modes[m].ok);
  std::printf("\n");
  if (counting) return 0;

  const double f = median(floor_ns);
  std::printf("repetitions per scan: %u (each cell: median over scans of the fastest repetition)\n", repeat);
  if (icount_fd >= 0)
    std::printf("UNITS: the 'us' columns are thousands of guest INSTRUCTIONS (qemu plugin count), not times\n");
  std::printf("\n");
  std::printf("| stage | GSF off us | x floor | GSF on us | x floor | GSF + refine us | x floor |\n");
  std::printf("| --- | ---: | ---: | ---: | ---: | ---: | ---: |\n");
  std::printf("| floor | %.0f | 1.00 | %.0f | 1.00 | %.0f | 1.00 |\n", f / 1e3, f / 1e3, f / 1e3);
  for (int k = 1; k < kStages; ++k) {
    std::printf("| %s |", kStageNames[k]);
    for (int m = 0; m < 3; ++m) {
      const double v = median(modes[m].per_scan[k]);
      std::printf(" %.0f | %.2f |", v / 1e3, v / f);
    }
    std::printf("\n");
  }
  // Ratios of whole queries measured scan by scan (same scan, same repetition window).
  std::vector<double> on_off, rf_on;
  for (size_t i = 0; i < modes[0].per_scan[kStages - 1].size(); ++i) {
    on_off.push_back(modes[1].per_scan[kStages - 1][i] / modes[0].per_scan[kStages - 1][i]);
    rf_on.push_back(modes[2].per_scan[kStages - 1][i] / modes[1].per_scan[kStages - 1][i]);
  }
  std::printf("\nGSF on / GSF off (total query): ratio of medians %.3f, median of per-scan ratios %.3f\n",
              median(modes[1].per_scan[kStages - 1]) / median(modes[0].per_scan[kStages - 1]), median(on_off));
  std::printf("GSF + refine / GSF on (total query): ratio of medians %.3f, median of per-scan ratios %.3f\n",
              median(modes[2].per_scan[kStages - 1]) / median(modes[1].per_scan[kStages - 1]), median(rf_on));
  // The tail (issue 25, item 4): the slowest scans against the median, each mode on the same scans.
  std::printf("tail (total query):");
  for (int m = 0; m < 3; ++m) {
    const std::vector<double>& t = modes[m].per_scan[kStages - 1];
    const double p95 = cli::percentile(t, 0.95);  // as gsf evaluate's p95
    std::printf("%s %s p95 %.0f us (%.2fx median), max %.0f us", m ? ";" : "", modes[m].name, p95 / 1e3,
                p95 / median(t), cli::percentile(t, 1.0) / 1e3);
  }
  std::printf("\n");
  std::printf(
      "floor median %.1f us; 'unattributed' = total minus the nine stage times (result assembly, "
      "correspondence ranking)\n",
      f / 1e3);
  return 0;
}
