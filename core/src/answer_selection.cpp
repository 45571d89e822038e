#include "gsf/detail/answer_selection.h"
#include "gsf/detail/angles.h"
#include "gsf/detail/disagree_weights.h"
#include "gsf/detail/pose_distance.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace gsf {
namespace {

// Indices of the best `cap` hypotheses by verification score (eligible[h] != 0, or all when null),
// best first, ties to the earlier hypothesis. Returns how many (<= cap).
uint32_t top_by_score(const PoseHypotheses& hyps, uint32_t H, const uint8_t* eligible, uint32_t cap, uint32_t* out) {
  uint32_t n = 0;
  for (uint32_t h = 0; h < H; ++h) {
    if (eligible && !eligible[h]) continue;
    const float sc = hyps[h].verification.score;
    uint32_t pos = n < cap ? n++ : cap;
    while (pos > 0 && hyps[out[pos - 1]].verification.score < sc) {
      if (pos < cap) out[pos] = out[pos - 1];
      --pos;
    }
    if (pos < cap) out[pos] = h;
  }
  return n;
}

}  // namespace

void rarity_weights(const VoxelLayer& voxels, const float* base, float exponent, uint32_t max_points, float* out) {
  for (int c = 0; c < kNumClasses; ++c) out[c] = base[c];
  if (exponent <= 0.0f || voxels.size() == 0 || max_points == 0) return;
  uint32_t counts[kNumClasses] = {};
  const uint32_t nv = voxels.size(), stride = (nv + max_points - 1) / max_points;
  uint32_t total = 0;
  for (uint32_t i = 0; i < nv; i += stride, ++total) ++counts[voxels.voxel(i).label];
  double mass = 0.0, scaled = 0.0;
  for (int c = 0; c < kNumClasses; ++c) {
    if (counts[c] == 0) continue;
    out[c] = base[c] * static_cast<float>(std::pow(double(counts[c]) / total, -double(exponent)));
    mass += double(base[c]) * counts[c];
    scaled += double(out[c]) * counts[c];
  }
  if (scaled > 0.0)
    for (int c = 0; c < kNumClasses; ++c) out[c] = static_cast<float>(out[c] * (mass / scaled));
}

uint32_t search_sample_points(const VerifyConfig& vc) {
  const uint32_t divisor = std::max(1u, std::min(vc.search_divisor, vc.polish_divisor));
  return std::max(1u, vc.max_points / divisor);
}

size_t AnswerSelector::required_bytes(uint32_t refine_slots, uint32_t max_voxels, uint32_t search_points) {
  return counted_bytes<AnswerSelector>(refine_slots, max_voxels, search_points);
}

Status AnswerSelector::bind(Arena& arena, uint32_t refine_slots, uint32_t max_voxels, uint32_t search_points) {
  refine_slots_ = refine_slots;
  refined_pose_ = arena.allocate<Eigen::Isometry3d>(refine_slots);
  refined_id_ = arena.allocate<uint32_t>(refine_slots);
  points_ = arena.allocate<VerifyPoint>(max_voxels);
  point_capacity_ = max_voxels;
  // A search samples at most search_points of at most max_voxels voxels.
  memo_.capacity = std::min(search_points, max_voxels);
  for (int m = 0; m < 2; ++m) memo_.slot[m] = arena.allocate<SearchMemo::Sample>(memo_.capacity);
  chosen_ = UINT32_MAX;
  return arena.overflowed() ? Status::BufferTooSmall : Status::Ok;
}

Eigen::Isometry3d AnswerSelector::scoring_pose_of(uint32_t h, uint32_t refined_count) const {
  for (uint32_t k = 0; k < refined_count; ++k)
    if (refined_id_[k] == h) return refined_pose_[k];
  return (*hyps_)[h].map_T_scan;
}

void AnswerSelector::set_verify_weights(const float* weights) {
  for (int c = 0; c < kNumClasses; ++c) verify_weights_[c] = weights[c];
}

// Every score reads the voxels through their compact copy (the same results, bit for bit); a layer
// larger than the copy (never: the copy has the layer's capacity) would read the voxels.
struct AnswerSelector::PoseScorer {
  const VerifyPoint* points;  // the compact copy, or nullptr: read the voxels
  const VoxelLayer& voxels;
  const SemanticGridView& semantic;
  const VerifyConfig& vc;
  const float* verify_weights;
  SearchMemo* memo;  // the pattern search's record (the compact copy's searches only)

  PoseVerification score(const Eigen::Isometry3d& T, uint32_t max_points, DisagreeWeights lambda) const {
    const uint32_t nv = voxels.size();
    return points ? verify_pose(points, nv, semantic, T, max_points, verify_weights, lambda)
                  : verify_pose(voxels, semantic, T, max_points, verify_weights, lambda);
  }
  PoseVerification search(const Eigen::Isometry3d& T, Eigen::Isometry3d* refined, const PoseVerification* at_start,
                          DisagreeWeights lambda) const {
    const uint32_t nv = voxels.size();
    return points ? verify_pose_refined(points, nv, semantic, T, vc.max_points, verify_weights, vc.refine_rounds,
                                        vc.refine_step_m, vc.refine_step_deg, refined, vc.search_divisor,
                                        vc.polish_divisor, at_start, lambda, memo)
                  : verify_pose_refined(voxels, semantic, T, vc.max_points, verify_weights, vc.refine_rounds,
                                        vc.refine_step_m, vc.refine_step_deg, refined, vc.search_divisor,
                                        vc.polish_divisor, at_start, lambda);
  }
};

