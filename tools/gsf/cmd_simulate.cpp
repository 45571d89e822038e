// gsf simulate --out DIR [--preset demo|tiny|suite|tiny-lattice] [--zone row|lattice|hall|avenue|auto]
//              [--cue-density X] [--seed N] [--beams N] [--map-beams N] [--label-noise P] [--object-confusion P]
//              [--thin-miss P] [--no-instance-ids] [--label-set semantic-kitti|nuscenes] [--offset X,Y[,Z]]
#include <cstdio>

#include "args.h"
#include "commands.h"
#include "sim/simulation.h"

namespace gsf::cli {
namespace {

// A share 0..1 from option `name` (given or its default) into *out.
bool get_share(const Args& args, const std::string& name, float* out, std::string* err) {
  double d;
  if (!args.get_double(name, &d, err) || !(d >= 0.0 && d <= 1.0)) {
    *err = "--" + name + " must be a number in 0..1";
    return false;
  }
  *out = static_cast<float>(d);
  return true;
}

// The sensing options: what the LiDAR sees and which label errors the written scans carry.
bool parse_sensing(const Args& args, sim::SimConfig* cfg, std::string* err) {
  if (!get_share(args, "label-noise", &cfg->label_noise, err)) return false;
  if (!get_share(args, "object-confusion", &cfg->object_confusion, err)) return false;
  if (!get_share(args, "thin-miss", &cfg->thin_miss, err)) return false;
  if (!get_share(args, "spurious-objects", &cfg->spurious_objects, err)) return false;
  cfg->instance_ids = !args.flag("no-instance-ids");
  if (args.get("label-set") != "semantic-kitti" && args.get("label-set") != "nuscenes") {
    *err = "--label-set must be semantic-kitti or nuscenes";
    return false;
  }
  cfg->nuscenes_labels = args.get("label-set") == "nuscenes";
  long long v;
  if (args.has("beams")) {
    if (!args.get_int("beams", &v, err) || v < 2 || v > 256) {
      *err = "--beams must be 2..256";
      return false;
    }
    cfg->lidar.beams = static_cast<int>(v);
  }
  if (args.has("map-coverage")) {
    double d;
    if (!args.get_double("map-coverage", &d, err) || !(d > 0.0 && d <= 1.0)) {
      *err = "--map-coverage must be a number in (0, 1]";
      return false;
    }
    cfg->map_coverage = static_cast<float>(d);
  }
  if (args.has("map-beams")) {
    if (!args.get_int("map-beams", &v, err) || v < 2 || v > 256) {
      *err = "--map-beams must be 2..256";
      return false;
    }
    cfg->map_beams = static_cast<int>(v);
  }
  return true;
}

// The world: the preset, then the seed, zone and cue density given over it.
bool parse_world(const Args& args, sim::SimConfig* cfg, std::string* err) {
  long long v;
  const std::string preset = args.get("preset");
  if (preset == "demo") *cfg = sim::SimConfig::demo();
  else if (preset == "tiny") *cfg = sim::SimConfig::tiny();
  else if (preset == "suite") *cfg = sim::SimConfig::suite(sim::ZoneType::Row, 1);
  else if (preset == "tiny-lattice") *cfg = sim::SimConfig::tiny_lattice();
  else {
    *err = "unknown preset '" + preset + "' (demo, tiny, suite or tiny-lattice)";
    return false;
  }
  uint64_t seed = cfg->world.seed;
  if (args.has("seed")) {
    if (!args.get_int("seed", &v, err) || v < 0) {
      if (err->empty()) *err = "--seed must be >= 0";
      return false;
    }
    seed = static_cast<uint64_t>(v);
  }
  sim::ZoneType zone = cfg->world.zone;
  if (args.has("zone")) {
    const std::string z = args.get("zone");
    if (z == "auto") zone = static_cast<sim::ZoneType>(seed % 4);
    else if (!sim::parse_zone(z.c_str(), &zone)) {
      *err = "--zone must be row, lattice, hall, avenue or auto";
      return false;
    }
  }
  if (preset == "suite") *cfg = sim::SimConfig::suite(zone, seed);  // zone size and time gap by seed
  cfg->world.zone = zone;
  cfg->world.seed = seed;
  if (args.has("seed") && preset == "tiny-lattice") cfg->time_gap.seed = seed * 2654435761u + 7u;
  double d;
  if (args.has("cue-density")) {
    if (!args.get_double("cue-density", &d, err) || !(d >= 0.0 && d <= 1.0)) {
      *err = "--cue-density must be a number in 0..1";
      return false;
    }
    cfg->world.cue_density = static_cast<float>(d);
  }
  return true;
}

// An integer option, when given, in lo..hi into *out; else `message` in *err.
template <typename T>
bool get_bounded(const Args& args, const std::string& name, long long lo, long long hi, const char* message, T* out,
                 std::string* err) {
  if (!args.has(name)) return true;
  long long v;
  if (!args.get_int(name, &v, err) || v < lo || v > hi) {
    *err = message;
    return false;
  }
  *out = static_cast<T>(v);
  return true;
}

// The stretches of sequence 02, the world's extent in blocks and the offset of the written poses.
bool parse_layout(const Args& args, sim::SimConfig* cfg, std::string* err) {
  return get_bounded(args, "stretches", 0, 1000, "--stretches must be 0..1000", &cfg->stretches, err) &&
         get_bounded(args, "stretch-scans", 2, 1000, "--stretch-scans must be 2..1000", &cfg->stretch_scans, err) &&
         get_bounded(args, "blocks-x", 1, 64, "--blocks-x must be 1..64", &cfg->world.blocks_x, err) &&
         get_bounded(args, "blocks-y", 1, 64, "--blocks-y must be 1..64", &cfg->world.blocks_y, err) &&
         (!args.has("offset") || args.get_doubles("offset", 2, 3, cfg->pose_offset, nullptr, err));
}

std::vector<OptionSpec> simulate_specs() {
  return {
      {"out", "dataset root to write (SemanticKITTI layout + meta.json)", "", false, true},
      {"preset",
       "world size: demo (a few km), tiny (tests), suite (bench/suite.sh: 2 x 2 blocks + zone) or "
       "tiny-lattice (ctest: one block + a small lattice)",
       "demo"},
      {"zone",
       "repetitive zone: row, lattice, hall, avenue, or auto (by seed: seed % 4 in that order); "
       "default: the preset's (row; lattice for tiny-lattice)",
       ""},
      {"cue-density",
       "share 0..1 of the zone's repeated instances with a distinctive cue within 6 m "
       "(default: legacy stuff for demo/tiny row, 0.5 otherwise)",
       ""},
      {"seed", "world seed (overrides the preset's)", ""},
      {"label-noise", "share 0..1 of points written with a confused label (pole<->trunk, terrain<->vegetation, ...)",
       "0"},
      {"object-confusion",
       "share 0..1 of instances relabelled whole, per scan, to one partner class (a pole read as a trunk, a "
       "car as a truck)",
       "0"},
      {"thin-miss",
       "P 0..1: pole, sign and trunk points missed (written as building / vegetation) with probability P x "
       "clamp((range - 10 m) / 50 m, 0, 1)",
       "0"},
      {"spurious-objects",
       "share 0..1: per scan, that many times its instance count of wall or hedge patches (0.3 m) written as a "
       "pole or trunk, an unstable segmentation's objects no map holds",
       "0"},
      {"no-instance-ids", "write labels with the instance id bits zeroed", "", true},
      {"label-set",
       "labels written: semantic-kitti (labels/, uint32) or nuscenes (lidarseg/, uint8: poles, signs and trunks only "
       "as static.manmade / static.vegetation)",
       "semantic-kitti"},
      {"beams", "LiDAR beams (e.g. 16, 32, 64 or 128; the query drive's when --map-beams is given)", ""},
      {"map-beams",
       "LiDAR beams of the mapping drive (sequence 00), e.g. 64 with --beams 16: a map from a dense sensor, "
       "queries from a sparse one (default: --beams)",
       ""},
      {"map-coverage",
       "share 0..1 of the world the map covers: the mapping drive keeps its poses in the western share of its x "
       "extent, so queries beyond are off the map and those at its edge see it partly (default 1)",
       ""},
      {"stretches",
       "write sequence 02: N runs of --stretch-scans consecutive scans 0.5-1.5 m apart (10 Hz driving) along query "
       "lanes, for tracking and several-scan localization (default 0: none)",
       ""},
      {"stretch-scans", "scans per stretch (default 20)", ""},
      {"blocks-x", "city blocks along x (overrides the preset)", ""},
      {"blocks-y", "city blocks along y (overrides the preset)", ""},
      {"offset",
       "X,Y[,Z] m added to every written pose (scans unchanged): the same drive posed in another frame, "
       "e.g. 512345,5412345 for UTM-size coordinates",
       ""},
      {"quiet", "no progress on stderr", "", true},
  };
}

// Writes the dataset and prints what it holds.
int run_simulate(const sim::SimConfig& cfg, const std::string& out, bool quiet) {
  sim::SimSummary sum;
  const Status s = sim::run_simulation(cfg, out, &sum, [&](const char* stage, uint32_t done, uint32_t total) {
    if (!quiet && (done % 10 == 0 || done == total)) {
      std::fprintf(stderr, "\r  simulate: %s %u / %u", stage, done, total);
      if (done == total) std::fprintf(stderr, "\n");
    }
  });
  if (s != Status::Ok) {
    std::fprintf(stderr, "gsf simulate: failed: %s\n", to_string(s));
    return 1;
  }
  std::printf(
      "simulated %.0f m of road, zone %s (%u repeated instances, %u with a cue): %u map scans, %u queries "
      "(%u in the repetitive zone, %u near it), %llu points -> %s\n",
      sum.road_length_m, sim::zone_name(cfg.world.zone), sum.zone_instances, sum.cued_instances, sum.map_scans,
      sum.queries, sum.zone_queries, sum.near_zone_queries, (unsigned long long)sum.points, out.c_str());
  return 0;
}

}  // namespace

int cmd_simulate(int argc, char** argv) {
  const std::vector<OptionSpec> specs = simulate_specs();
  if (wants_help(argc, argv)) {
    std::printf("%s", usage_text("simulate",
                                 "Generate a semantic LiDAR world: sequence 00 = mapping drive, 01 = "
                                 "localization drive after a time gap.",
                                 specs)
                          .c_str());
    return 0;
  }
  Args args;
  std::string err;
  sim::SimConfig cfg;
  if (!args.parse(argc, argv, 2, specs, &err) || !parse_world(args, &cfg, &err) || !parse_sensing(args, &cfg, &err) ||
      !parse_layout(args, &cfg, &err))
    return usage_error("simulate", err);
  return run_simulate(cfg, args.get("out"), args.flag("quiet"));
}

}  // namespace gsf::cli
