// gsf simulate --out DIR [--preset demo|tiny] [--seed N] [--beams N]
#include <cstdio>

#include "args.h"
#include "commands.h"
#include "sim/simulation.h"

namespace gsf::cli {

int cmd_simulate(int argc, char** argv) {
  const std::vector<OptionSpec> specs = {
      {"out", "dataset root to write (SemanticKITTI layout + meta.json)", "", false, true},
      {"preset", "world size: demo (a few km) or tiny (tests)", "demo"},
      {"seed", "world seed (overrides the preset's)", ""},
      {"beams", "LiDAR beams (e.g. 32 or 64)", ""},
      {"blocks-x", "city blocks along x (overrides the preset)", ""},
      {"blocks-y", "city blocks along y (overrides the preset)", ""},
      {"quiet", "no progress on stderr", "", true},
  };
  if (wants_help(argc, argv)) {
    std::printf("%s", usage_text("simulate", "Generate a semantic LiDAR world: sequence 00 = mapping drive, 01 = "
                                             "localization drive after a time gap.", specs).c_str());
    return 0;
  }
  Args args;
  std::string err;
  if (!args.parse(argc, argv, 2, specs, &err)) return usage_error("simulate", err);
  sim::SimConfig cfg;
  if (args.get("preset") == "demo") cfg = sim::SimConfig::demo();
  else if (args.get("preset") == "tiny") cfg = sim::SimConfig::tiny();
  else return usage_error("simulate", "unknown preset '" + args.get("preset") + "' (demo or tiny)");
  long long v;
  if (args.has("seed")) {
    if (!args.get_int("seed", &v, &err)) return usage_error("simulate", err);
    cfg.world.seed = static_cast<uint64_t>(v);
  }
  if (args.has("beams")) {
    if (!args.get_int("beams", &v, &err) || v < 2 || v > 256) return usage_error("simulate", "--beams must be 2..256");
    cfg.lidar.beams = static_cast<int>(v);
  }
  if (args.has("blocks-x")) {
    if (!args.get_int("blocks-x", &v, &err) || v < 1 || v > 64) return usage_error("simulate", "--blocks-x must be 1..64");
    cfg.world.blocks_x = static_cast<int>(v);
  }
  if (args.has("blocks-y")) {
    if (!args.get_int("blocks-y", &v, &err) || v < 1 || v > 64) return usage_error("simulate", "--blocks-y must be 1..64");
    cfg.world.blocks_y = static_cast<int>(v);
  }
  const bool quiet = args.flag("quiet");
  sim::SimSummary sum;
  const Status s = sim::run_simulation(cfg, args.get("out"), &sum, [&](const char* stage, uint32_t done, uint32_t total) {
    if (!quiet && (done % 10 == 0 || done == total)) {
      std::fprintf(stderr, "\r  simulate: %s %u / %u", stage, done, total);
      if (done == total) std::fprintf(stderr, "\n");
    }
  });
  if (s != Status::Ok) {
    std::fprintf(stderr, "gsf simulate: failed: %s\n", to_string(s));
    return 1;
  }
  std::printf("simulated %.0f m of road: %u map scans, %u queries (%u in the repetitive zone), %llu points -> %s\n",
              sum.road_length_m, sum.map_scans, sum.queries, sum.zone_queries, (unsigned long long)sum.points,
              args.get("out").c_str());
  return 0;
}

}  // namespace gsf::cli
