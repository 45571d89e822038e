// gsf build-map --dataset DIR --sequence 00 --out MAP [--logits synthetic|none] [--classes SET]
#include <cstdio>

#include "args.h"
#include "commands.h"
#include "gsf/map_format.h"
#include "pipeline.h"

namespace gsf::cli {

int cmd_build_map(int argc, char** argv) {
  const std::vector<OptionSpec> specs = {
      {"dataset", "SemanticKITTI-layout root (or nuScenes-lidarseg samples)", "", false, true},
      {"sequence", "mapping sequence", "00"},
      {"out", "map file to write", "", false, true},
      {"logits", "synthetic: confusion-model logits and predicted labels; none: ground-truth labels", "synthetic"},
      {"classes", "label set of the dataset's labels: auto, semantic-kitti, nuscenes or a class-table file (docs/data-formats.md)", "auto"},
      {"set", "config overrides name=value[,...] (must match at evaluate/localize time)", ""},
      {"quiet", "no progress on stderr", "", true},
  };
  if (wants_help(argc, argv)) {
    std::printf("%s", usage_text("build-map", "Build a map file from a labelled sequence with poses.", specs).c_str());
    return 0;
  }
  Args args;
  std::string err;
  if (!args.parse(argc, argv, 2, specs, &err)) return usage_error("build-map", err);
  LogitMode logits;
  if (!parse_logit_mode(args.get("logits"), &logits)) return usage_error("build-map", "--logits must be synthetic or none");
  LocalizerConfig cfg = default_config();
  if (!apply_overrides(&cfg, args.get("set"), &err)) return usage_error("build-map", err);
  LabelSet labels;
  if (!resolve_label_set(args.get("classes"), args.get("dataset"), args.get("sequence"), &labels, &err))
    return usage_error("build-map", err);
  cfg.classes = labels.config_table();
  Status s;
  auto src = open_source(args.get("dataset"), args.get("sequence"), &s, &labels);
  if (s != Status::Ok || src->size() == 0) {
    std::fprintf(stderr, "gsf build-map: cannot open sequence '%s' under '%s': %s\n", args.get("sequence").c_str(),
                 args.get("dataset").c_str(), s == Status::Ok ? "no scans" : to_string(s));
    return 1;
  }
  const Meta meta = read_meta(args.get("dataset"));
  const float road = meta.present && meta.road_length_m > 0 ? meta.road_length_m : static_cast<float>(path_length(*src));
  std::vector<uint64_t> blob;
  size_t bytes = 0;
  mapping::MapBuildStats st;
  s = build_map(*src, cfg, logits, road, &blob, &bytes, &st, !args.flag("quiet"));
  if (s != Status::Ok) {
    std::fprintf(stderr, "gsf build-map: failed: %s\n", to_string(s));
    return 1;
  }
  if (!write_file(args.get("out"), blob.data(), bytes, &err)) {
    std::fprintf(stderr, "gsf build-map: %s\n", err.c_str());
    return 1;
  }
  std::printf("map %s (%s labels): %u scans, %u voxels, %u instances (%u geometric poles), %u triangles (%u keys), %u refine points, %zu bytes "
              "(%.2f MB/km over %.0f m); %.1f s accumulate, %.1f s cluster, %.1f s fields, %.1f s triangles\n",
              args.get("out").c_str(), labels.name.c_str(), st.scans, st.map_voxels, st.instances, st.pole_instances, st.triangles, st.index_keys,
              st.refine_points, bytes, road > 0 ? bytes / 1e6 / (road / 1000.0) : 0.0, road, st.seconds_accumulate,
              st.seconds_cluster, st.seconds_fields, st.seconds_triangles);
  return 0;
}

}  // namespace gsf::cli
