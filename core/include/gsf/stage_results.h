// What the stages hand the facade for its results (Localizer: LocalizeResult, score_pose): plain data,
// defined here so that a public header never needs a stage's (gsf/detail) header.
#pragma once
#include <cstdint>

namespace gsf {

// Whole-scan verification of one pose against the map's semantic layer (semantic_grid.h).
struct PoseVerification {
  float score = 0.0f;  // agree - disagree (stability-weighted)
  float agree = 0.0f;
  float disagree = 0.0f;
  uint32_t scored = 0;   // sampled voxels that landed on a known cell
  uint32_t unknown = 0;  // sampled voxels that landed outside the map's layer
};

// What the confidence was computed from (confidence.h; LocalizeResult diagnostics).
struct ConfidenceEvidence {
  float z_rival = 0.0f;  // against the closest rival; without one, the closest probe of either kind
  float z_shift = 0.0f;  // against the closest shifted probe (2 or 8 m)
  // Against the closest probe shifted 8 m: farther than the 5 m a right answer may be off, so a pose that
  // stands out only at that scale is right even where its 2 m neighbours tie it (a uniform street).
  float z_shift_far = 0.0f;
  float z_turn = 0.0f;   // against the closest turned probe
  uint32_t rivals = 0;   // rivals compared (at most AnswerConfidence::kMaxRivals)
  uint32_t samples = 0;  // sampled voxels compared
  uint32_t blocks = 0;   // scan blocks holding them
  // The answer's inliers: the scan's instances some vote pair puts within hypotheses.tls_threshold of its
  // map instance at the answer, never fewer than its hypothesis's own count (LocalizeResult::inliers; a
  // clique counts only among the consistency graph's pairs).
  uint32_t inliers = 0;
  float inlier_share = 0.0f;  // inliers / the scan's instances on the map's observed cells at the answer
  float known_share = 0.0f;   // share of the samples that landed on the map's semantic layer at the answer
  float agreement = 0.0f;     // agree / (agree + disagree) at the answer (diagnostic, not in the model)
  // The closest rival's margin (the comparison z_rival comes from): sum over the samples of (evidence at
  // the answer - evidence at the rival) over the sum of |evidence at the answer|, the share of the
  // answer's evidence the rival does not have. Independent of the class weights' scale, like z.
  float rival_margin = 0.0f;
};

}  // namespace gsf
