// The evaluation behind `gsf evaluate` and `gsf demo`: localize every query of a sequence against a map
// in each mode, compare with ground truth, print the table, write JSON and SVG pictures.
#pragma once
#include <string>
#include <vector>

#include "pipeline.h"
#include "vehicle_modes.h"

namespace gsf::cli {

struct EvalOptions {
  std::string map_path;
  std::string dataset;
  std::string sequence = "01";
  std::string map_sequence = "00";  // for the Scan Context peer (its database is the map drive's scans)
  std::vector<std::string> modes;   // instance, gsf, scan-context
  LogitMode logits = LogitMode::Synthetic;
  // The decision rule's threshold, "answered" = status Ok and confidence >= it; it sets the localizer
  // modes' config.confidence.min_probability. < 0: the config's own (defaults + overrides).
  double min_confidence = -1;
  std::string json_out;  // empty: no JSON file
  std::string svg_dir;   // empty: no pictures (else map + trajectory, correspondences, reliability)
  bool png = false;      // also each picture as PNG (rsvg-convert, Debian's librsvg2-bin)
  uint32_t limit = 0;    // evaluate only the first N queries (0 = all)
  bool progress = true;
  std::string classes = "auto";    // label set (pipeline.h resolve_label_set)
  std::string overrides;           // config overrides (name=value,...) applied to every localizer mode
  LabelErrorOptions label_errors;  // simulated network errors on the query scans' labels (none by default)
  PriorDraw prior;                 // a position prior around each query's truth (--prior-sigma)
  double odometry_noise = 0.02;    // --mode track, --sequence-window: odometry noise (vehicle_modes.h noisy_odometry)
  double prediction_offset = 0;    // --mode track: predictions knocked off (vehicle_modes.h offset_prediction)
  uint32_t sequence_window = 0;    // --sequence-window N (1..4): localize_sequence over the stretches; 0: off
  // --repeat R: each query localized R times in a row by each localizer mode, its time the fastest run's
  // (the library is deterministic: every run gives the same answer), so a load spike costs no row.
  uint32_t repeat = 1;
  // --one-shot-too (with a prior): each localizer mode also localizes each query without the prior, right
  // after it, as the run "MODE-one-shot": the prior's time against one-shot's on the same scans under the
  // same machine load.
  bool one_shot_too = false;
};

// Returns the process exit code.
int run_evaluation(const EvalOptions& options);

}  // namespace gsf::cli
