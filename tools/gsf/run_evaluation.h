// The evaluation behind `gsf evaluate` and `gsf demo`: localize every query of a sequence against a map
// in each mode, compare with ground truth, print the table, write JSON and SVG pictures.
#pragma once
#include <string>
#include <vector>

#include "pipeline.h"

namespace gsf::cli {

struct EvalOptions {
  std::string map_path;
  std::string dataset;
  std::string sequence = "01";
  std::string map_sequence = "00";  // for the Scan Context peer (its database is the map drive's scans)
  std::vector<std::string> modes;   // instance, gsf, scan-context
  LogitMode logits = LogitMode::Synthetic;
  double threshold = 0.5;  // default ambiguity threshold for "answered"
  std::string json_out;    // empty: no JSON file
  std::string svg_dir;     // empty: no pictures
  uint32_t limit = 0;      // evaluate only the first N queries (0 = all)
  bool progress = true;
  std::string classes = "auto";  // label set (pipeline.h resolve_label_set)
  std::string overrides;         // config overrides (name=value,...) applied to every localizer mode
};

// Returns the process exit code.
int run_evaluation(const EvalOptions& options);

}  // namespace gsf::cli
