// The reliability diagram of the localizer's confidence (gsf evaluate --svg DIR -> DIR/reliability.svg):
// per mode, each confidence bin's mean predicted confidence (x) against its observed success rate (y),
// the diagonal of perfect calibration, the decision rule's threshold, ECE per mode in the legend, and
// below the curves the bins' query counts as bars with their numbers.
#pragma once
#include <string>
#include <vector>

#include "evaluation.h"

namespace gsf::cli {

// `modes`: the summaries to draw (their calibration bins); min_confidence: the rule's threshold.
bool save_reliability_svg(const std::string& path, const std::vector<ModeSummary>& modes, double min_confidence);

}  // namespace gsf::cli
