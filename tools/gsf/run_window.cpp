// gsf evaluate --sequence-window N: every scan of the simulator's 10 Hz stretches (sequence 02) through
// Localizer::localize_sequence with window.scans = N (1: one-shot, the same answers as localize()), the
// odometry between consecutive scans from the dataset's poses with noise (--odometry-noise); the window
// restarts at each stretch. Reports success, answered (confident), confident wrong and time per scan,
// overall and in the repetitive zone.
#include <cstdio>
#include <fstream>
#include <vector>

#include "commands.h"
#include "evaluation.h"
#include "gsf/localizer.h"
#include "gsf/map_format.h"
#include "gsf/port/clock.h"
#include "json_writer.h"
#include "run_evaluation.h"
#include "stretch_evaluation.h"
#include "vehicle_modes.h"

namespace gsf::cli {
namespace {

struct WindowRecord {
  uint32_t stretch = 0, index = 0, frame = 0, sequence_index = 0;
  bool in_zone = false;
  std::string status;
  bool ok = false, success = false, answered = false, combined = false, checked = false, contradicted = false;
  PoseError error;
  double confidence = 0, single_confidence = 0, time_ms = 0, window_ms = 0;
  uint32_t window_scans = 0, candidates = 0;
  uint32_t ids[kMaxWindowScans] = {};
  ConfidenceEvidence evidence;
};

struct WindowCounts {
  uint32_t scans = 0, success = 0, answered = 0, wrong = 0, combined = 0, combined_answered = 0;
  void add(const WindowRecord& r) {
    ++scans;
    success += r.success;
    answered += r.answered;
    wrong += r.answered && !r.success;
    combined += r.combined;
    combined_answered += r.combined && r.answered;
  }
};

struct WindowSummary {
  WindowCounts all, zone;
  double median_ms = 0, p95_ms = 0, max_ms = 0;
  // Scans on which the window combined or checked: how many, the median of their window step and of
  // their one-shot part (the same scans, the same moment: a ratio robust to the machine's load).
  uint32_t window_runs = 0;
  double median_window_ms = 0, median_window_one_shot_ms = 0;
};

struct WindowRun {
  const EvalOptions& o;
  Localizer& loc;
  port::ScanSource& src;
  LabelSet& labels;
  port::ScanBuffer& buf;
  const ScanLabelErrors& label_errors;
};

// One scan: odometry from the previous scan of the stretch (none for its first), localize_sequence.
WindowRecord run_window_scan(const WindowRun& t, uint32_t i, bool first, Eigen::Isometry3d* last_truth) {
  WindowRecord rec;
  rec.index = i;
  rec.frame = t.src.frame_id(i);
  Eigen::Isometry3d truth;
  t.src.pose(i, &truth);
  LocalizeResult r;
  const Status rs =
      read_scan(t.src, i, t.buf, t.o.logits, 2000000u + rec.frame, t.labels.config_table(), &t.label_errors);
  const Eigen::Isometry3d odometry =
      first ? Eigen::Isometry3d::Identity() : noisy_odometry(*last_truth, truth, t.o.odometry_noise, t.o.prior.seed, i);
  if (first) t.loc.reset_sequence();
  if (rs == Status::Ok) t.loc.localize_sequence(t.buf.view(), odometry, &r);
  else r.status = rs;
  *last_truth = truth;
  rec.status = to_string(r.status);
  rec.ok = r.status == Status::Ok;
  rec.confidence = rec.ok ? r.confidence : 0.0;
  rec.single_confidence = r.single_confidence;
  rec.answered = rec.ok && r.confident;
  rec.combined = r.window_combined;
  rec.checked = r.window_checked;
  rec.contradicted = r.window_contradicted;
  rec.sequence_index = r.sequence_index;
  rec.window_scans = r.window_scans;
  rec.candidates = r.window_candidates;
  for (uint32_t k = 0; k < kMaxWindowScans; ++k) rec.ids[k] = r.window_ids[k];
  rec.time_ms = double(r.times.total) / 1e6;
  rec.window_ms = double(r.times.window) / 1e6;
  rec.evidence = r.confidence_evidence;
  if (rec.ok) {
    rec.error = pose_error(r.map_frame_T_scan, truth);
    rec.success = is_success(rec.error);
  }
  return rec;
}

WindowSummary summarize_window(const std::vector<WindowRecord>& recs) {
  WindowSummary s;
  std::vector<double> ms;
  for (const WindowRecord& r : recs) {
    s.all.add(r);
    if (r.in_zone) s.zone.add(r);
    ms.push_back(r.time_ms);
  }
  std::vector<double> step, base;
  for (const WindowRecord& r : recs)
    if (r.combined || r.checked || r.candidates > 0) {
      step.push_back(r.window_ms);
      base.push_back(r.time_ms - r.window_ms);
    }
  s.window_runs = static_cast<uint32_t>(step.size());
  if (!step.empty()) {
    s.median_window_ms = percentile(step, 0.5);
    s.median_window_one_shot_ms = percentile(base, 0.5);
  }
  if (!ms.empty()) {
    s.median_ms = percentile(ms, 0.5);
    s.p95_ms = percentile(ms, 0.95);
    s.max_ms = percentile(ms, 1.0);
  }
  return s;
}

void print_window(const WindowSummary& s, uint32_t window, uint32_t stretches, const EvalOptions& o) {
  std::printf("\nsequence window %u: %u stretches, %u scans (sequence %s), odometry noise %.3f\n", window, stretches,
              s.all.scans, o.sequence.c_str(), o.odometry_noise);
  std::printf("%-8s %7s %9s %9s %12s %9s %16s %10s %8s %8s\n", "scans", "count", "success", "answered", "conf. wrong",
              "combined", "combined+answer", "median ms", "p95 ms", "max ms");
  auto row = [&](const char* name, const WindowCounts& c, bool times) {
    const double n = c.scans ? c.scans : 1;
    std::printf("%-8s %7u %8.1f%% %8.1f%% %12u %9u %16u", name, c.scans, 100.0 * c.success / n, 100.0 * c.answered / n,
                c.wrong, c.combined, c.combined_answered);
    if (times) std::printf(" %10.2f %8.2f %8.2f", s.median_ms, s.p95_ms, s.max_ms);
    std::printf("\n");
  };
  row("all", s.all, true);
  row("zone", s.zone, false);
  std::printf("  the window ran on %u scans: median %.2f ms its step, %.2f ms their one-shot part\n", s.window_runs,
              s.median_window_ms, s.median_window_one_shot_ms);
  std::printf(
      "  (success: status Ok within 5 m / 10 deg; answered: confident; conf. wrong: answered beyond 5 m / 10 deg; "
      "combined: the answer is the window's; zone: scans in the repetitive zone; ms: per scan)\n");
}

void write_counts(JsonWriter& j, const char* key, const WindowCounts& c) {
  j.key(key);
  j.begin_object();
  j.field("scans", c.scans);
  j.field("success", c.success);
  j.field("answered", c.answered);
  j.field("confident_wrong", c.wrong);
  j.field("combined", c.combined);
  j.field("combined_answered", c.combined_answered);
  j.end_object();
}

void write_window_record(JsonWriter& j, const WindowRecord& r) {
  j.begin_object();
  j.field("stretch", r.stretch);
  j.field("index", r.index);
  j.field("frame", r.frame);
  j.field("in_zone", r.in_zone);
  j.field("status", r.status);
  j.field("confidence", r.confidence);
  j.field("single_confidence", r.single_confidence);
  j.field("answered", r.answered);
  j.field("success", r.success);
  j.field("combined", r.combined);
  j.field("checked", r.checked);
  j.field("contradicted", r.contradicted);
  j.field("sequence_index", r.sequence_index);
  j.key("window_ids");
  j.begin_array();
  for (uint32_t k = 0; k < r.window_scans && k < kMaxWindowScans; ++k) j.value(r.ids[k]);
  j.end_array();
  j.field("window_candidates", r.candidates);
  j.field("z_rival", r.evidence.z_rival);
  j.field("rival_margin", r.evidence.rival_margin);
  j.field("z_shift", r.evidence.z_shift);
  j.field("z_shift_far", r.evidence.z_shift_far);
  j.field("z_turn", r.evidence.z_turn);
  j.field("inliers", r.evidence.inliers);
  j.field("inlier_share", r.evidence.inlier_share);
  j.field("samples", r.evidence.samples);
  j.field("known_share", r.evidence.known_share);
  j.field("agreement", r.evidence.agreement);
  j.field("translation_error_m", r.ok ? r.error.translation_m : -1.0);
  j.field("rotation_error_deg", r.ok ? r.error.rotation_deg : -1.0);
  j.field("time_ms", r.time_ms);
  j.field("window_ms", r.window_ms);
  j.end_object();
}

void write_window_json(const std::string& path, const EvalOptions& o, const WindowSummary& s,
                       const std::vector<WindowRecord>& recs) {
  JsonWriter j;
  j.begin_object();
  j.field("map", o.map_path);
  j.field("dataset", o.dataset);
  j.field("sequence", o.sequence);
  j.field("mode", "sequence-window");
  j.field("sequence_window", o.sequence_window);
  j.field("odometry_noise", o.odometry_noise);
  j.key("summary");
  j.begin_object();
  write_counts(j, "all", s.all);
  write_counts(j, "zone", s.zone);
  j.field("median_ms", s.median_ms);
  j.field("p95_ms", s.p95_ms);
  j.field("max_ms", s.max_ms);
  j.field("window_runs", s.window_runs);
  j.field("median_window_ms", s.median_window_ms);
  j.field("median_window_one_shot_ms", s.median_window_one_shot_ms);
  j.end_object();
  j.key("scans");
  j.begin_array();
  for (const WindowRecord& r : recs) write_window_record(j, r);
  j.end_array();
  j.end_object();
  std::ofstream f(path);
  f << j.str() << "\n";
}

}  // namespace

int run_window(const EvalOptions& o) {
  StretchEvaluation ev;
  if (const int code = open_stretch_evaluation(o, "--sequence-window", o.sequence_window, &ev)) return code;
  const WindowRun run{o, ev.loc, *ev.src, ev.labels, ev.buf->buffer(), ev.label_errors};
  std::vector<WindowRecord> recs;
  uint32_t stretches = 0;
  for (uint32_t k = 0; k < ev.stretches.size() && (o.limit == 0 || recs.size() < o.limit); ++k, ++stretches) {
    const auto [first, length] = ev.stretches[k];
    Eigen::Isometry3d last_truth = Eigen::Isometry3d::Identity();
    for (uint32_t i = first; i < first + length && i < ev.src->size(); ++i) {
      recs.push_back(run_window_scan(run, i, i == first, &last_truth));
      recs.back().stretch = k;
      recs.back().in_zone = ev.in_zone(i);
    }
    if (o.progress) std::fprintf(stderr, "\r  sequence window: %u / %zu stretches", k + 1, ev.stretches.size());
  }
  if (o.progress) std::fprintf(stderr, "\n");
  const WindowSummary sum = summarize_window(recs);
  print_window(sum, o.sequence_window, stretches, o);
  if (ev.label_errors.rates.any()) std::printf("  labels: %s\n", describe(ev.label_errors).c_str());
  if (!o.json_out.empty()) write_window_json(o.json_out, o, sum, recs);
  return 0;
}

}  // namespace gsf::cli
