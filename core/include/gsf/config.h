// LocalizerConfig: every capacity and tuning value of the query pipeline, one sub-struct per stage
// (stage_configs.h).
// Defaults are the evaluated settings (docs/results.md); units in comments. Each settable value is in
// the one parameter list (core/src/parameters.def; gsf/parameters.h: names, units, ranges, docs; the
// table is docs/parameters.md). The map builder records the
// values that must agree between map and localizer in MapParams (map_params_from).
#pragma once
#include <cstdint>

#include "gsf/class_table.h"
#include "gsf/map_format.h"
#include "gsf/stage_configs.h"
#include "gsf/status.h"

namespace gsf {

struct LocalizerConfig {
  uint32_t max_scan_points = 262144;  // larger scans are rejected with CapacityExceeded
  // The label set of the scans' raw label ids (class_table.h). nullptr: SemanticKITTI, with
  // cluster.instance_classes as the instance classes. With a table, its roles decide: instance classes
  // (cluster.instance_classes is ignored), pole / trunk hosts (poles.pole_hosts / trunk_hosts are
  // replaced) and class stabilities. Read during required_bytes(), budget() and init() only: init()
  // copies the table into the workspace, so the caller's table need not outlive it. The map records
  // the table's id; a localizer with another table gets ConfigMismatch.
  const ClassTable* classes = nullptr;
  VoxelConfig voxel;
  ClusterConfig cluster;
  // Geometric pole / trunk instances (pole_extraction.h); runs only when the label set has host
  // classes (nuScenes-lidarseg: static.manmade, static.vegetation), else costs nothing.
  PoleConfig poles;
  FieldConfig field;
  TriangleConfig triangle;
  MatchConfig match;
  GsfFilterConfig gsf;
  HypothesisConfig hypotheses;
  VerifyConfig verify;
  RefineConfig refine;  // off by default (the "gsf+refine" evaluation row turns it on)
  ConfidenceConfig confidence;
  TrackConfig track;  // Localizer::track (tracker.h, docs/vehicle-modes.md)
  // Localizer::localize_sequence: several scans tied by odometry (scan_window.h, docs/vehicle-modes.md).
  WindowConfig window;
};

// Ok, or InvalidArgument when a parameter is out of its range or breaks a rule with another one;
// check_config() (parameters.h) says which parameter and why.
Status validate(const LocalizerConfig& config);
// The label set in effect: *config.classes, or the built-in SemanticKITTI table.
const ClassTable& label_set(const LocalizerConfig& config);
// Instance labels a map built with this config can hold: the label set's instance classes, plus kPole /
// kTrunk when it has pole / trunk hosts.
ClassMask instance_label_mask(const LocalizerConfig& config);
// The pole-extraction settings in effect (hosts and stabilities from the label set).
PoleConfig effective_pole_config(const LocalizerConfig& config);
// The parameters a map built for this config records (and a localizer checks).
MapParams map_params_from(const LocalizerConfig& config);
// Ok if a map built with `params` can serve a localizer with `config`.
Status check_map_params(const LocalizerConfig& config, const MapParams& params);

}  // namespace gsf