AnswerChoice AnswerSelector::choose(PoseHypotheses& hyps, const VoxelLayer& voxels, const SemanticGridView& semantic,
                                    const float* weights, const HypothesisConfig& hc, const VerifyConfig& vc) {
  hyps_ = &hyps;
  const bool verify = vc.enabled && !semantic.empty();
  uint32_t best = 0;
  uint8_t full_scored[PoseHypotheses::kMaxHypotheses] = {};
  uint32_t refined_count = 0;
  rival_count_ = 0;
  const bool compact = prepare_scoring(voxels, weights, vc, verify);
  if (verify) {
    const PoseScorer scorer{compact ? points_ : nullptr, voxels, semantic, vc, verify_weights_, &memo_};
    refined_count = verify_hypotheses(hyps, scorer, vc, hc, full_scored);
    best = pick_answer_and_rivals(hyps, full_scored, hc, refined_count);
  }
  AnswerChoice choice;
  choice.index = best;
  choice.answer = hyps[best];
  choice.verified = verify;
  chosen_ = best;
  rank_for_report(hyps, verify, full_scored, &choice);
  answer_pose_ = verify ? scoring_pose_of(best, refined_count) : hyps[best].map_T_scan;
  return choice;
}

// This scan's verification weights (rarity_weights) and the voxels' compact copy, when verification
// reads it. Returns whether it does.
bool AnswerSelector::prepare_scoring(const VoxelLayer& voxels, const float* weights, const VerifyConfig& vc,
                                     bool verify) {
  compact_points_ = 0;
  disagree_ = DisagreeWeights(vc.disagree_weight);  // until verify_hypotheses measures this scan's
  rarity_weights(voxels, weights, vc.rarity_exponent, vc.max_points, verify_weights_);
  const bool compact = verify && voxels.size() <= point_capacity_ && points_ != nullptr;
  if (compact) {
    fill_verify_points(voxels, points_);
    compact_points_ = voxels.size();
  }
  return compact;
}

// Coarse score for every hypothesis, the full score for the best `full_top` (marked in full_scored),
// then the best `refine_top` at their best local alignment, a hypothesis within the same-pose tolerance
// of a better one skipped (the same peak: its search would end where the better one's does), and the
// best `refine_turned` turned more than 90 deg from the best. Each step ranks, then caps. Returns how
// many were refined (their ids and poses in refined_id_, refined_pose_).
uint32_t AnswerSelector::verify_hypotheses(PoseHypotheses& hyps, const PoseScorer& scorer, const VerifyConfig& vc,
                                           const HypothesisConfig& hc, uint8_t* full_scored) {
  const uint32_t H = hyps.size();
  uint32_t top[PoseHypotheses::kMaxHypotheses];
  const uint32_t coarse_points = std::max<uint32_t>(1, vc.max_points / vc.coarse_divisor);
  for (uint32_t h = 0; h < H; ++h) hyps[h].verification = scorer.score(hyps[h].map_T_scan, coarse_points, disagree_);
  uint32_t nt = top_by_score(hyps, H, nullptr, vc.full_top, top);
  if (nt > 0) disagree_ = weigh_disagreements(hyps, scorer, hc, top, nt);
  for (uint32_t k = 0; k < nt; ++k) {
    hyps[top[k]].verification = scorer.score(hyps[top[k]].map_T_scan, vc.max_points, disagree_);
    full_scored[top[k]] = 1;
  }
  const uint32_t slots = vc.refine_rounds > 0 ? refine_slots_ : 0;
  nt = distinct_of(hyps, hc, top, top_by_score(hyps, H, full_scored, std::min(vc.refine_top, slots), top));
  nt = add_turned(hyps, hc, full_scored, vc.refine_turned, slots, top, nt);
  for (uint32_t k = 0; k < nt; ++k) {
    refined_id_[k] = top[k];
    const PoseVerification full = hyps[top[k]].verification;  // verify_pose at max_points, just above
    hyps[top[k]].verification = scorer.search(hyps[top[k]].map_T_scan, &refined_pose_[k], &full, disagree_);
  }
  return nt;
}

