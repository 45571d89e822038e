// gsf evaluate --map MAP --dataset DIR --sequence 01 --json OUT.json [--mode gsf|instance|scan-context|all]
// [--min-confidence P] [--svg DIR [--png]] [--label-noise P] [--object-confusion P] [--thin-miss P] [--noise-seed N]
// [--prior-sigma S [--prior-bias B] [--prior-radius R] [--prior-seed N] [--one-shot-too]] [--repeat R]
// | --mode track [--odometry-noise F]
// [--prediction-offset D]
// | --sequence-window N [--odometry-noise F]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "args.h"
#include "commands.h"
#include "label_error_options.h"
#include "run_evaluation.h"
#include "svg.h"

namespace gsf::cli {

bool parse_modes(const std::string& s, std::vector<std::string>* modes) {
  modes->clear();
  std::stringstream ss(s);
  std::string m;
  while (std::getline(ss, m, ',')) {
    if (m == "all") {
      for (const char* x : {"instance", "gsf", "gsf+refine", "scan-context"}) modes->push_back(x);
    } else if (m == "instance" || m == "gsf" || m == "gsf+refine" || m == "scan-context") {
      modes->push_back(m);
    } else {
      return false;
    }
  }
  return !modes->empty();
}

// --prior-* and --odometry-noise into o. False with *error on a bad value.
bool parse_vehicle_mode_options(const Args& args, EvalOptions* o, std::string* error) {
  if (args.has("prior-sigma")) {
    PriorDraw& p = o->prior;
    long long seed = 1;
    p.enabled = true;
    if (!args.get_double("prior-sigma", &p.sigma, error) || !args.get_double("prior-bias", &p.bias, error) ||
        !args.get_int("prior-seed", &seed, error))
      return false;
    p.seed = static_cast<uint64_t>(seed);
    p.radius = std::max(5.0, 3.0 * p.sigma);
    if (args.has("prior-radius") && !args.get_double("prior-radius", &p.radius, error)) return false;
    if (args.has("prior-heading-tolerance") &&
        !args.get_double("prior-heading-tolerance", &p.heading_tolerance_deg, error))
      return false;
    if (!(p.sigma >= 0) || !(p.bias >= 0) || !(p.radius > 0) || !std::isfinite(p.radius) ||
        !(p.heading_tolerance_deg >= 0 && p.heading_tolerance_deg <= 180)) {
      *error = "--prior-sigma and --prior-bias must be >= 0, --prior-radius > 0, --prior-heading-tolerance in [0, 180]";
      return false;
    }
  } else if (args.has("prior-bias") || args.has("prior-radius") || args.has("prior-heading-tolerance")) {
    *error = "--prior-bias, --prior-radius and --prior-heading-tolerance need --prior-sigma";
    return false;
  }
  if (!args.get_double("odometry-noise", &o->odometry_noise, error)) return false;
  if (!(o->odometry_noise >= 0 && o->odometry_noise <= 1)) {
    *error = "--odometry-noise must be in [0, 1]";
    return false;
  }
  if (!args.get_double("prediction-offset", &o->prediction_offset, error)) return false;
  if (!(o->prediction_offset >= 0 && o->prediction_offset <= 50)) {
    *error = "--prediction-offset must be in [0, 50]";
    return false;
  }
  return true;
}

namespace {

std::vector<OptionSpec> evaluate_option_specs() {
  std::vector<OptionSpec> specs = {
      {"map", "map file (gsf build-map)", "", false, true},
      {"dataset", "dataset root with the query sequence", "", false, true},
      {"sequence", "query sequence", "01"},
      {"map-sequence", "mapping sequence (Scan Context peer database)", "00"},
      {"mode",
       "comma list of instance (GSF off, Outram), gsf, gsf+refine, scan-context, or all; or track (tracking over the "
       "10 Hz stretches of sequence 02, gsf simulate --stretches; on real data the whole --sequence is one drive), or "
       "drive (the same stretches through Localizer::localize_next, the library's vehicle loop: tracking, and on a "
       "loss the same scan from scratch: the window of the last scans localized from scratch, or the prior of "
       "--prior-sigma)",
       "all"},
      {"json", "write per-mode summaries and per-query results here", ""},
      {"svg", "directory for the pictures (map + trajectory, correspondences, reliability diagram)", ""},
      {"png",
       "with --svg: also each picture as PNG beside it (runs rsvg-convert, Debian package librsvg2-bin; exit 1 if "
       "it cannot)",
       "", true},
      {"logits", "synthetic or none (see build-map)", "synthetic"},
      {"min-confidence",
       "decision rule: answer when status Ok and confidence >= VALUE (0..1; sets confidence.min_probability; default: "
       "the config's)",
       ""},
      {"limit", "evaluate only the first N queries", "0"},
      {"classes",
       "label set of the dataset's labels: auto, semantic-kitti, nuscenes or a class-table file (docs/data-formats.md)",
       "auto"},
      {"set", "config overrides name=value[,name=value] (see pipeline.cpp), e.g. gsf.tau=0.1", ""},
      {"quiet", "no progress on stderr", "", true},
      {"prior-sigma",
       "localize with a position prior drawn around each query's truth: N(0, S^2) m per axis (docs/vehicle-modes.md)",
       ""},
      {"prior-bias", "with --prior-sigma: the prior's centre also B m off the truth (a wrong prior when B > radius)",
       "0"},
      {"prior-radius", "with --prior-sigma: the prior's radius in m (default 3 x sigma, at least 5)", ""},
      {"prior-seed", "with --prior-sigma: seed of the priors' draws", "1"},
      {"prior-heading-tolerance",
       "with --prior-sigma: the prior also carries a heading (a GNSS course), the truth's yaw with N(0, (T/3)^2) "
       "deg of error, tolerance T deg (0: none)",
       "0"},
      {"one-shot-too",
       "with --prior-sigma: each localizer mode also localizes every query without the prior, right after it (the "
       "run MODE-one-shot): the prior's time against one-shot's on the same scans under the same load",
       "", true},
      {"repeat",
       "localizer modes (not track, drive or --sequence-window): each query localized R times in a row, its time the "
       "fastest run's (the answers are the same; a load spike then costs no query its time)",
       "1"},
      {"odometry-noise",
       "--mode track, --sequence-window: odometry error as a share of the distance travelled (and 10 deg/m x it of "
       "yaw)",
       "0.02"},
      {"prediction-offset",
       "--mode track: each tracked scan's prediction also moved D x U(0,1) m in a random direction and turned D x "
       "U(-1,1) deg (seeded by --prior-seed): wrong predictions, to measure the tracking confidence",
       "0"},
      {"sequence-window",
       "N in 1..4: every scan of the 10 Hz stretches of sequence 02 (real data: of --sequence, one drive) through "
       "localize_sequence, combining the last N scans when one is not confident (1: one-shot; docs/vehicle-modes.md)",
       ""},
  };
  for (const OptionSpec& o : label_error_option_specs()) specs.push_back(o);
  return specs;
}

// --mode track or drive: the modes that run the simulator's 10 Hz stretches scan after scan.
bool stretch_mode(const Args& args) { return args.get("mode") == "track" || args.get("mode") == "drive"; }

// The options into *o, in the order the command line is checked; false with *error on a usage error.
bool parse_eval_options(const Args& args, EvalOptions* o, std::string* error) {
  o->map_path = args.get("map");
  o->dataset = args.get("dataset");
  o->sequence = args.get("sequence");
  o->map_sequence = args.get("map-sequence");
  o->json_out = args.get("json");
  o->svg_dir = args.get("svg");
  o->png = args.flag("png");
  if (o->png && o->svg_dir.empty()) {
    *error = "--png needs --svg DIR";
    return false;
  }
  if (o->png && find_rsvg_convert().empty())
    std::fprintf(stderr,
                 "gsf evaluate: --png: rsvg-convert not found on PATH (Debian: apt-get install librsvg2-bin); the "
                 "SVGs will be written, the PNGs not\n");
  o->progress = !args.flag("quiet");
  o->overrides = args.get("set");
  o->classes = args.get("classes");
  if (!parse_label_error_options(args, &o->label_errors, error)) return false;
  if (stretch_mode(args)) {
    o->modes = {args.get("mode")};
  } else if (!parse_modes(args.get("mode"), &o->modes)) {
    *error = "bad --mode '" + args.get("mode") + "'";
    return false;
  }
  if (!parse_logit_mode(args.get("logits"), &o->logits)) {
    *error = "--logits must be synthetic or none";
    return false;
  }
  long long lim;
  if (!args.get_int("limit", &lim, error) || lim < 0) {
    if (error->empty()) *error = "--limit must be >= 0";
    return false;
  }
  if (args.has("min-confidence")) {
    if (!args.get_double("min-confidence", &o->min_confidence, error)) return false;
    if (!(o->min_confidence >= 0 && o->min_confidence <= 1)) {
      *error = "--min-confidence must be in [0, 1]";
      return false;
    }
  }
  o->limit = static_cast<uint32_t>(lim);
  long long repeat;
  if (!args.get_int("repeat", &repeat, error) || repeat < 1 || repeat > 100) {
    if (error->empty()) *error = "--repeat must be 1..100";
    return false;
  }
  o->repeat = static_cast<uint32_t>(repeat);
  o->one_shot_too = args.flag("one-shot-too");
  if (!parse_vehicle_mode_options(args, o, error)) return false;
  if (o->one_shot_too && !o->prior.enabled) {
    *error = "--one-shot-too needs --prior-sigma";
    return false;
  }
  return true;
}

}  // namespace

int cmd_evaluate(int argc, char** argv) {
  const std::vector<OptionSpec> specs = evaluate_option_specs();
  if (wants_help(argc, argv)) {
    std::printf("%s", usage_text("evaluate",
                                 "Localize a query sequence with ground truth; report success rate "
                                 "(t < 5 m, r < 10 deg), ATE/ARE, time per stage, memory.",
                                 specs)
                          .c_str());
    return 0;
  }
  Args args;
  std::string err;
  if (!args.parse(argc, argv, 2, specs, &err)) return usage_error("evaluate", err);
  EvalOptions o;
  if (!parse_eval_options(args, &o, &err)) return usage_error("evaluate", err);
  const bool stretches = args.has("sequence-window") || stretch_mode(args);
  if (stretches && (o.repeat > 1 || o.one_shot_too))  // their scans depend on the scans before them
    return usage_error("evaluate",
                       "--repeat and --one-shot-too are for the per-query modes, not track, drive or "
                       "--sequence-window");
  if (args.has("sequence-window")) {
    long long n = 0;
    if (!args.get_int("sequence-window", &n, &err) || n < 1 || n > 4)
      return usage_error("evaluate", "--sequence-window must be 1..4");
    o.sequence_window = static_cast<uint32_t>(n);
    if (!args.has("sequence")) o.sequence = "02";  // the simulator's stretches
    return run_window(o);
  }
  if (stretch_mode(args)) {
    if (!args.has("sequence")) o.sequence = "02";  // the simulator's stretches
    return run_tracking(o);
  }
  return run_evaluation(o);
}

}  // namespace gsf::cli
