// gsf build-map --dataset DIR --sequence 00 --out MAP [--logits synthetic|none] [--classes SET] [--origin X,Y[,Z]]
// [--frame NAME] [--tile-size M] [--resident-tiles N] [--spill-dir DIR]
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

int cmd_build_map(int argc, char** argv) {
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
      {"resident-tiles", "tiles held in memory at once; the others are spilled to a temporary file (0: no limit)",
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
  if (wants_help(argc, argv)) {
    std::printf("%s", usage_text("build-map", "Build a map file from a labelled sequence with poses.", specs).c_str());
    return 0;
  }
  Args args;
  std::string err;
  if (!args.parse(argc, argv, 2, specs, &err)) return usage_error("build-map", err);
  LogitMode logits;
  if (!parse_logit_mode(args.get("logits"), &logits))
    return usage_error("build-map", "--logits must be synthetic or none");
  LocalizerConfig cfg = default_config();
  if (!apply_overrides(&cfg, args.get("set"), &err)) return usage_error("build-map", err);
  LabelSet labels;
  if (!resolve_label_set(args.get("classes"), args.get("dataset"), args.get("sequence"), &labels, &err))
    return usage_error("build-map", err);
  cfg.classes = labels.config_table();
  ScanLabelErrors label_errors;
  if (!scan_label_errors_from_args(args, labels, args.get("sequence"), "build-map", &label_errors, &err))
    return usage_error("build-map", err);
  mapping::MapBuildConfig options;
  if (args.has("origin")) {
    double o[3] = {0, 0, 0};
    if (!args.get_doubles("origin", 2, 3, o, nullptr, &err)) return usage_error("build-map", err);
    options.origin_given = true;
    options.origin = {o[0], o[1], o[2]};
  }
  options.frame = args.get("frame");
  {
    char* end = nullptr;
    const std::string tile = args.get("tile-size"), resident = args.get("resident-tiles");
    options.tile_size = std::strtof(tile.c_str(), &end);
    if (end == tile.c_str() || *end != '\0' || !(options.tile_size >= 0.0f && options.tile_size <= 100000.0f))
      return usage_error("build-map", "--tile-size must be a number of metres >= 0, got '" + tile + "'");
    const long n = std::strtol(resident.c_str(), &end, 10);
    if (end == resident.c_str() || *end != '\0' || n < 0 || n > 1000000)
      return usage_error("build-map", "--resident-tiles must be a count >= 0, got '" + resident + "'");
    options.max_resident_tiles = static_cast<uint32_t>(n);
    options.spill_dir = args.get("spill-dir");
    const std::string md = args.get("triangle-min-detections");
    if (!md.empty()) {  // default: MapBuildConfig's
      const long d = std::strtol(md.c_str(), &end, 10);
      if (end == md.c_str() || *end != '\0' || d < 0 || d > 1000000)
        return usage_error("build-map", "--triangle-min-detections must be a count >= 0, got '" + md + "'");
      options.triangle_min_detections = static_cast<uint32_t>(d);
    }
    const std::string sc = args.get("scan-triangles");
    if (!sc.empty()) {
      if (sc != "0" && sc != "1") return usage_error("build-map", "--scan-triangles must be 0 or 1, got '" + sc + "'");
      options.scan_triangles = sc == "1" ? 1u : 0u;
    }
    const std::string share = args.get("scan-triangle-share");
    if (!share.empty()) {
      const long k = std::strtol(share.c_str(), &end, 10);
      if (end == share.c_str() || *end != '\0' || k < 0 || k > 1000000)
        return usage_error("build-map", "--scan-triangle-share must be a count >= 0, got '" + share + "'");
      options.scan_triangle_max_key_share = static_cast<uint32_t>(k);
    }
  }
  MapGeoreference probe;
  if (!set_frame_name(&probe, options.frame.c_str()))
    return usage_error("build-map", "--frame must be 1..31 printable ASCII characters, got '" + options.frame + "'");
  Status s;
  auto src = open_source(args.get("dataset"), args.get("sequence"), &s, &labels);
  if (s != Status::Ok || src->size() == 0) {
    std::fprintf(stderr, "gsf build-map: cannot open sequence '%s' under '%s': %s\n", args.get("sequence").c_str(),
                 args.get("dataset").c_str(), s == Status::Ok ? "no scans" : to_string(s));
    return 1;
  }
  const Meta meta = read_meta(args.get("dataset"));
  const float road =
      meta.present && meta.road_length_m > 0 ? meta.road_length_m : static_cast<float>(path_length(*src));
  size_t bytes = 0;
  mapping::MapBuildStats st;
  uint32_t failed_scan = UINT32_MAX;
  options.stages = cfg;
  options.road_length_m = road;
  // Straight to the file, section by section (the map is never whole in memory; written to OUT.partial
  // and renamed, so a failed build leaves no map behind).
  mapping::FileMapSink sink(args.get("out"));
  if (!sink.is_open()) {
    std::fprintf(stderr, "gsf build-map: cannot create '%s.partial'\n", args.get("out").c_str());
    return 1;
  }
  s = build_map(*src, options, logits, sink, &bytes, &st, !args.flag("quiet"), &failed_scan, &label_errors);
  if (s != Status::Ok) {
    if (failed_scan != UINT32_MAX && s == Status::InvalidInput)
      std::fprintf(stderr,
                   "gsf build-map: failed: %s at scan %u (file %u): its pose is more than %.0f m from the map "
                   "origin (give an --origin near the drive) or not finite, or its points are unusable\n",
                   to_string(s), failed_scan, src->frame_id(failed_scan), mapping::kMaxMapLocalCoordinate);
    else if (s == Status::IoError)
      std::fprintf(stderr, "gsf build-map: failed: cannot write '%s'\n", args.get("out").c_str());
    else std::fprintf(stderr, "gsf build-map: failed: %s\n", to_string(s));
    return 1;
  }
  std::printf(
      "map %s (%s labels): %u scans, %u voxels, %u instances (%u geometric poles), %u triangles (%u keys), %u refine "
      "points, %zu bytes "
      "(%.2f MB/km over %.0f m); %.1f s accumulate, %.1f s cluster, %.1f s fields, %.1f s triangles; "
      "peak RSS %.0f MB\n",
      args.get("out").c_str(), labels.name.c_str(), st.scans, st.map_voxels, st.instances, st.pole_instances,
      st.triangles, st.index_keys, st.refine_points, bytes, road > 0 ? bytes / 1e6 / (road / 1000.0) : 0.0, road,
      st.seconds_accumulate, st.seconds_cluster, st.seconds_fields, st.seconds_triangles, peak_rss_bytes() / 1e6);
  if (st.tiles.tiles > 1)
    std::printf(
        "  tiles: %u of %.0f m, at most %u resident (peak %llu voxels), %llu spills, %llu reloads, %.0f MB "
        "spill file\n",
        st.tiles.tiles, options.tile_size, st.tiles.peak_resident,
        static_cast<unsigned long long>(st.tiles.peak_resident_voxels),
        static_cast<unsigned long long>(st.tiles.spills), static_cast<unsigned long long>(st.tiles.reloads),
        st.tiles.spill_bytes / 1e6);
  if (options.triangle_min_detections > 0)
    std::printf(
        "  triangles over %u of %u instances (found by the query stages in >= %u of the scans' %llu detections)\n",
        st.triangle_instances, st.instances, options.triangle_min_detections,
        static_cast<unsigned long long>(st.scan_detections));
  if (options.scan_triangles)
    std::printf(
        "  %u of the triangles from the mapping scans' views (what a query there forms; %u more left out: "
        "their key was crowded)\n",
        st.scan_triangles, st.scan_triangles_crowded);
  if (label_errors.rates.any())
    std::printf("  simulated network errors on the scans' labels: %s\n", describe(label_errors).c_str());
  std::printf("  origin %.3f, %.3f, %.3f m in frame '%s' (map coordinates are relative to it)\n", st.georef.origin[0],
              st.georef.origin[1], st.georef.origin[2], st.georef.frame);
  if (st.instances_dropped > 0 || st.field_points_dropped > 0 || st.scan_points_dropped > 0)
    std::printf(
        "  capacity: %u instances, %llu field points and %llu scan points (beyond scan_max_voxels) were left "
        "out (MapBuildConfig)\n",
        st.instances_dropped, static_cast<unsigned long long>(st.field_points_dropped),
        static_cast<unsigned long long>(st.scan_points_dropped));
  return 0;
}

}  // namespace gsf::cli
