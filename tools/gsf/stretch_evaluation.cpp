#include "stretch_evaluation.h"

#include <cstdio>

namespace gsf::cli {
namespace {

// The simulator's stretches, or the whole sequence of a real dataset (no meta.json).
bool find_stretches(const Meta& meta, const port::ScanSource& src,
                    std::vector<std::pair<uint32_t, uint32_t>>* stretches) {
  if (meta.present) *stretches = meta.stretches;
  else if (src.size() > 0) stretches->assign(1, {0u, static_cast<uint32_t>(src.size())});
  return !stretches->empty();
}

}  // namespace

int open_stretch_evaluation(const EvalOptions& o, const char* mode_flag, uint32_t window_scans, StretchEvaluation* ev) {
  std::string err;
  if (read_map_file(o.map_path, &ev->file, &err) != Status::Ok ||
      load_map(ev->file.data(), ev->file.bytes, &ev->map) != Status::Ok) {
    std::fprintf(stderr, "gsf evaluate: cannot load map '%s' %s\n", o.map_path.c_str(), err.c_str());
    return 1;
  }
  LocalizerConfig cfg = default_config();
  std::string note;
  if (!resolve_label_set(o.classes, o.dataset, o.sequence, &ev->labels, &err) ||
      !apply_overrides(&cfg, o.overrides, &err) ||
      !resolve_scan_label_errors(o.label_errors, ev->labels, o.sequence, &ev->label_errors, &note, &err)) {
    std::fprintf(stderr, "gsf evaluate: %s\n", err.c_str());
    return 2;
  }
  ev->meta = read_meta(o.dataset);
  Status s;
  ev->src = open_source(o.dataset, o.sequence, &s, &ev->labels);
  if (s != Status::Ok || !find_stretches(ev->meta, *ev->src, &ev->stretches)) {
    std::fprintf(stderr,
                 "gsf evaluate: %s needs the drive of sequence %s (a simulated dataset: gsf simulate --stretches)\n",
                 mode_flag, o.sequence.c_str());
    return 1;
  }
  cfg.classes = ev->labels.config_table();
  if (window_scans > 0) cfg.window.scans = window_scans;
  if (o.min_confidence >= 0) cfg.confidence.min_probability = static_cast<float>(o.min_confidence);
  ev->workspace.assign(Localizer::required_bytes(cfg) / 8 + 2, 0);
  if ((s = ev->loc.init(cfg, ev->map, ev->workspace.data(), ev->workspace.size() * 8, &ev->clock)) != Status::Ok) {
    std::fprintf(stderr, "gsf evaluate: init failed: %s\n", to_string(s));
    return 1;
  }
  ev->buf = std::make_unique<port::OwnedScanBuffer>(kMaxScanPoints, true);
  return 0;
}

}  // namespace gsf::cli