// This scan's disagree weights (disagree_weights.h): the best coarse hypothesis against up to
// kMaxRivals of the others at another place or heading (top: the coarse ranking, best first, n > 0).
DisagreeWeights AnswerSelector::weigh_disagreements(const PoseHypotheses& hyps, const PoseScorer& scorer,
                                                    const HypothesisConfig& hc, const uint32_t* top, uint32_t n) const {
  const float configured = scorer.vc.disagree_weight;
  if (scorer.points == nullptr) return DisagreeWeights(configured);  // never: the copy has the layer's capacity
  const Eigen::Isometry3d& best = hyps[top[0]].map_T_scan;
  const double same_rad = double(hc.same_pose_deg) / kDegPerRad;
  Eigen::Isometry3d competitors[kMaxRivals];
  uint32_t count = 0;
  for (uint32_t k = 1; k < n && count < kMaxRivals; ++k)
    if (!within_pose(best, hyps[top[k]].map_T_scan, hc.same_pose_m, same_rad))
      competitors[count++] = hyps[top[k]].map_T_scan;
  return scan_disagree_weights(scorer.points, scorer.voxels.size(), scorer.semantic, best, competitors, count,
                               scorer.vc.max_points, configured);
}

// Keeps in top[0, n) (best first) only the hypotheses not within the same-pose tolerance of a better
// kept one; returns how many.
uint32_t AnswerSelector::distinct_of(const PoseHypotheses& hyps, const HypothesisConfig& hc, uint32_t* top,
                                     uint32_t n) const {
  const double same_rad = double(hc.same_pose_deg) / kDegPerRad;
  uint32_t kept = 0;
  for (uint32_t k = 0; k < n; ++k) {
    const Eigen::Isometry3d& b = hyps[top[k]].map_T_scan;
    bool twin = false;
    for (uint32_t j = 0; j < kept && !twin; ++j) {
      twin = within_pose(hyps[top[j]].map_T_scan, b, hc.same_pose_m, same_rad);
    }
    if (!twin) top[kept++] = top[k];
  }
  return kept;
}

// Appends to top[0, n) (best first; nothing when n = 0) the best `turned` fully scored hypotheses not
// within the same-pose tolerance of one in it or appended, whose heading is more than 90 deg from
// top[0]'s, keeping at most `cap` in all; returns the new count.
uint32_t AnswerSelector::add_turned(const PoseHypotheses& hyps, const HypothesisConfig& hc, const uint8_t* full_scored,
                                    uint32_t turned, uint32_t cap, uint32_t* top, uint32_t n) const {
  if (n == 0 || turned == 0 || n >= cap) return n;
  const uint32_t H = hyps.size();
  uint32_t ranked[PoseHypotheses::kMaxHypotheses];
  const uint32_t nr = top_by_score(hyps, H, full_scored, H, ranked);
  const Eigen::Isometry3d& best = hyps[top[0]].map_T_scan;
  const double same_rad = double(hc.same_pose_deg) / kDegPerRad, anywhere = std::numeric_limits<double>::infinity();
  const uint32_t end = std::min(cap, n + turned);
  for (uint32_t k = 0; k < nr && n < end; ++k) {
    const uint32_t h = ranked[k];
    if (within_pose(best, hyps[h].map_T_scan, anywhere, 0.5 * kPi)) continue;  // not turned > 90 deg
    bool twin = false;                                                         // (top[j] == h is within any tolerance)
    for (uint32_t j = 0; j < n && !twin; ++j)
      twin = within_pose(hyps[top[j]].map_T_scan, hyps[h].map_T_scan, hc.same_pose_m, same_rad);
    if (!twin) top[n++] = h;
  }
  return n;
}

// The answer, and as runner-up the best fully scored hypotheses at another place or heading (into
// rival_pose_, at the poses they were scored at): a near-twin of the answer (within same_pose_m and
// same_pose_deg in the bird's-eye view the verification sees) is the same answer, not a rival.
// Returns the answer.
uint32_t AnswerSelector::pick_answer_and_rivals(const PoseHypotheses& hyps, const uint8_t* full_scored,
                                                const HypothesisConfig& hc, uint32_t refined_count) {
  const uint32_t H = hyps.size();
  uint32_t top[PoseHypotheses::kMaxHypotheses];
  const uint32_t nt = top_by_score(hyps, H, full_scored, H, top);
  const uint32_t best = nt > 0 ? top[0] : 0;
  const Eigen::Isometry3d& a = hyps[best].map_T_scan;
  const double same_rad = double(hc.same_pose_deg) / kDegPerRad;
  for (uint32_t k = 1; k < nt && rival_count_ < kMaxRivals; ++k) {
    if (within_pose(a, hyps[top[k]].map_T_scan, hc.same_pose_m, same_rad)) continue;
    rival_pose_[rival_count_++] = scoring_pose_of(top[k], refined_count);
  }
  return best;
}

// The hypotheses to report: the best by verified score (the order found without verification).
void AnswerSelector::rank_for_report(const PoseHypotheses& hyps, bool verify, const uint8_t* full_scored,
                                     AnswerChoice* choice) {
  const uint32_t H = hyps.size();
  uint32_t* shown = choice->rank;
  uint32_t reported = std::min(H, AnswerChoice::kMaxRanked);
  if (verify) reported = top_by_score(hyps, H, nullptr, AnswerChoice::kMaxRanked, shown);
  else
    for (uint32_t k = 0; k < reported; ++k) shown[k] = k;
  choice->ranked = reported;
  for (uint32_t k = 0; k < reported; ++k) choice->fully_verified[k] = verify && full_scored[shown[k]];
}

}  // namespace gsf
