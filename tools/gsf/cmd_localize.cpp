// gsf localize --map MAP --dataset DIR --sequence 01 [--frame N] [--mode gsf|instance] [--label-noise P]
// [--object-confusion P] [--thin-miss P] [--noise-seed N] [--prior x,y,radius[,heading_deg,tolerance_deg]]: one JSON
// line per scan, the pose in the map's frame
// ("pose", with the map origin applied) and in the map-local frame.
#include <cstdio>

#include "args.h"
#include "commands.h"
#include "gsf/localizer.h"
#include "gsf/map_format.h"
#include "gsf/port/clock.h"
#include "json_writer.h"
#include "label_error_options.h"
#include "pipeline.h"
#include "result_json.h"
#include "vehicle_modes.h"

namespace gsf::cli {
namespace {

std::vector<OptionSpec> localize_option_specs() {
  std::vector<OptionSpec> specs = {
      {"map", "map file", "", false, true},
      {"dataset", "dataset root", "", false, true},
      {"sequence", "sequence with the scans", "01"},
      {"frame", "localize only the scan with this file number (default: all)", ""},
      {"mode", "gsf or instance (GSF filter off)", "gsf"},
      {"logits", "synthetic or none", "synthetic"},
      {"classes",
       "label set of the dataset's labels: auto, semantic-kitti, nuscenes or a class-table file (docs/data-formats.md)",
       "auto"},
      {"prior",
       "position prior x,y,radius[,heading_deg,tolerance_deg] in the map's frame (m, deg): only poses inside it "
       "(docs/vehicle-modes.md)",
       ""},
  };
  for (const OptionSpec& o : label_error_option_specs()) specs.push_back(o);
  return specs;
}

// What the command line asks for beyond the paths, checked before the map or a scan is read.
struct LocalizeRequest {
  LogitMode logits = LogitMode::Synthetic;
  bool has_prior = false;
  PositionPrior prior;
  long long frame = -1;  // -1: every scan
  LabelSet labels;
  ScanLabelErrors label_errors;
};

// The options into *req; false with *error on a usage error. The label set and the label errors need
// only the dataset's folder.
bool parse_localize_request(const Args& args, LocalizeRequest* req, std::string* error) {
  if (args.get("mode") != "gsf" && args.get("mode") != "instance") {
    *error = "--mode must be gsf or instance";
    return false;
  }
  if (!parse_logit_mode(args.get("logits"), &req->logits)) {
    *error = "--logits must be synthetic or none";
    return false;
  }
  req->has_prior = args.has("prior");
  if (req->has_prior && !parse_prior(args.get("prior"), &req->prior, error)) return false;
  if (args.has("frame") && !args.get_int("frame", &req->frame, error)) return false;
  return resolve_label_set(args.get("classes"), args.get("dataset"), args.get("sequence"), &req->labels, error) &&
         scan_label_errors_from_args(args, req->labels, args.get("sequence"), "localize", &req->label_errors, error);
}

// The map file read and validated into *file and *map (which points into it); false after saying why.
bool open_map(const std::string& path, MapFile* file, MapView* map) {
  std::string err;
  if (read_map_file(path, file, &err) != Status::Ok) {
    std::fprintf(stderr, "gsf localize: %s\n", err.c_str());
    return false;
  }
  const Status s = load_map(file->data(), file->bytes, map);
  if (s != Status::Ok) {
    std::fprintf(stderr, "gsf localize: invalid map: %s\n", map_load_error(*file, s).c_str());
    return false;
  }
  return true;
}

// One scan's answer as one JSON line on stdout. "pose" is in the map's frame (the frame of the mapping
// poses, "map_frame"); "pose_map_local" is the same pose relative to the map origin.
void print_result(uint32_t frame, const LocalizeResult& r, const MapView& map) {
  JsonWriter j;
  j.begin_object();
  j.field("frame", frame);
  j.field("status", to_string(r.status));
  write_pose(j, "pose", r.map_frame_T_scan);
  j.field("map_frame", map.georef.frame);
  write_pose(j, "pose_map_local", r.map_T_scan);
  j.field("inliers", r.inliers);
  j.field("score", r.score);
  j.field("confidence", r.confidence);
  j.field("answered", r.status == Status::Ok && r.confident);  // the default decision rule
  j.field("time_ms", double(r.times.total) / 1e6);
  write_result_diagnostics(j, r, nullptr);
  j.end_object();
  std::printf("%s\n", j.str().c_str());
}

}  // namespace

int cmd_localize(int argc, char** argv) {
  const std::vector<OptionSpec> specs = localize_option_specs();
  if (wants_help(argc, argv)) {
    std::printf(
        "%s", usage_text("localize", "Localize scans against a map; prints one JSON object per scan.", specs).c_str());
    return 0;
  }
  Args args;
  std::string err;
  if (!args.parse(argc, argv, 2, specs, &err)) return usage_error("localize", err);
  LocalizeRequest req;
  if (!parse_localize_request(args, &req, &err)) return usage_error("localize", err);
  MapFile file;
  MapView map;
  if (!open_map(args.get("map"), &file, &map)) return 1;
  Status s = Status::Ok;
  auto src = open_source(args.get("dataset"), args.get("sequence"), &s, &req.labels);
  if (s != Status::Ok) {
    std::fprintf(stderr, "gsf localize: cannot open sequence: %s\n", to_string(s));
    return 1;
  }
  LocalizerConfig cfg = default_config();
  cfg.classes = req.labels.config_table();
  cfg.gsf.enabled = args.get("mode") == "gsf";
  std::vector<uint64_t> workspace(Localizer::required_bytes(cfg) / 8 + 2);
  port::SteadyClock clock;
  Localizer loc;
  s = loc.init(cfg, map, workspace.data(), workspace.size() * 8, &clock);
  if (s != Status::Ok) {
    std::fprintf(stderr, "gsf localize: init failed: %s\n", to_string(s));
    return 1;
  }
  port::OwnedScanBuffer buf(kMaxScanPoints, true);
  bool found = req.frame < 0;
  for (uint32_t i = 0; i < src->size(); ++i) {
    if (req.frame >= 0 && src->frame_id(i) != req.frame) continue;
    found = true;
    LocalizeResult r;
    s = read_scan(*src, i, buf.buffer(), req.logits, 2000000u + src->frame_id(i), cfg.classes, &req.label_errors);
    if (s == Status::Ok && req.has_prior) loc.localize(buf.buffer().view(), req.prior, &r);
    else if (s == Status::Ok) loc.localize(buf.buffer().view(), &r);
    else r.status = s;
    print_result(src->frame_id(i), r, map);
  }
  if (!found) {
    std::fprintf(stderr, "gsf localize: no frame %lld in the sequence\n", req.frame);
    return 1;
  }
  return 0;
}

}  // namespace gsf::cli
