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
  std::filesystem::create_directories(out);
  const auto t0 = std::chrono::steady_clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); };

  std::printf("[1/3] simulating the %s world into %s\n", args.get("preset").c_str(), dataset.c_str());
  sim::SimSummary sum;
  Status s = sim::run_simulation(cfg, dataset, &sum, [&](const char* stage, uint32_t done, uint32_t total) {
    if (!quiet && (done % 10 == 0 || done == total)) {
      std::fprintf(stderr, "\r  simulate: %s %u / %u", stage, done, total);
      if (done == total) std::fprintf(stderr, "\n");
    }
  });
  if (s != Status::Ok) {
    std::fprintf(stderr, "gsf demo: simulation failed: %s\n", to_string(s));
    return 1;
  }
  std::printf("      %.0f m of road, %u map scans, %u queries (%u in the repetitive zone)  [%.0f s]\n",
              sum.road_length_m, sum.map_scans, sum.queries, sum.zone_queries, elapsed());

  std::printf("[2/3] building the map from sequence 00\n");
  auto src = open_source(dataset, "00", &s);
  if (s != Status::Ok) return 1;
  size_t bytes = 0;
  mapping::MapBuildStats st;
  mapping::MapBuildConfig build_config;
  build_config.stages = default_config();
  build_config.road_length_m = sum.road_length_m;
  const std::string map_path = out + "/map.gsfmap";
  mapping::FileMapSink sink(map_path);
  if (!sink.is_open()) {
    std::fprintf(stderr, "gsf demo: cannot create '%s.partial'\n", map_path.c_str());
    return 1;
  }
  s = build_map(*src, build_config, LogitMode::Synthetic, sink, &bytes, &st, !quiet);
  if (s != Status::Ok) {
    std::fprintf(stderr, "gsf demo: map build failed: %s\n", to_string(s));
    return 1;
  }
  std::printf("      %u instances, %u triangles, %zu bytes (%.2f MB/km)  [%.0f s]\n", st.instances, st.triangles, bytes,
              bytes / 1e6 / (sum.road_length_m / 1000.0), elapsed());

  std::printf(
      "[3/3] evaluating sequence 01: instance-only (GSF off, Outram), GSF on, GSF + refinement, Scan Context peer\n");
  EvalOptions o;
  o.map_path = map_path;
  o.dataset = dataset;
  o.modes = {"instance", "gsf", "gsf+refine", "scan-context"};
  o.json_out = out + "/results.json";
  o.svg_dir = out;
  o.png = args.flag("png");
  o.progress = !quiet;
  const int rc = run_evaluation(o);
  const char* pic = o.png ? "{svg,png}" : "svg";
  std::printf(
      "\nwrote %s/results.json, %s/map_trajectory.%s, %s/correspondences_*.%s, %s/reliability.%s  [total %.0f s]\n",
      out.c_str(), out.c_str(), pic, out.c_str(), pic, out.c_str(), pic, elapsed());
  return rc;
}

}  // namespace gsf::cli
