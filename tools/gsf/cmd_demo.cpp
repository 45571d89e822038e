// gsf demo [--out DIR] [--preset demo|tiny] [--png]: simulate -> build map -> evaluate every mode -> table + SVGs.
#include <chrono>
#include <cstdio>
#include <filesystem>

#include "args.h"
#include "commands.h"
#include "pipeline.h"
#include "run_evaluation.h"
#include "sim/simulation.h"

namespace gsf::cli {
namespace {

// Seconds since the demo began, for the progress lines.
class Stopwatch {
 public:
  double seconds() const { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count(); }

 private:
  std::chrono::steady_clock::time_point t0_ = std::chrono::steady_clock::now();
};

// Step 1: the world of `preset` simulated into `dataset`; false after saying why.
bool simulate_world(const sim::SimConfig& cfg, const std::string& preset, const std::string& dataset, bool quiet,
                    const Stopwatch& clock, sim::SimSummary* sum) {
  std::printf("[1/3] simulating the %s world into %s\n", preset.c_str(), dataset.c_str());
  const Status s = sim::run_simulation(cfg, dataset, sum, [&](const char* stage, uint32_t done, uint32_t total) {
    if (!quiet && (done % 10 == 0 || done == total)) {
      std::fprintf(stderr, "\r  simulate: %s %u / %u", stage, done, total);
      if (done == total) std::fprintf(stderr, "\n");
    }
  });
  if (s != Status::Ok) {
    std::fprintf(stderr, "gsf demo: simulation failed: %s\n", to_string(s));
    return false;
  }
  std::printf("      %.0f m of road, %u map scans, %u queries (%u in the repetitive zone)  [%.0f s]\n",
              sum->road_length_m, sum->map_scans, sum->queries, sum->zone_queries, clock.seconds());
  return true;
}

// Step 2: the map of the dataset's sequence 00 written to `map_path`; false after saying why.
bool build_demo_map(const std::string& dataset, const sim::SimSummary& sum, const std::string& map_path, bool quiet,
                    const Stopwatch& clock) {
  std::printf("[2/3] building the map from sequence 00\n");
  Status s = Status::Ok;
  auto src = open_source(dataset, "00", &s);
  if (s != Status::Ok) return false;
  size_t bytes = 0;
  mapping::MapBuildStats st;
  mapping::MapBuildConfig build_config;
  build_config.stages = default_config();
  build_config.road_length_m = sum.road_length_m;
  mapping::FileMapSink sink(map_path);
  if (!sink.is_open()) {
    std::fprintf(stderr, "gsf demo: cannot create '%s.partial'\n", map_path.c_str());
    return false;
  }
  s = build_map(*src, build_config, LogitMode::Synthetic, sink, &bytes, &st, !quiet);
  if (s != Status::Ok) {
    std::fprintf(stderr, "gsf demo: map build failed: %s\n", to_string(s));
    return false;
  }
  std::printf("      %u instances, %u triangles, %zu bytes (%.2f MB/km)  [%.0f s]\n", st.instances, st.triangles, bytes,
              bytes / 1e6 / (sum.road_length_m / 1000.0), clock.seconds());
  return true;
}

// Step 3: every mode evaluated on sequence 01, results.json and the pictures into `out`; run_evaluation's
// exit status.
int evaluate_demo(const std::string& out, const std::string& dataset, const std::string& map_path, bool png, bool quiet,
                  const Stopwatch& clock) {
  std::printf(
      "[3/3] evaluating sequence 01: instance-only (GSF off, Outram), GSF on, GSF + refinement, Scan Context peer\n");
  EvalOptions o;
  o.map_path = map_path;
  o.dataset = dataset;
  o.modes = {"instance", "gsf", "gsf+refine", "scan-context"};
  o.json_out = out + "/results.json";
  o.svg_dir = out;
  o.png = png;
  o.progress = !quiet;
  const int rc = run_evaluation(o);
  const char* pic = o.png ? "{svg,png}" : "svg";
  std::printf(
      "\nwrote %s/results.json, %s/map_trajectory.%s, %s/correspondences_*.%s, %s/reliability.%s  [total %.0f s]\n",
      out.c_str(), out.c_str(), pic, out.c_str(), pic, out.c_str(), pic, clock.seconds());
  return rc;
}

}  // namespace

int cmd_demo(int argc, char** argv) {
  const std::vector<OptionSpec> specs = {
      {"out", "output directory (dataset, map, results.json, SVGs)", "out/demo"},
      {"preset", "demo (a few km of road) or tiny", "demo"},
      {"png", "also each picture as PNG (runs rsvg-convert, Debian package librsvg2-bin; exit 1 if it cannot)", "",
       true},
      {"quiet", "no progress on stderr", "", true},
  };
  if (wants_help(argc, argv)) {
    std::printf("%s", usage_text("demo",
                                 "The end-to-end demo on a built-in simulated world with a repetitive zone "
                                 "and a time gap: simulate, build the map, evaluate all modes.",
                                 specs)
                          .c_str());
    return 0;
  }
  Args args;
  std::string err;
  if (!args.parse(argc, argv, 2, specs, &err)) return usage_error("demo", err);
  sim::SimConfig cfg;
  if (args.get("preset") == "demo") cfg = sim::SimConfig::demo();
  else if (args.get("preset") == "tiny") cfg = sim::SimConfig::tiny();
  else return usage_error("demo", "unknown preset '" + args.get("preset") + "'");
  const bool quiet = args.flag("quiet");
  const std::string out = args.get("out");
  const std::string dataset = out + "/dataset";
  const std::string map_path = out + "/map.gsfmap";
  std::filesystem::create_directories(out);
  const Stopwatch clock;
  sim::SimSummary sum;
  if (!simulate_world(cfg, args.get("preset"), dataset, quiet, clock, &sum)) return 1;
  if (!build_demo_map(dataset, sum, map_path, quiet, clock)) return 1;
  return evaluate_demo(out, dataset, map_path, args.flag("png"), quiet, clock);
}

}  // namespace gsf::cli
