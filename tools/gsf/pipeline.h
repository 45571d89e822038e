// Shared host-side glue for the CLI: default config, dataset reading with synthetic logits, map
// building from a scan source, and the simulator's meta.json.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "gsf/config.h"
#include "gsf/parameters.h"
#include "gsf/port/logit_synthesis.h"
#include "gsf/port/scan_source.h"
#include "gsf/port/semantic_kitti.h"
#include "label_errors/label_errors.h"
#include "mapping/map_builder.h"

namespace gsf::cli {

LocalizerConfig default_config();
// Applies a "name=value" override (e.g. gsf.tau=0.1) through the parameter list (gsf/parameters.h);
// false with a message for an unknown name, a value that is no number, or one outside its range.
bool apply_override(LocalizerConfig* config, const std::string& assignment, std::string* error);
// A comma list of them, then check_config() over the result (the rules between parameters).
bool apply_overrides(LocalizerConfig* config, const std::string& comma_list, std::string* error);
// A parameter's range as text ("(0, 1000]", "a whole number in [1, 4096]", "0 or 1"), a number as the
// docs print it, and a failed check as "name = value: why".
std::string range_text(const ParamInfo& param);
std::string number_text(double x);
std::string value_text(const ParamInfo& param, double value);
std::string describe(const ConfigCheck& check, const LocalizerConfig& config);

enum class LogitMode { None, Synthetic };
bool parse_logit_mode(const std::string& s, LogitMode* out);

// The label set of a dataset's labels (--classes): "auto" (nuScenes-lidarseg for a dataset with a
// lidarseg/ folder, else SemanticKITTI), "semantic-kitti", "nuscenes", or a class-table file
// (port/class_table_file.h). With any set but SemanticKITTI, nuScenes scans are read with their raw
// lidarseg ids, which the table maps.
struct LabelSet {
  std::string name;
  ClassTable table;
  bool semantic_kitti = true;  // the library default: config.classes stays nullptr
  bool nuscenes_raw = false;
  bool nuscenes_data = false;  // the dataset is nuScenes-lidarseg (lidarseg/ folder), raw ids or not
  const ClassTable* config_table() const { return semantic_kitti ? nullptr : &table; }
};
bool resolve_label_set(const std::string& spec, const std::string& dataset_root, const std::string& sequence,
                       LabelSet* out, std::string* error);

// Opens a dataset sequence: SemanticKITTI layout, or nuScenes-lidarseg (lidarseg/ folder) automatically.
std::unique_ptr<port::ScanSource> open_source(const std::string& root, const std::string& sequence, Status* status,
                                              const LabelSet* labels = nullptr);

// Simulated network errors on the scans' labels (label_error_options.h): the rates and the run's seed.
struct LabelErrorOptions {
  label_errors::LabelErrorRates rates;
  uint64_t noise_seed = label_errors::kDefaultNoiseSeed;
};
// What read_scan applies to the scans of one sequence: the rates, the label space of the labels as read,
// and the seed's parts (each scan: real_scan_seed(noise_seed, sequence, frame number)).
struct ScanLabelErrors {
  label_errors::LabelErrorRates rates;
  label_errors::LabelSpace space = label_errors::LabelSpace::SemanticKitti;
  uint64_t noise_seed = label_errors::kDefaultNoiseSeed;
  std::string sequence;
};
// The errors for `sequence` of a dataset with label set `labels`: nuScenes data read with raw lidarseg ids
// gets the nuScenes space, everything else the SemanticKITTI one. False (a usage error) for nuScenes data
// read as SemanticKITTI ids (--classes semantic-kitti): its mapped labels have lost the classes the
// nuScenes partners are in. *note: what to tell the user (thin misses do nothing on nuScenes labels).
bool resolve_scan_label_errors(const LabelErrorOptions& options, const LabelSet& labels, const std::string& sequence,
                               ScanLabelErrors* out, std::string* note, std::string* error);
// One line for output: "label noise 0.1, object confusion 0.15, thin miss 0 on nuscenes-lidarseg labels,
// noise seed 1", or "none (ground-truth labels)".
std::string describe(const ScanLabelErrors& errors);

// Reads scan `index` and, for LogitMode::Synthetic, replaces labels by the confusion model's argmax
// ("what a network predicted") and fills logits. scan_id keeps map and query draws independent.
// `classes`: the label set of the scan's ids (nullptr: SemanticKITTI). `errors` (optional): simulated
// network errors applied to the labels first, seeded by the scan's frame number.
Status read_scan(port::ScanSource& src, uint32_t index, port::ScanBuffer& buf, LogitMode mode, uint64_t scan_id,
                 const ClassTable* classes = nullptr, const ScanLabelErrors* errors = nullptr);

struct Meta {
  bool present = false;
  float road_length_m = 0;
  std::vector<bool> query_in_zone;
  std::vector<bool> query_near_zone;  // within 60 m of the zone, not inside (simulator meta.json)
  std::string zone_type;              // "row", "lattice", "hall", "avenue"; empty if not recorded
  float cue_density = -1;             // -1: legacy row stuff or not recorded
  // The 10 Hz stretches of sequence 02 (gsf simulate --stretches): first scan and length of each.
  std::vector<std::pair<uint32_t, uint32_t>> stretches;
  std::vector<bool> stretch_in_zone;
};
Meta read_meta(const std::string& dataset_root);

// Length of a drive from its poses (sum of steps shorter than 50 m, so jumps between roads do not count).
double path_length(port::ScanSource& src);

// config.classes is the label set of src's labels.
// Builds the map of every scan of `src`: with config.block_tiles > 0 (and tiles) block by block, reading the
// scans again per block (MapBuilder::build_blocked, no spill file), else each scan once through add_scan.
// On failure *failed_scan is the index of the scan add_scan refused, that could not be read or that has
// no pose (NotFound) (UINT32_MAX when the failure came later, at build()). The map goes to `sink`
// section by section (mapping/map_writer.h; a FileMapSink writes the file without holding the map). `errors`
// (optional): simulated network errors on every mapping scan's labels (read_scan).
Status build_map(port::ScanSource& src, const mapping::MapBuildConfig& config, LogitMode logits, mapping::MapSink& sink,
                 size_t* bytes, mapping::MapBuildStats* stats, bool progress, uint32_t* failed_scan = nullptr,
                 const ScanLabelErrors* errors = nullptr);

constexpr uint32_t kMaxScanPoints = 262144;

}  // namespace gsf::cli
