// gsf evaluate --mode track: a vehicle's loop over the simulator's 10 Hz stretches (sequence 02). The
// first scan of a stretch, and any scan after a loss, is localized one-shot (with a prior when
// --prior-sigma is given); every other scan is tracked from the last answered pose x the odometry between
// the dataset's poses (with noise). A tracked scan that is not confident is a loss: the same scan is
// localized one-shot (a recovery when that answers).
// gsf evaluate --mode drive: the same stretches through Localizer::localize_next, the library's own loop:
// tracking while the last pose was confident; at a stretch's start and on a loss localize_sequence (the
// window of the last scans localized from scratch) or, with --prior-sigma, the prior.
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <vector>

#include "commands.h"
#include "evaluation.h"
#include "gsf/localizer.h"
#include "gsf/map_format.h"
#include "gsf/port/clock.h"
#include "json_writer.h"
#include "result_json.h"
#include "run_evaluation.h"
#include "stretch_evaluation.h"
#include "vehicle_modes.h"

namespace gsf::cli {
namespace {

constexpr double kTrackTranslation = 0.3;  // m: a tracked pose is precise within this and kTrackRotationDeg
constexpr double kTrackRotationDeg = 1.0;

struct ScanRecord {
  uint32_t stretch = 0, index = 0, frame = 0;
  const char* how = "one-shot";  // one-shot (start or after no answer), track, recovery (one-shot after a loss)
  std::string status;
  bool answered = false, success = false, precise = false, loss = false;
  bool in_zone = false;  // in the simulated world's repetitive zone (meta.json)
  PoseError error;
  Eigen::Vector3d error_in_scan = Eigen::Vector3d::Zero();  // the position error along the true scan's x, y, z
  double confidence = 0, time_ms = 0, track_ms = 0;
  StageMs track_stages;  // of the track() call (voxel, pose = pattern search, refine = ICP, confidence = probes)
  // --mode track: the track() call's pose and evidence, kept through a loss's recovery (was the loss right?)
  bool has_track_attempt = false;
  PoseError attempt_error;
  double attempt_confidence = 0;
  double attempt_from_prediction_m = 0;  // how far the result moved from the prediction (the reach rule's distance)
  ConfidenceEvidence attempt_evidence;
};

struct TrackSummary {
  uint32_t scans = 0, one_shot = 0, tracked = 0, tracked_precise = 0, answered = 0, precise = 0, wrong = 0;
  uint32_t losses = 0, recoveries = 0, lost_scans = 0;
  uint32_t success = 0;  // within 5 m / 10 deg, answered or not
  uint32_t zone_scans = 0, zone_answered = 0, zone_wrong = 0;
  double median_one_shot_ms = 0, median_track_ms = 0, median_scan_ms = 0;
  StageMs median_track_stage;
};

// The loop's state within one stretch.
struct Vehicle {
  bool have_pose = false;
  bool started = false;  // --mode drive: localize_next has seen this stretch's first scan
  Eigen::Isometry3d last_estimate, last_truth;
};

struct TrackRun {
  const EvalOptions& o;
  const MapView& map;
  Localizer& loc;
  port::ScanSource& src;
  LabelSet& labels;
  port::ScanBuffer& buf;
  const ScanLabelErrors& label_errors;  // simulated network errors on the scans' labels (none by default)
};

void judge_scan(const LocalizeResult& r, const Eigen::Isometry3d& truth, ScanRecord* rec) {
  rec->status = to_string(r.status);
  rec->confidence = r.status == Status::Ok ? r.confidence : 0.0;
  rec->answered = r.status == Status::Ok && r.confident;
  if (r.status != Status::Ok) return;
  rec->error = pose_error(r.map_frame_T_scan, truth);
  rec->error_in_scan = truth.linear().transpose() * (r.map_frame_T_scan.translation() - truth.translation());
  rec->success = is_success(rec->error);
  rec->precise = rec->error.translation_m < kTrackTranslation && rec->error.rotation_deg < kTrackRotationDeg;
}

void finish_scan(const LocalizeResult& r, const Eigen::Isometry3d& truth, Vehicle* v, ScanRecord* rec) {
  judge_scan(r, truth, rec);
  v->have_pose = rec->answered;
  v->last_estimate = r.map_frame_T_scan;
  v->last_truth = truth;
}

// One scan of --mode drive: Localizer::localize_next decides (its own pose; the odometry from the
// dataset's poses with noise, none at the stretch's first scan).
ScanRecord drive_scan(const TrackRun& t, uint32_t i, const Eigen::Isometry3d& truth, Vehicle* v, ScanRecord rec,
                      LocalizeResult& r) {
  const bool first = !v->started;
  if (first) t.loc.reset_drive();
  const Eigen::Isometry3d odometry = first
                                         ? Eigen::Isometry3d::Identity()
                                         : noisy_odometry(v->last_truth, truth, t.o.odometry_noise, t.o.prior.seed, i);
  const PositionPrior prior = draw_prior(t.o.prior, truth, i);
  t.loc.localize_next(t.buf.view(), odometry, t.o.prior.enabled ? &prior : nullptr, &r);
  v->started = true;
  rec.how = r.tracked ? "track" : r.track_lost ? "recovery" : "one-shot";
  rec.loss = r.track_lost;
  rec.time_ms = double(r.times.total) / 1e6;
  if (r.tracked) {
    rec.track_ms = rec.time_ms;
    rec.track_stages = stage_ms(r.times);
  }
  finish_scan(r, truth, v, &rec);
  return rec;
}

// One scan of the loop: track when the vehicle has a pose, one-shot otherwise or after a loss.
ScanRecord run_scan(const TrackRun& t, uint32_t i, Vehicle* v) {
  ScanRecord rec;
  rec.index = i;
  rec.frame = t.src.frame_id(i);
  Eigen::Isometry3d truth;
  t.src.pose(i, &truth);
  LocalizeResult r;
  const Status rs =
      read_scan(t.src, i, t.buf, t.o.logits, 2000000u + rec.frame, t.labels.config_table(), &t.label_errors);
  if (rs != Status::Ok) r.status = rs;
  if (rs == Status::Ok && t.o.modes.front() == "drive") return drive_scan(t, i, truth, v, rec, r);
  if (rs == Status::Ok && v->have_pose) {
    const Eigen::Isometry3d predicted = offset_prediction(
        v->last_estimate * noisy_odometry(v->last_truth, truth, t.o.odometry_noise, t.o.prior.seed, i),
        t.o.prediction_offset, t.o.prior.seed, i);
    t.loc.track(t.buf.view(), predicted, &r);
    rec.how = "track";
    rec.track_ms = rec.time_ms = double(r.times.total) / 1e6;
    rec.track_stages = stage_ms(r.times);
    rec.loss = !(r.status == Status::Ok && r.confident);
    if (r.status == Status::Ok) {
      rec.has_track_attempt = true;
      rec.attempt_error = pose_error(r.map_frame_T_scan, truth);
      rec.attempt_confidence = r.confidence;
      rec.attempt_from_prediction_m = (r.map_frame_T_scan.translation() - predicted.translation()).norm();
      rec.attempt_evidence = r.confidence_evidence;
    }
  }
  if (rs == Status::Ok && (!v->have_pose || rec.loss)) {
    const PositionPrior prior = draw_prior(t.o.prior, truth, i);
    if (t.o.prior.enabled) t.loc.localize(t.buf.view(), prior, &r);
    else t.loc.localize(t.buf.view(), &r);
    rec.how = rec.loss ? "recovery" : "one-shot";
    rec.time_ms += double(r.times.total) / 1e6;
  }
  finish_scan(r, truth, v, &rec);
  return rec;
}

TrackSummary summarize_tracking(const std::vector<ScanRecord>& recs) {
  TrackSummary s;
  std::vector<double> one_shot_ms, track_ms, scan_ms, voxel, search, icp, probes;
  for (const ScanRecord& r : recs) {
    ++s.scans;
    const bool tracked = std::string(r.how) == "track";
    s.one_shot += !tracked;
    s.tracked += tracked;
    s.tracked_precise += tracked && r.precise;
    s.answered += r.answered;
    s.success += r.success;
    s.precise += r.answered && r.precise;
    s.wrong += r.answered && !r.success;
    s.losses += r.loss;
    s.recoveries += r.loss && r.answered;
    s.lost_scans += !r.answered;
    s.zone_scans += r.in_zone;
    s.zone_answered += r.in_zone && r.answered;
    s.zone_wrong += r.in_zone && r.answered && !r.success;
    scan_ms.push_back(r.time_ms);
    if (tracked) {
      track_ms.push_back(r.track_ms);
      voxel.push_back(r.track_stages.voxel);
      search.push_back(r.track_stages.pose);
      icp.push_back(r.track_stages.refine);
      probes.push_back(r.track_stages.confidence);
    } else if (!r.loss) one_shot_ms.push_back(r.time_ms);
  }
  s.median_one_shot_ms = one_shot_ms.empty() ? 0 : percentile(one_shot_ms, 0.5);
  s.median_track_ms = track_ms.empty() ? 0 : percentile(track_ms, 0.5);
  s.median_scan_ms = scan_ms.empty() ? 0 : percentile(scan_ms, 0.5);
  if (!track_ms.empty()) {
    s.median_track_stage.voxel = percentile(voxel, 0.5);
    s.median_track_stage.pose = percentile(search, 0.5);
    s.median_track_stage.refine = percentile(icp, 0.5);
    s.median_track_stage.confidence = percentile(probes, 0.5);
  }
  return s;
}

void print_tracking(const TrackSummary& s, uint32_t stretches, const EvalOptions& o) {
  std::printf("\n%s: %u stretches, %u scans (sequence %s), odometry noise %.3f",
              o.modes.front() == "drive" ? "drive (localize_next)" : "tracking", stretches, s.scans, o.sequence.c_str(),
              o.odometry_noise);
  if (o.prior.enabled)
    std::printf(", one-shot with a prior (sigma %.1f m, radius %.1f m)", o.prior.sigma, o.prior.radius);
  std::printf("\n%8s %8s %8s %15s %9s %15s %13s %7s %10s %11s %10s %10s\n", "scans", "one-shot", "tracked",
              "tracked precise", "answered", "answered prec.", "conf. wrong", "losses", "recoveries", "one-shot ms",
              "track ms", "x one-shot");
  const double ratio = s.median_one_shot_ms > 0 ? s.median_track_ms / s.median_one_shot_ms : 0.0;
  std::printf("%8u %8u %8u %14.1f%% %8.1f%% %14.1f%% %13u %7u %10u %11.2f %10.2f %10.2f\n", s.scans, s.one_shot,
              s.tracked, s.tracked ? 100.0 * s.tracked_precise / s.tracked : 0.0,
              s.scans ? 100.0 * s.answered / s.scans : 0.0, s.scans ? 100.0 * s.precise / s.scans : 0.0, s.wrong,
              s.losses, s.recoveries, s.median_one_shot_ms, s.median_track_ms, ratio);
  if (s.zone_scans > 0)
    std::printf("  repetitive zone: %u scans, %u answered (%.1f%%), %u confident wrong\n", s.zone_scans,
                s.zone_answered, 100.0 * s.zone_answered / s.zone_scans, s.zone_wrong);
  std::printf("  track median stage ms: voxel %.2f  search %.2f  icp %.2f  probes %.2f\n", s.median_track_stage.voxel,
              s.median_track_stage.pose, s.median_track_stage.refine, s.median_track_stage.confidence);
  std::printf(
      "  (precise: within %.1f m / %.0f deg of the truth; answered prec.: answered and precise, of all scans; conf. "
      "wrong: answered beyond 5 m / 10 deg; ms: medians per scan)\n",
      kTrackTranslation, kTrackRotationDeg);
}

void write_tracking_json(const std::string& path, const EvalOptions& o, const TrackSummary& s,
                         const std::vector<ScanRecord>& recs) {
  JsonWriter j;
  j.begin_object();
  j.field("map", o.map_path);
  j.field("dataset", o.dataset);
  j.field("sequence", o.sequence);
  j.field("mode", o.modes.front());
  j.field("odometry_noise", o.odometry_noise);
  j.field("prediction_offset", o.prediction_offset);
  j.field("prior_sigma_m", o.prior.enabled ? o.prior.sigma : -1.0);
  j.key("summary");
  j.begin_object();
  j.field("scans", s.scans);
  j.field("one_shot", s.one_shot);
  j.field("tracked", s.tracked);
  j.field("tracked_precise", s.tracked_precise);
  j.field("success", s.success);
  j.field("answered", s.answered);
  j.field("answered_precise", s.precise);
  j.field("confident_wrong", s.wrong);
  j.field("losses", s.losses);
  j.field("recoveries", s.recoveries);
  j.field("zone_scans", s.zone_scans);
  j.field("zone_answered", s.zone_answered);
  j.field("zone_confident_wrong", s.zone_wrong);
  j.field("median_one_shot_ms", s.median_one_shot_ms);
  j.field("median_track_ms", s.median_track_ms);
  j.field("median_scan_ms", s.median_scan_ms);
  write_stage_ms(j, "median_track_stage_ms", s.median_track_stage);
  j.end_object();
  j.key("scans");
  j.begin_array();
  for (const ScanRecord& r : recs) {
    j.begin_object();
    j.field("stretch", r.stretch);
    j.field("index", r.index);
    j.field("frame", r.frame);
    j.field("how", r.how);
    j.field("status", r.status);
    j.field("confidence", r.confidence);
    j.field("answered", r.answered);
    j.field("success", r.success);
    j.field("precise", r.precise);
    j.field("loss", r.loss);
    j.field("in_zone", r.in_zone);
    j.field("translation_error_m", r.status == "Ok" ? r.error.translation_m : -1.0);
    j.field("rotation_error_deg", r.status == "Ok" ? r.error.rotation_deg : -1.0);
    if (r.status == "Ok") {  // forward, left, up of the true scan (a bias shows which way it pulls)
      j.key("error_in_scan_m");
      j.begin_array();
      for (int k = 0; k < 3; ++k) j.value(r.error_in_scan[k]);
      j.end_array();
    }
    j.field("time_ms", r.time_ms);
    if (r.has_track_attempt) {
      j.key("track_attempt");
      j.begin_object();
      j.field("confidence", r.attempt_confidence);
      j.field("translation_error_m", r.attempt_error.translation_m);
      j.field("rotation_error_deg", r.attempt_error.rotation_deg);
      j.field("from_prediction_m", r.attempt_from_prediction_m);
      j.field("z_shift", double(r.attempt_evidence.z_shift));
      j.field("z_turn", double(r.attempt_evidence.z_turn));
      j.field("z_rival", double(r.attempt_evidence.z_rival));
      j.field("agreement", double(r.attempt_evidence.agreement));
      j.field("samples", r.attempt_evidence.samples);
      j.end_object();
    }
    j.end_object();
  }
  j.end_array();
  j.end_object();
  std::ofstream f(path);
  f << j.str() << "\n";
}

}  // namespace

int run_tracking(const EvalOptions& o) {
  StretchEvaluation ev;
  if (const int code = open_stretch_evaluation(o, "--mode track", 0, &ev)) return code;
  const TrackRun run{o, ev.map, ev.loc, *ev.src, ev.labels, ev.buf->buffer(), ev.label_errors};
  std::vector<ScanRecord> recs;
  uint32_t stretches = 0;
  for (uint32_t k = 0; k < ev.stretches.size() && (o.limit == 0 || recs.size() < o.limit); ++k, ++stretches) {
    Vehicle v;
    const auto [first, length] = ev.stretches[k];
    for (uint32_t i = first; i < first + length && i < ev.src->size(); ++i) {
      recs.push_back(run_scan(run, i, &v));
      recs.back().stretch = k;
      recs.back().in_zone = ev.in_zone(i);
    }
    if (o.progress) std::fprintf(stderr, "\r  track: %u / %zu stretches", k + 1, ev.stretches.size());
  }
  if (o.progress) std::fprintf(stderr, "\n");
  const TrackSummary sum = summarize_tracking(recs);
  print_tracking(sum, stretches, o);
  if (ev.label_errors.rates.any()) std::printf("  labels: %s\n", describe(ev.label_errors).c_str());
  if (!o.json_out.empty()) write_tracking_json(o.json_out, o, sum, recs);
  return 0;
}

}  // namespace gsf::cli
