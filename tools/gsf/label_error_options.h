// The label-error options of build-map, evaluate and localize: simulated segmentation-network errors
// applied to each scan's ground-truth labels as it is read (--label-noise, --object-confusion,
// --thin-miss with gsf simulate's meanings; --noise-seed). Maps are built from predicted labels too, so
// build-map takes them as well; map and queries get independent errors (the seed includes the sequence).
#pragma once
#include <string>
#include <vector>

#include "args.h"
#include "pipeline.h"

namespace gsf::cli {

std::vector<OptionSpec> label_error_option_specs();
// Reads the options (usage error: a rate outside 0..1, a seed that is not a whole number >= 0).
bool parse_label_error_options(const Args& args, LabelErrorOptions* out, std::string* error);
// Parses the options and resolves them for `sequence` of a dataset with label set `labels`
// (resolve_scan_label_errors), printing its note as "gsf COMMAND: note: ..." on stderr. False: a usage
// error, in *error.
bool scan_label_errors_from_args(const Args& args, const LabelSet& labels, const std::string& sequence,
                                 const std::string& command, ScanLabelErrors* out, std::string* error);

}  // namespace gsf::cli
