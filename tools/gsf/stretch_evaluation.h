// What the stretch evaluations (gsf evaluate --mode track, --sequence-window N) share: the map, the
// label set and simulated label errors, the localizer set up once, and the stretches to drive. A
// simulated dataset's stretches are its meta.json's (gsf simulate --stretches, sequence 02); a dataset
// without meta.json (real data: SemanticKITTI, nuScenes-lidarseg) is one stretch, the whole sequence
// in frame order, so both modes run on a real drive too.
#pragma once
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "commands.h"
#include "gsf/localizer.h"
#include "gsf/port/clock.h"
#include "gsf/port/scan_buffer.h"
#include "pipeline.h"
#include "run_evaluation.h"

namespace gsf::cli {

struct StretchEvaluation {
  MapFile file;
  MapView map;
  LabelSet labels;
  ScanLabelErrors label_errors;
  Meta meta;
  std::unique_ptr<port::ScanSource> src;
  std::vector<std::pair<uint32_t, uint32_t>> stretches;  // first scan and length of each
  std::vector<uint64_t> workspace;
  port::SteadyClock clock;
  Localizer loc;
  std::unique_ptr<port::OwnedScanBuffer> buf;

  bool in_zone(uint32_t scan) const { return scan < meta.stretch_in_zone.size() && meta.stretch_in_zone[scan]; }
};

// Loads o.map_path, resolves the labels and their errors, opens o.sequence, finds its stretches and
// initialises the localizer with the default config, o's overrides and o.min_confidence, then
// window.scans = `window_scans` (0: the default). `mode_flag` names the option in messages ("--mode
// track"). Returns 0, or the process exit code after printing why (1: a file or the stretches, 2: a
// usage error).
int open_stretch_evaluation(const EvalOptions& o, const char* mode_flag, uint32_t window_scans, StretchEvaluation* ev);

}  // namespace gsf::cli
