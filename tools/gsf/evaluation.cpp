#include "evaluation.h"

#include <algorithm>
#include <cmath>

namespace gsf::cli {

PoseError pose_error(const Eigen::Isometry3d& estimate, const Eigen::Isometry3d& ground_truth) {
  const Eigen::Isometry3d d = estimate.inverse() * ground_truth;
  PoseError e;
  e.translation_m = d.translation().norm();
  const double c = std::clamp((d.rotation().trace() - 1.0) / 2.0, -1.0, 1.0);
  e.rotation_deg = std::acos(c) * 180.0 / M_PI;
  return e;
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const double pos = p * static_cast<double>(v.size() - 1);
  const size_t lo = static_cast<size_t>(std::floor(pos));
  const size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (v[hi] - v[lo]) * (pos - static_cast<double>(lo));
}

int reliability_bin(double confidence) {
  int bin = 0;
  while (bin + 1 < kReliabilityBins && confidence >= double(bin + 1) / kReliabilityBins) ++bin;
  return bin;
}

Calibration calibrate(const std::vector<Outcome>& outcomes) {
  Calibration c;
  std::array<double, kReliabilityBins> confidence_sum{}, success_sum{};
  for (const Outcome& o : outcomes) {
    const int b = reliability_bin(o.confidence);
    ++c.bins[b].count;
    confidence_sum[b] += o.confidence;
    success_sum[b] += o.success ? 1.0 : 0.0;
    const double miss = o.confidence - (o.success ? 1.0 : 0.0);
    c.brier += miss * miss;
  }
  c.queries = static_cast<uint32_t>(outcomes.size());
  if (c.queries) c.brier /= c.queries;
  for (int b = 0; b < kReliabilityBins; ++b) {
    ReliabilityBin& bin = c.bins[b];
    bin.lo = double(b) / kReliabilityBins;
    bin.hi = double(b + 1) / kReliabilityBins;
    if (bin.count == 0) {
      bin.mean_confidence = bin.success_rate = std::nan("");
      continue;
    }
    bin.mean_confidence = confidence_sum[b] / bin.count;
    bin.success_rate = success_sum[b] / bin.count;
    c.ece += double(bin.count) / c.queries * std::fabs(bin.success_rate - bin.mean_confidence);
  }
  return c;
}

RuleOutcome rule_outcome(const std::vector<QueryRecord>& records) {
  RuleOutcome o;
  for (const QueryRecord& r : records) {
    o.answered += r.answered ? 1u : 0u;
    o.wrong += r.answered && !r.success ? 1u : 0u;
    o.declined_right += r.success && !r.answered ? 1u : 0u;
  }
  if (!records.empty()) o.answered_share = double(o.answered) / records.size();
  if (o.answered) o.precision = double(o.answered - o.wrong) / o.answered;
  return o;
}

namespace {

// Success counts by region, ATE / ARE over the successes.
void summarize_success(const std::vector<QueryRecord>& records, ModeSummary* s) {
  double t_sum = 0, r_sum = 0;
  for (const auto& r : records) {
    s->with_pose += r.has_pose ? 1u : 0u;
    uint32_t* region_queries = r.in_zone     ? &s->zone_queries
                               : r.near_zone ? &s->near_zone_queries
                                             : &s->elsewhere_queries;
    uint32_t* region_successes = r.in_zone     ? &s->zone_successes
                                 : r.near_zone ? &s->near_zone_successes
                                               : &s->elsewhere_successes;
    ++*region_queries;
    if (!r.success) continue;
    ++s->successes;
    ++*region_successes;
    t_sum += r.error.translation_m;
    r_sum += r.error.rotation_deg;
  }
  auto rate = [](uint32_t k, uint32_t n) { return n ? double(k) / n : 0.0; };
  s->success_rate = rate(s->successes, s->queries);
  s->zone_success_rate = rate(s->zone_successes, s->zone_queries);
  s->near_zone_success_rate = rate(s->near_zone_successes, s->near_zone_queries);
  s->elsewhere_success_rate = rate(s->elsewhere_successes, s->elsewhere_queries);
  if (s->successes) {
    s->ate_m = t_sum / s->successes;
    s->are_deg = r_sum / s->successes;
  }
}

// Median / p95 / mean time per query and the median of each stage.
void summarize_times(const std::vector<QueryRecord>& records, ModeSummary* s) {
  std::vector<double> times;
  std::vector<double> st[10];
  for (const auto& r : records) {
    times.push_back(r.time_ms);
    const double v[10] = {r.stages.voxel, r.stages.cluster, r.stages.field, r.stages.triangle,   r.stages.match,
                          r.stages.gsf,   r.stages.clique,  r.stages.pose,  r.stages.confidence, r.stages.refine};
    for (int k = 0; k < 10; ++k) st[k].push_back(v[k]);
  }
  s->median_ms = percentile(times, 0.5);
  s->p95_ms = percentile(times, 0.95);
  for (double t : times) s->mean_ms += t;
  if (!times.empty()) s->mean_ms /= static_cast<double>(times.size());
  double* ms[10] = {&s->median_stage.voxel,    &s->median_stage.cluster, &s->median_stage.field,
                    &s->median_stage.triangle, &s->median_stage.match,   &s->median_stage.gsf,
                    &s->median_stage.clique,   &s->median_stage.pose,    &s->median_stage.confidence,
                    &s->median_stage.refine};
  for (int k = 0; k < 10; ++k) *ms[k] = percentile(st[k], 0.5);
}

// Precision against share answered when answering the queries with a pose and confidence >= t, for t
// = 0, every query's confidence, and 1.
std::vector<CurvePoint> precision_curve(const std::vector<QueryRecord>& records) {
  std::vector<double> thresholds = {0.0, 1.0};
  for (const auto& r : records)
    if (r.has_pose) thresholds.push_back(r.confidence);
  std::sort(thresholds.begin(), thresholds.end());
  thresholds.erase(std::unique(thresholds.begin(), thresholds.end()), thresholds.end());
  std::vector<CurvePoint> curve;
  for (double t : thresholds) {
    uint32_t answered = 0, right = 0;
    for (const auto& r : records)
      if (r.has_pose && r.confidence >= t) {
        ++answered;
        right += r.success ? 1u : 0u;
      }
    curve.push_back(
        {t, records.empty() ? 0.0 : double(answered) / records.size(), answered ? double(right) / answered : 1.0});
  }
  return curve;
}

}  // namespace

ModeSummary summarize(const std::string& mode, const std::vector<QueryRecord>& records, double min_confidence) {
  ModeSummary s;
  s.mode = mode;
  s.queries = static_cast<uint32_t>(records.size());
  s.min_confidence = min_confidence;
  summarize_success(records, &s);
  summarize_times(records, &s);
  s.rule = rule_outcome(records);
  std::vector<Outcome> outcomes;
  for (const auto& r : records) outcomes.push_back({r.has_pose ? r.confidence : 0.0, r.success});
  s.calibration = calibrate(outcomes);
  s.curve = precision_curve(records);
  return s;
}

}  // namespace gsf::cli
