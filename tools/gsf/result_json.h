// The library's per-query counts as JSON ("diagnostics"), shared by `gsf evaluate --json` and
// `gsf localize`: what each cap dropped, the headings kept, the hypotheses with their verified
// scores, the stage times. With a ground truth (evaluation) each hypothesis also gets its distance and
// heading error to the truth.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Geometry>

#include "evaluation.h"
#include "gsf/localizer.h"
#include "json_writer.h"

namespace gsf::cli {

struct QueryTruth {
  Eigen::Isometry3d truth = Eigen::Isometry3d::Identity();  // map-local (to_map_local of the dataset pose)
  uint32_t true_correspondences = 0;                        // selected correspondences the truth agrees with
  // Query instances that have a map instance of the same label within 2 m under the true pose (what
  // any matcher could find at best), of query_instances.
  uint32_t repeatable_instances = 0;
  uint32_t answer_repeatable_instances = 0;  // the same under the answer's pose: what a right answer explains
  uint32_t answer_layer_instances = 0;       // under the answer, on (or beside) a semantic cell of their class
  double truth_verified_score = 0;           // the truth's own whole-scan verification score
  double truth_known_share = 0;              // the truth's sampled voxels on cells the map holds, of all sampled
  const std::vector<std::array<float, 2>>* true_pairs = nullptr;  // (GSF weight, range m) of each true one
};

// A result's stage times in milliseconds.
StageMs stage_ms(const StageTimes& times);
// Writes `key` with the nine stage times.
void write_stage_ms(JsonWriter& j, const char* key, const StageMs& t);

// Writes `key` with a pose as 12 numbers, row-major 3x4 [R | t], every digit kept (JsonWriter::exact).
void write_pose(JsonWriter& j, const char* key, const Eigen::Isometry3d& pose);

// Writes key "diagnostics" with an object; `truth` may be null. Hypotheses are map-local, so is truth.
void write_result_diagnostics(JsonWriter& j, const LocalizeResult& x, const QueryTruth* truth);

}  // namespace gsf::cli
