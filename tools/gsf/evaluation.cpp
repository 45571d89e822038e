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

ModeSummary summarize(const std::string& mode, const std::vector<QueryRecord>& records, double default_threshold) {
  ModeSummary s;
  s.mode = mode;
  s.queries = static_cast<uint32_t>(records.size());
  s.default_threshold = default_threshold;
  std::vector<double> times;
  std::vector<double> st[9];
  double t_sum = 0, r_sum = 0;
  for (const auto& r : records) {
    times.push_back(r.time_ms);
    const double v[9] = {r.stages.voxel, r.stages.cluster, r.stages.field, r.stages.triangle, r.stages.match,
                         r.stages.gsf,   r.stages.clique,  r.stages.pose,  r.stages.refine};
    for (int k = 0; k < 9; ++k) st[k].push_back(v[k]);
    if (r.answered) ++s.answered;
    if (r.in_zone) ++s.zone_queries;
    else if (r.near_zone) ++s.near_zone_queries;
    else ++s.elsewhere_queries;
    if (r.success) {
      ++s.successes;
      if (r.in_zone) ++s.zone_successes;
      else if (r.near_zone) ++s.near_zone_successes;
      else ++s.elsewhere_successes;
      t_sum += r.error.translation_m;
      r_sum += r.error.rotation_deg;
    }
  }
  if (s.queries) s.success_rate = double(s.successes) / s.queries;
  if (s.zone_queries) s.zone_success_rate = double(s.zone_successes) / s.zone_queries;
  if (s.near_zone_queries) s.near_zone_success_rate = double(s.near_zone_successes) / s.near_zone_queries;
  if (s.elsewhere_queries) s.elsewhere_success_rate = double(s.elsewhere_successes) / s.elsewhere_queries;
  if (s.successes) {
    s.ate_m = t_sum / s.successes;
    s.are_deg = r_sum / s.successes;
  }
  s.median_ms = percentile(times, 0.5);
  s.p95_ms = percentile(times, 0.95);
  for (double t : times) s.mean_ms += t;
  if (!times.empty()) s.mean_ms /= static_cast<double>(times.size());
  double* ms[9] = {&s.median_stage.voxel,    &s.median_stage.cluster, &s.median_stage.field,
                   &s.median_stage.triangle, &s.median_stage.match,   &s.median_stage.gsf,
                   &s.median_stage.clique,   &s.median_stage.pose,    &s.median_stage.refine};
  for (int k = 0; k < 9; ++k) *ms[k] = percentile(st[k], 0.5);

  // Declining curve: sweep the ambiguity threshold over the answered queries' values.
  std::vector<double> thresholds = {0.0};
  for (const auto& r : records)
    if (r.answered) thresholds.push_back(r.ambiguity);
  thresholds.push_back(1.0);
  std::sort(thresholds.begin(), thresholds.end());
  thresholds.erase(std::unique(thresholds.begin(), thresholds.end()), thresholds.end());
  auto point_at = [&](double th) {
    uint32_t answered = 0, correct = 0;
    for (const auto& r : records)
      if (r.answered && r.ambiguity <= th) {
        ++answered;
        correct += r.success ? 1u : 0u;
      }
    CurvePoint p{th, s.queries ? double(answered) / s.queries : 0.0, answered ? double(correct) / answered : 1.0};
    return p;
  };
  for (double th : thresholds) s.curve.push_back(point_at(th));
  const CurvePoint d = point_at(default_threshold);
  s.precision_at_default = d.precision;
  s.answered_at_default = d.answered;
  s.wrong_answers_at_default = d.answered * (1.0 - d.precision);
  return s;
}

}  // namespace gsf::cli
