// gsf build-map --dataset DIR --sequence 00 --out MAP [--logits synthetic|none] [--classes SET] [--origin X,Y[,Z]]
// [--frame NAME] [--tile-size M] [--block-tiles N] [--resident-tiles N] [--spill-dir DIR]
// [--label-noise P] [--object-confusion P] [--thin-miss P] [--noise-seed N]   (label_error_options.h)
#include <cstdio>
#include <cstdlib>

#include "args.h"
#include "commands.h"
#include "gsf/map_format.h"
#include "label_error_options.h"
#include "peak_rss.h"
#include "pipeline.h"

namespace gsf::cli {

namespace {

std::vector<OptionSpec> build_map_specs() {
  std::vector<OptionSpec> specs = {
      {"dataset", "SemanticKITTI-layout root (or nuScenes-lidarseg samples)", "", false, true},
      {"sequence", "mapping sequence", "00"},
      {"out", "map file to write", "", false, true},
      {"logits", "synthetic: confusion-model logits and predicted labels; none: ground-truth labels", "synthetic"},
      {"classes",
       "label set of the dataset's labels: auto, semantic-kitti, nuscenes or a class-table file (docs/data-formats.md)",
       "auto"},
      {"set", "config overrides name=value[,...] (must match at evaluate/localize time)", ""},
      {"origin",
       "map origin X,Y[,Z] in the poses' frame (m); everything in the map is stored relative to it "
       "(default: the first pose's translation rounded half up to a whole metre)",
       ""},
      {"frame", "name of the poses' frame recorded in the map, 1..31 printable ASCII (e.g. utm-32N)", "local"},
      {"tile-size",
       "bounded memory: voxel accumulators in square tiles of this side (m), the map built tile by tile; 0: "
       "one tile (the whole map in memory). The map is the same either way",
       "64"},
      {"block-tiles",
       "build the map in blocks of N x N tiles, one in memory at a time, reading each scan once more per block it "
       "reaches (no spill file); 0: read each scan once, spilling tiles beyond --resident-tiles to a file",
       "2"},
      {"resident-tiles",
       "with --block-tiles 0: tiles held in memory at once; the others are spilled to a temporary file (0: no limit)",
       "24"},
      {"spill-dir", "directory of the spill file (default: the system's temporary directory)", ""},
      {"triangle-min-detections",
       "triangles only among map instances the query's instance stages find in at least this many mapping scans "
       "(0: all instances; default: the library's MapBuildConfig)",
       ""},
      {"scan-triangles",
       "1: also the triangles a query would form at each mapping scan's pose (0: only each apex's nearest map "
       "instances; default: the library's MapBuildConfig)",
       ""},
      {"scan-triangle-share",
       "a scan triangle is left out when this many map triangles already have its index key (0: no limit; "
       "default: the library's MapBuildConfig)",
       ""},
      {"quiet", "no progress on stderr", "", true},
  };
  for (const OptionSpec& o : label_error_option_specs()) specs.push_back(o);
  return specs;
}

// What build-map was asked for.
struct BuildMapOptions {
  std::string dataset, sequence, out;
  bool quiet = false;
  LogitMode logits = LogitMode::Synthetic;
  LabelSet labels;  // options.stages.classes points into it
  ScanLabelErrors label_errors;
  mapping::MapBuildConfig options;  // road_length_m is the dataset's, set once it is open
};

// A count 0..1000000 written in decimal (nothing else) into *out.
bool parse_count(const std::string& text, uint32_t* out) {
  char* end = nullptr;
  const long n = std::strtol(text.c_str(), &end, 10);
  if (end == text.c_str() || *end != '\0' || n < 0 || n > 1000000) return false;
  *out = static_cast<uint32_t>(n);
  return true;
}

// The bounded-memory tiles and the triangle choices; those not given keep MapBuildConfig's defaults.
bool parse_tiles_and_triangles(const Args& args, mapping::MapBuildConfig* options, std::string* err) {
  char* end = nullptr;
  const std::string tile = args.get("tile-size"), resident = args.get("resident-tiles");
  options->tile_size = std::strtof(tile.c_str(), &end);
  if (end == tile.c_str() || *end != '\0' || !(options->tile_size >= 0.0f && options->tile_size <= 100000.0f)) {
    *err = "--tile-size must be a number of metres >= 0, got '" + tile + "'";
    return false;
  }
  if (!parse_count(resident, &options->max_resident_tiles)) {
    *err = "--resident-tiles must be a count >= 0, got '" + resident + "'";
    return false;
  }
  options->spill_dir = args.get("spill-dir");
  const std::string block = args.get("block-tiles");
  if (!parse_count(block, &options->block_tiles)) {
    *err = "--block-tiles must be a count >= 0, got '" + block + "'";
    return false;
  }
  const std::string md = args.get("triangle-min-detections");
  if (!md.empty() && !parse_count(md, &options->triangle_min_detections)) {
    *err = "--triangle-min-detections must be a count >= 0, got '" + md + "'";
    return false;
  }
  const std::string sc = args.get("scan-triangles");
  if (!sc.empty()) {
    if (sc != "0" && sc != "1") {
      *err = "--scan-triangles must be 0 or 1, got '" + sc + "'";
      return false;
    }
    options->scan_triangles = sc == "1" ? 1u : 0u;
  }
  const std::string share = args.get("scan-triangle-share");
  if (!share.empty() && !parse_count(share, &options->scan_triangle_max_key_share)) {
    *err = "--scan-triangle-share must be a count >= 0, got '" + share + "'";
    return false;
  }
  return true;
}

// Every usage error, before anything is read but the dataset's folder (label set, label errors).
bool parse_build_map(const Args& args, BuildMapOptions* o, std::string* err) {
  o->dataset = args.get("dataset");
  o->sequence = args.get("sequence");
  o->out = args.get("out");
  o->quiet = args.flag("quiet");
  if (!parse_logit_mode(args.get("logits"), &o->logits)) {
    *err = "--logits must be synthetic or none";
    return false;
  }
  LocalizerConfig cfg = default_config();
  if (!apply_overrides(&cfg, args.get("set"), err)) return false;
  if (!resolve_label_set(args.get("classes"), o->dataset, o->sequence, &o->labels, err)) return false;
  cfg.classes = o->labels.config_table();
  if (!scan_label_errors_from_args(args, o->labels, o->sequence, "build-map", &o->label_errors, err)) return false;
  mapping::MapBuildConfig& options = o->options;
  if (args.has("origin")) {
    double origin[3] = {0, 0, 0};
    if (!args.get_doubles("origin", 2, 3, origin, nullptr, err)) return false;
    options.origin_given = true;
    options.origin = {origin[0], origin[1], origin[2]};
  }
  options.frame = args.get("frame");
  if (!parse_tiles_and_triangles(args, &options, err)) return false;
  MapGeoreference probe;
  if (!set_frame_name(&probe, options.frame.c_str())) {
    *err = "--frame must be 1..31 printable ASCII characters, got '" + options.frame + "'";
    return false;
  }
  options.stages = cfg;
  return true;
}

// Why the build failed, on stderr.
void report_build_failure(const BuildMapOptions& o, port::ScanSource& src, Status s, uint32_t failed_scan) {
  if (failed_scan != UINT32_MAX && s == Status::InvalidInput)
    std::fprintf(stderr,
                 "gsf build-map: failed: %s at scan %u (file %u): its pose is more than %.0f m from the map "
                 "origin (give an --origin near the drive) or not finite, or its points are unusable\n",
                 to_string(s), failed_scan, src.frame_id(failed_scan), mapping::kMaxMapLocalCoordinate);
  else if (failed_scan != UINT32_MAX && s == Status::NotFound)
    std::fprintf(stderr, "gsf build-map: failed: %s: scan %u (file %u) has no pose (poses.txt has no line %u)\n",
                 to_string(s), failed_scan, src.frame_id(failed_scan), src.frame_id(failed_scan) + 1);
  else if (s == Status::IoError) std::fprintf(stderr, "gsf build-map: failed: cannot write '%s'\n", o.out.c_str());
  else std::fprintf(stderr, "gsf build-map: failed: %s\n", to_string(s));
}

// What the map holds and what building it cost, on stdout.
void print_build_report(const BuildMapOptions& o, const mapping::MapBuildStats& st, size_t bytes, float road) {
  std::printf(
      "map %s (%s labels): %u scans, %u voxels, %u instances (%u geometric poles), %u triangles (%u keys), %u refine "
      "points, %zu bytes "
      "(%.2f MB/km over %.0f m); %.1f s accumulate, %.1f s cluster, %.1f s fields, %.1f s triangles; "
      "peak RSS %.0f MB\n",
      o.out.c_str(), o.labels.name.c_str(), st.scans, st.map_voxels, st.instances, st.pole_instances, st.triangles,
      st.index_keys, st.refine_points, bytes, road > 0 ? bytes / 1e6 / (road / 1000.0) : 0.0, road,
      st.seconds_accumulate, st.seconds_cluster, st.seconds_fields, st.seconds_triangles, peak_rss_bytes() / 1e6);
  if (st.blocks > 0)
    std::printf(
        "  tiles: %u of %.0f m in %u blocks of %u x %u, one in memory at a time (peak %u tiles, %llu voxels, "
        "%.0f MB as spill records), %llu scan reads after the first pass; no spill file\n",
        st.tiles.tiles, o.options.tile_size, st.blocks, o.options.block_tiles, o.options.block_tiles,
        st.tiles.peak_resident, static_cast<unsigned long long>(st.tiles.peak_resident_voxels),
        st.tiles.peak_resident_bytes / 1e6, static_cast<unsigned long long>(st.block_scan_reads));
  else if (st.tiles.tiles > 1)
    std::printf(
        "  tiles: %u of %.0f m, at most %u resident (peak %llu voxels, %.0f MB as spill records), %llu spills, "
        "%llu reloads; spill file peak %.0f MB (its live slots at most %.0f MB; %llu compactions moved %.0f MB)\n",
        st.tiles.tiles, o.options.tile_size, st.tiles.peak_resident,
        static_cast<unsigned long long>(st.tiles.peak_resident_voxels), st.tiles.peak_resident_bytes / 1e6,
        static_cast<unsigned long long>(st.tiles.spills), static_cast<unsigned long long>(st.tiles.reloads),
        st.tiles.spill_peak_bytes / 1e6, st.tiles.spill_live_peak_bytes / 1e6,
        static_cast<unsigned long long>(st.tiles.compactions), st.tiles.compaction_bytes / 1e6);
  if (o.options.triangle_min_detections > 0)
    std::printf(
        "  triangles over %u of %u instances (found by the query stages in >= %u of the scans' %llu detections)\n",
        st.triangle_instances, st.instances, o.options.triangle_min_detections,
        static_cast<unsigned long long>(st.scan_detections));
  if (o.options.scan_triangles)
    std::printf(
        "  %u of the triangles from the mapping scans' views (what a query there forms; %u more left out: "
        "their key was crowded)\n",
        st.scan_triangles, st.scan_triangles_crowded);
  if (o.label_errors.rates.any())
    std::printf("  simulated network errors on the scans' labels: %s\n", describe(o.label_errors).c_str());
  std::printf("  origin %.3f, %.3f, %.3f m in frame '%s' (map coordinates are relative to it)\n", st.georef.origin[0],
              st.georef.origin[1], st.georef.origin[2], st.georef.frame);
  if (st.instances_dropped > 0 || st.field_points_dropped > 0 || st.scan_points_dropped > 0)
    std::printf(
        "  capacity: %u instances, %llu field points and %llu scan points (beyond scan_max_voxels) were left "
        "out (MapBuildConfig)\n",
        st.instances_dropped, static_cast<unsigned long long>(st.field_points_dropped),
        static_cast<unsigned long long>(st.scan_points_dropped));
}

// Opens the sequence and builds the map straight to the file, section by section (the map is never
// whole in memory; written to OUT.partial and renamed, so a failed build leaves no map behind).
int run_build_map(BuildMapOptions& o) {
  Status s;
  auto src = open_source(o.dataset, o.sequence, &s, &o.labels);
  if (s != Status::Ok || src->size() == 0) {
    std::fprintf(stderr, "gsf build-map: cannot open sequence '%s' under '%s': %s\n", o.sequence.c_str(),
                 o.dataset.c_str(), s == Status::Ok ? "no scans" : to_string(s));
    return 1;
  }
  const Meta meta = read_meta(o.dataset);
  const float road =
      meta.present && meta.road_length_m > 0 ? meta.road_length_m : static_cast<float>(path_length(*src));
  size_t bytes = 0;
  mapping::MapBuildStats st;
  uint32_t failed_scan = UINT32_MAX;
  o.options.road_length_m = road;
  mapping::FileMapSink sink(o.out);
  if (!sink.is_open()) {
    std::fprintf(stderr, "gsf build-map: cannot create '%s.partial'\n", o.out.c_str());
    return 1;
  }
  s = build_map(*src, o.options, o.logits, sink, &bytes, &st, !o.quiet, &failed_scan, &o.label_errors);
  if (s != Status::Ok) {
    report_build_failure(o, *src, s, failed_scan);
    return 1;
  }
  print_build_report(o, st, bytes, road);
  return 0;
}

}  // namespace

int cmd_build_map(int argc, char** argv) {
  const std::vector<OptionSpec> specs = build_map_specs();
  if (wants_help(argc, argv)) {
    std::printf("%s", usage_text("build-map", "Build a map file from a labelled sequence with poses.", specs).c_str());
    return 0;
  }
  Args args;
  std::string err;
  BuildMapOptions o;
  if (!args.parse(argc, argv, 2, specs, &err) || !parse_build_map(args, &o, &err)) return usage_error("build-map", err);
  return run_build_map(o);
}

}  // namespace gsf::cli
