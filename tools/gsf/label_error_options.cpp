#include "label_error_options.h"

#include <cstdio>

namespace gsf::cli {
namespace {

bool get_rate(const Args& args, const std::string& name, float* out, std::string* error) {
  double d;
  if (!args.get_double(name, &d, error) || !(d >= 0.0 && d <= 1.0)) {
    *error = "--" + name + " must be a number in 0..1, got '" + args.get(name) + "'";
    return false;
  }
  *out = static_cast<float>(d);
  return true;
}

}  // namespace

std::vector<OptionSpec> label_error_option_specs() {
  return {
      {"label-noise",
       "simulated network errors: share 0..1 of each scan's points relabelled to a partner class as it is read "
       "(gsf simulate's; docs/simulator.md has the SemanticKITTI and nuScenes partner tables)",
       "0"},
      {"object-confusion",
       "share 0..1 of each scan's objects relabelled whole to one partner: instances by id, id-less poles / signs / "
       "trunks and nuScenes things and thin manmade / vegetation by 0.5 m grid components",
       "0"},
      {"thin-miss",
       "P 0..1: SemanticKITTI pole, sign and trunk points missed with P x clamp((range - 10 m) / 50 m, 0, 1) (no "
       "effect on nuScenes-lidarseg labels)",
       "0"},
      {"noise-seed", "seed of the label errors (with the sequence name and frame number of each scan)", "1"},
  };
}

bool parse_label_error_options(const Args& args, LabelErrorOptions* out, std::string* error) {
  if (!get_rate(args, "label-noise", &out->rates.label_noise, error) ||
      !get_rate(args, "object-confusion", &out->rates.object_confusion, error) ||
      !get_rate(args, "thin-miss", &out->rates.thin_miss, error))
    return false;
  long long seed;
  if (!args.get_int("noise-seed", &seed, error) || seed < 0) {
    *error = "--noise-seed must be a whole number >= 0, got '" + args.get("noise-seed") + "'";
    return false;
  }
  out->noise_seed = static_cast<uint64_t>(seed);
  return true;
}

bool scan_label_errors_from_args(const Args& args, const LabelSet& labels, const std::string& sequence,
                                 const std::string& command, ScanLabelErrors* out, std::string* error) {
  LabelErrorOptions options;
  std::string note;
  if (!parse_label_error_options(args, &options, error) ||
      !resolve_scan_label_errors(options, labels, sequence, out, &note, error))
    return false;
  if (!note.empty()) std::fprintf(stderr, "gsf %s: note: %s\n", command.c_str(), note.c_str());
  return true;
}

}  // namespace gsf::cli
