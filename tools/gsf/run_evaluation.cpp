#include "run_evaluation.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>

#include "baselines/scan_context.h"
#include "commands.h"
#include "evaluation.h"
#include "gsf/detail/semantic_grid.h"
#include "gsf/localizer.h"
#include "gsf/map_format.h"
#include "gsf/port/clock.h"
#include "gsf/semantic_classes.h"
#include "json_writer.h"
#include "reliability_svg.h"
#include "result_json.h"
#include "svg.h"

namespace gsf::cli {
namespace {

double ms(uint64_t ns) { return double(ns) / 1e6; }

// A query instance for the correspondence picture: centroid in the scan frame and dense class.
struct PictureInstance {
  float xyz[3];
  uint8_t label;
};

struct ModeRun {
  std::string mode;
  std::vector<QueryRecord> records;
  std::vector<std::vector<Localizer::Correspondence>> corr;  // per query (for the figure)
  std::vector<std::vector<PictureInstance>> instances;       // per query of a localizer mode (for the figure)
  uint64_t workspace_bytes = 0;
};

// The library's per-query counts: where candidates were dropped, what the hypotheses were.
void write_diagnostics(JsonWriter& j, const QueryRecord& r) {
  QueryTruth t;
  t.truth = r.truth_local;
  t.true_correspondences = r.true_correspondences;
  t.repeatable_instances = r.repeatable_instances;
  t.answer_repeatable_instances = r.answer_repeatable_instances;
  t.answer_layer_instances = r.answer_layer_instances;
  t.truth_verified_score = r.truth_verified_score;
  t.truth_known_share = r.truth_known_share;
  t.true_pairs = &r.true_pairs;
  write_result_diagnostics(j, r.result, &t);
}

// The decision rule's numbers and the confidence's reliability bins, into the mode's summary object.
void write_rule_and_calibration(JsonWriter& j, const ModeSummary& s) {
  j.field("min_confidence", s.min_confidence);
  j.field("precision_at_rule", s.rule.precision);
  j.field("answered_at_rule", s.rule.answered_share);
  j.field("wrong_at_rule", s.rule.wrong);
  j.field("declined_right", s.rule.declined_right);
  j.field("ece", s.calibration.ece);
  j.field("brier", s.calibration.brier);
  j.key("reliability");
  j.begin_array();
  for (const ReliabilityBin& b : s.calibration.bins) {
    j.begin_object();
    j.field("lo", b.lo);
    j.field("hi", b.hi);
    j.field("count", b.count);
    j.field("mean_confidence", b.mean_confidence);  // null when empty
    j.field("success_rate", b.success_rate);
    j.end_object();
  }
  j.end_array();
  j.key("precision_curve");  // answer if the query has a pose and confidence >= threshold
  j.begin_array();
  for (const auto& p : s.curve) {
    j.begin_object();
    j.field("threshold", p.threshold);
    j.field("answered", p.answered);
    j.field("precision", p.precision);
    j.end_object();
  }
  j.end_array();
}

void write_summary_json(JsonWriter& j, const ModeSummary& s, uint64_t workspace_bytes) {
  j.key("summary");
  j.begin_object();
  j.field("queries", s.queries);
  j.field("with_pose", s.with_pose);
  j.field("answered", s.rule.answered);
  j.field("successes", s.successes);
  j.field("success_rate", s.success_rate);
  j.field("zone_queries", s.zone_queries);
  j.field("zone_success_rate", s.zone_success_rate);
  j.field("near_zone_queries", s.near_zone_queries);
  j.field("near_zone_success_rate", s.near_zone_success_rate);
  j.field("elsewhere_queries", s.elsewhere_queries);
  j.field("elsewhere_success_rate", s.elsewhere_success_rate);
  j.field("ate_m", s.ate_m);
  j.field("are_deg", s.are_deg);
  j.field("median_ms", s.median_ms);
  j.field("p95_ms", s.p95_ms);
  j.field("mean_ms", s.mean_ms);
  j.field("time_ratio_to_instance", s.time_ratio_to_gsf_off);
  j.field("workspace_bytes", static_cast<unsigned long long>(workspace_bytes));
  write_stage_ms(j, "median_stage_ms", s.median_stage);
  write_rule_and_calibration(j, s);
  j.end_object();
}

void write_query_json(JsonWriter& j, const QueryRecord& r, bool diagnostics) {
  j.begin_object();
  j.field("index", r.index);
  j.field("frame", r.frame);
  j.field("status", r.status);
  j.field("confidence", r.confidence);
  j.field("answered", r.answered);  // the decision rule: status Ok and confident
  j.field("success", r.success);
  j.field("in_zone", r.in_zone);
  j.field("near_zone", r.near_zone);
  j.field("translation_error_m", r.has_pose ? r.error.translation_m : -1.0);
  j.field("rotation_error_deg", r.has_pose ? r.error.rotation_deg : -1.0);
  j.field("time_ms", r.time_ms);
  j.field("inliers", r.inliers);
  if (r.has_pose) write_pose(j, "pose", r.estimate);  // the map's frame (the dataset's)
  if (diagnostics) write_diagnostics(j, r);
  j.end_object();
}

// The simulated network errors the query scans' labels carried (none: all rates 0).
void write_label_errors_json(JsonWriter& j, const ScanLabelErrors& e) {
  j.key("label_errors");
  j.begin_object();
  j.field("label_noise", static_cast<double>(e.rates.label_noise));
  j.field("object_confusion", static_cast<double>(e.rates.object_confusion));
  j.field("thin_miss", static_cast<double>(e.rates.thin_miss));
  j.field("noise_seed", static_cast<unsigned long long>(e.noise_seed));
  j.field("label_space", label_errors::label_space_name(e.space));
  j.end_object();
}

void write_json(const std::string& path, const EvalOptions& o, const MapView& map, const std::vector<ModeRun>& runs,
                const std::vector<ModeSummary>& sums, const Meta& meta, const ScanLabelErrors& errors) {
  JsonWriter j;
  j.begin_object();
  j.field("map", o.map_path);
  j.field("dataset", o.dataset);
  j.field("sequence", o.sequence);
  j.field("map_bytes", static_cast<unsigned long long>(map.total_bytes));
  j.field("map_frame", map.georef.frame);
  j.key("map_origin");
  j.begin_array();
  for (double o : map.georef.origin) j.exact(o);
  j.end_array();
  j.field("road_length_m", map.counts.road_length_m);
  j.field("map_bytes_per_km",
          map.counts.road_length_m > 0 ? map.total_bytes / (map.counts.road_length_m / 1000.0) : 0.0);
  j.field("map_instances", map.counts.instances);
  j.field("map_triangles", map.counts.triangles);
  j.field("success_translation_m", kSuccessTranslation);
  j.field("success_rotation_deg", kSuccessRotationDeg);
  j.field("zone_type", meta.zone_type);
  j.field("cue_density", static_cast<double>(meta.cue_density));
  write_label_errors_json(j, errors);
  if (o.prior.enabled) {
    j.key("prior");  // a position prior drawn around each query's truth (vehicle_modes.h draw_prior)
    j.begin_object();
    j.field("sigma_m", o.prior.sigma);
    j.field("bias_m", o.prior.bias);
    j.field("radius_m", o.prior.radius);
    j.field("heading_tolerance_deg", o.prior.heading_tolerance_deg);
    j.field("seed", static_cast<unsigned long long>(o.prior.seed));
    j.end_object();
  }
  j.key("modes");
  j.begin_object();
  for (size_t m = 0; m < runs.size(); ++m) {
    j.key(runs[m].mode);
    j.begin_object();
    write_summary_json(j, sums[m], runs[m].workspace_bytes);
    j.key("queries");
    j.begin_array();
    for (const auto& r : runs[m].records) write_query_json(j, r, runs[m].mode != "scan-context");
    j.end_array();
    j.end_object();
  }
  j.end_object();
  j.end_object();
  std::ofstream f(path);
  f << j.str() << "\n";
}

// The reliability diagram of the localizer modes (Scan Context's confidence is only a stand-in).
void write_reliability_svg(const EvalOptions& o, const std::vector<ModeSummary>& sums,
                           std::vector<std::string>* written) {
  std::vector<ModeSummary> shown;
  for (const ModeSummary& s : sums)
    if (s.mode != "scan-context") shown.push_back(s);
  const std::string path = o.svg_dir + "/reliability.svg";
  if (!shown.empty() && save_reliability_svg(path, shown, shown[0].min_confidence)) written->push_back(path);
}

// Pictures' colours for a query's outcome.
const char* const kRight = "#1a9850";
const char* const kWrong = "#d73027";
const char* const kNoPose = "#999999";
constexpr double kCliqueWidth = 4.0;

// A bounding box in metres.
struct WorldBox {
  double min_x = 1e300, min_y = 1e300, max_x = -1e300, max_y = -1e300;
  void add(double x, double y) {
    min_x = std::min(min_x, x);
    max_x = std::max(max_x, x);
    min_y = std::min(min_y, y);
    max_y = std::max(max_y, y);
  }
  bool contains(double x, double y) const { return x >= min_x && x <= max_x && y >= min_y && y <= max_y; }
};

// Legend rows for the classes of `counts` (per dense class), each drawn by `swatch_of` in its colour.
std::vector<LegendEntry> class_legend(const std::vector<uint32_t>& counts,
                                      const std::function<LegendEntry(const std::string&, const std::string&)>& row) {
  std::vector<LegendEntry> rows;
  for (int c = 0; c < kNumClasses; ++c)
    if (counts[c] > 0)
      rows.push_back(row(class_colour(c), std::string(class_name(c)) + " (" + std::to_string(counts[c]) + ")"));
  return rows;
}

// Two legends beside a map of w x h pixels: to the right of it, stacked, or under it side by side (below
// the scale bar) when the map is much wider than tall.
void draw_legends(SvgPicture& svg, double w, double h, const std::vector<LegendEntry>& first,
                  const std::string& first_title, const std::vector<LegendEntry>& second,
                  const std::string& second_title) {
  if (w > 2 * h) {
    const SvgPicture::Box a = draw_legend(svg, 0, h + 46, first, first_title);
    draw_legend(svg, a.max_x + 16, h + 46, second, second_title);
  } else {
    const SvgPicture::Box a = draw_legend(svg, w + 16, 0, first, first_title);
    draw_legend(svg, w + 16, a.max_y + 12, second, second_title);
  }
}

// The title (bold) and a subtitle above a picture whose content starts at y = 0.
void draw_title(SvgPicture& svg, const std::string& title, const std::string& subtitle) {
  svg.text(0, -32, title, 16, "start", 0, "#222", true);
  svg.text(0, -12, subtitle, 12, "start", 0, "#444");
}

// Map instances by class, and each query of the shown mode at its true position coloured by its outcome
// (filled: answered under the decision rule, ring: declined), a wrong pose joined to where it was put.
void write_map_trajectory_svg(const EvalOptions& o, const MapView& map, const ModeRun& shown,
                              std::vector<std::string>* written) {
  WorldBox box;
  for (uint32_t i = 0; i < map.counts.instances; ++i)
    box.add(map.instances[i].centroid[0], map.instances[i].centroid[1]);
  std::vector<Eigen::Vector3d> estimate(shown.records.size());
  for (size_t q = 0; q < shown.records.size(); ++q) {
    const QueryRecord& r = shown.records[q];
    box.add(r.truth_local.translation().x(), r.truth_local.translation().y());
    estimate[q] = to_map_local(map.georef, r.estimate).translation();  // map-local, like the map's instances
    if (r.has_pose) box.add(estimate[q].x(), estimate[q].y());
  }
  if (box.min_x > box.max_x) return;
  const MapProjection p = fit_projection(box.min_x - 15, box.min_y - 15, box.max_x + 15, box.max_y + 15, 1400, 1100);
  const double w = p.px(box.max_x + 15), h = p.py(box.min_y - 15);
  SvgPicture svg;
  svg.rect(0, 0, w, h, "#fcfcfc", 1.0, "#bbbbbb");
  std::vector<uint32_t> classes(kNumClasses, 0);
  for (uint32_t i = 0; i < map.counts.instances; ++i) {
    const auto& m = map.instances[i];
    if (m.label < kNumClasses) ++classes[m.label];
    svg.circle(p.px(m.centroid[0]), p.py(m.centroid[1]), 2.2, class_colour(m.label), 0.85);
  }
  uint32_t count[2][3] = {};                           // [answered][right, wrong, no pose]
  for (size_t q = 0; q < shown.records.size(); ++q) {  // wrong poses first, under the markers
    const QueryRecord& r = shown.records[q];
    if (r.has_pose && !r.success)
      svg.line(p.px(r.truth_local.translation().x()), p.py(r.truth_local.translation().y()), p.px(estimate[q].x()),
               p.py(estimate[q].y()), kWrong, 1.2, "4 3", 0.8);
  }
  for (const QueryRecord& r : shown.records) {
    const std::string colour = r.success ? kRight : r.has_pose ? kWrong : kNoPose;
    ++count[r.answered][r.success ? 0 : r.has_pose ? 1 : 2];
    const double x = p.px(r.truth_local.translation().x()), y = p.py(r.truth_local.translation().y());
    if (r.answered) svg.circle(x, y, 4.5, colour, 0.95, "#ffffff", 0.8);
    else svg.circle(x, y, 4, "#ffffff", 1.0, colour, 2);
  }
  char sub[300];
  std::snprintf(
      sub, sizeof(sub),
      "%zu queries of mode %s at their true positions: %u right (t < 5 m, r < 10 deg), %u wrong, %u without a "
      "pose; %u answered (confident); %u in the repetitive zone",
      shown.records.size(), shown.mode.c_str(), count[0][0] + count[1][0], count[0][1] + count[1][1], count[0][2],
      count[1][0] + count[1][1],
      static_cast<unsigned>(
          std::count_if(shown.records.begin(), shown.records.end(), [](const QueryRecord& r) { return r.in_zone; })));
  draw_title(svg, "Map and query drive (bird's-eye, north up)", sub);
  // The outcomes that occur, with their counts (filled: answered, ring: declined).
  std::vector<LegendEntry> outcomes;
  const char* const names[3] = {"right pose", "wrong pose", "no pose"};
  const char* const colours[3] = {kRight, kWrong, kNoPose};
  for (int k = 0; k < 3; ++k)
    for (int a = 1; a >= 0; --a) {
      if (count[a][k] == 0) continue;
      const std::string c = colours[k];
      outcomes.push_back({[c, a](SvgPicture& s, double cx, double cy) {
                            if (a) s.circle(cx, cy, 4.5, c, 0.95, "#ffffff", 0.8);
                            else s.circle(cx, cy, 4, "#ffffff", 1.0, c, 2);
                          },
                          std::string(names[k]) +
                              (k == 2 ? ""
                               : a    ? ", answered"
                                      : ", declined (not confident)") +
                              " (" + std::to_string(count[a][k]) + ")"});
    }
  if (count[0][1] + count[1][1] > 0)
    outcomes.push_back(legend_line(kWrong, 1.2, "wrong pose: to where it was put", "4 3", 0.8));
  draw_legends(svg, w, h,
               class_legend(classes, [](const std::string& c,
                                        const std::string& label) { return legend_dot(c, 3, label, 0.85); }),
               "map instances by class", outcomes, "queries (" + shown.mode + ")");
  draw_scale_bar(svg, 0, h + 14, p.scale);
  const std::string path = o.svg_dir + "/map_trajectory.svg";
  if (svg.save(path)) written->push_back(path);
}

// A query instance's centroid (scan frame) placed by `place`.
Eigen::Vector3d placed_at(const Eigen::Isometry3d& place, const float* xyz) {
  return place * Eigen::Vector3d(xyz[0], xyz[1], xyz[2]);
}

// Each correspondence judged by the ground truth: true when the pair is within 2 m under the true pose.
std::vector<bool> judge_correspondences(const MapView& map, const QueryRecord& r,
                                        const std::vector<Localizer::Correspondence>& corr) {
  std::vector<bool> truthful(corr.size());
  for (size_t k = 0; k < corr.size(); ++k) {
    const float* m = map.instances[corr[k].map_instance].centroid;
    const Eigen::Vector3d qt =
        r.truth_local * Eigen::Vector3d(corr[k].query_xyz[0], corr[k].query_xyz[1], corr[k].query_xyz[2]);
    truthful[k] = (qt - Eigen::Vector3d(m[0], m[1], m[2])).norm() < 2.0;
  }
  return truthful;
}

// What the correspondence picture shows, with a 12 m margin: both poses, the placed query instances and
// both ends of every pair.
WorldBox correspondence_box(const MapView& map, const QueryRecord& r, const Eigen::Isometry3d& place,
                            const std::vector<PictureInstance>& inst,
                            const std::vector<Localizer::Correspondence>& corr) {
  WorldBox box;
  box.add(place.translation().x(), place.translation().y());
  box.add(r.truth_local.translation().x(), r.truth_local.translation().y());
  for (const auto& i : inst) box.add(placed_at(place, i.xyz).x(), placed_at(place, i.xyz).y());
  for (const auto& c : corr) {
    const float* m = map.instances[c.map_instance].centroid;
    box.add(m[0], m[1]);
    box.add(placed_at(place, c.query_xyz).x(), placed_at(place, c.query_xyz).y());
  }
  box.min_x -= 12, box.min_y -= 12, box.max_x += 12, box.max_y += 12;
  return box;
}

// The map's instances inside the box (dots) and the query's placed instances (rings); *classes counts
// the instances drawn of each dense class.
void draw_instance_layers(SvgPicture& svg, const MapProjection& p, const WorldBox& box, const MapView& map,
                          const Eigen::Isometry3d& place, const std::vector<PictureInstance>& inst,
                          std::vector<uint32_t>* classes) {
  for (uint32_t i = 0; i < map.counts.instances; ++i) {
    const auto& m = map.instances[i];
    if (!box.contains(m.centroid[0], m.centroid[1])) continue;
    if (m.label < kNumClasses) ++(*classes)[m.label];
    svg.circle(p.px(m.centroid[0]), p.py(m.centroid[1]), 3.5, class_colour(m.label), 0.5);
  }
  for (const auto& i : inst) {
    const Eigen::Vector3d v = placed_at(place, i.xyz);
    if (i.label < kNumClasses) ++(*classes)[i.label];
    svg.circle(p.px(v.x()), p.py(v.y()), 6, "none", 1.0, class_colour(i.label), 1.8);
  }
}

// The estimated pose (or the true one the instances are placed at): a dot with the heading; the true
// pose: a cross.
void draw_pose_marks(SvgPicture& svg, const MapProjection& p, const Eigen::Isometry3d& place,
                     const Eigen::Isometry3d& truth) {
  const Eigen::Vector3d o0 = place.translation(), o1 = place * Eigen::Vector3d(8, 0, 0);
  svg.line(p.px(o0.x()), p.py(o0.y()), p.px(o1.x()), p.py(o1.y()), "#000000", 2.5);
  svg.circle(p.px(o0.x()), p.py(o0.y()), 5.5, "#000000");
  const Eigen::Vector3d t = truth.translation();
  svg.line(p.px(t.x()) - 8, p.py(t.y()) - 8, p.px(t.x()) + 8, p.py(t.y()) + 8, kRight, 2.5);
  svg.line(p.px(t.x()) - 8, p.py(t.y()) + 8, p.px(t.x()) + 8, p.py(t.y()) - 8, kRight, 2.5);
}

// Each pair a line from the placed query instance to its map instance. False pairs outside the clique
// first (thin, faint: a lattice has hundreds), then true ones, then the clique's (thick). Round caps: a
// true pair under a right pose is a line of a metre or less, a green dash inside its query ring.
void draw_correspondence_lines(SvgPicture& svg, const MapProjection& p, const MapView& map,
                               const Eigen::Isometry3d& place, const std::vector<Localizer::Correspondence>& corr,
                               const std::vector<bool>& truthful) {
  for (int pass = 0; pass < 3; ++pass)
    for (size_t k = 0; k < corr.size(); ++k) {
      const int layer = corr[k].in_clique ? 2 : truthful[k] ? 1 : 0;
      if (layer != pass) continue;
      const Eigen::Vector3d a = placed_at(place, corr[k].query_xyz);
      const float* m = map.instances[corr[k].map_instance].centroid;
      svg.line(p.px(a.x()), p.py(a.y()), p.px(m[0]), p.py(m[1]), truthful[k] ? kRight : kWrong,
               layer == 2   ? kCliqueWidth
               : layer == 1 ? 2.0
                            : 0.7,
               "", layer == 0 ? 0.4 : 0.95, true);
    }
}

// The picture's title and subtitle: the pairs (true, false, in the clique) and the outcome.
void draw_correspondence_title(SvgPicture& svg, const ModeRun& run, const QueryRecord& r,
                               const std::vector<Localizer::Correspondence>& corr, const std::vector<bool>& truthful) {
  uint32_t n_true = 0, n_clique = 0, clique_true = 0;
  for (size_t k = 0; k < corr.size(); ++k) {
    n_true += truthful[k];
    n_clique += corr[k].in_clique;
    clique_true += corr[k].in_clique && truthful[k];
  }
  char title[200], sub[300];
  std::snprintf(title, sizeof(title), "Correspondences of query frame %u, mode %s: the query's instances over the map",
                r.frame, run.mode.c_str());
  char outcome[120];
  if (r.has_pose)
    std::snprintf(outcome, sizeof(outcome), "%s pose (%.2f m, %.2f deg off): instances placed at the estimated pose",
                  r.success ? "right" : "wrong", r.error.translation_m, r.error.rotation_deg);
  else std::snprintf(outcome, sizeof(outcome), "no pose: instances placed at the true pose");
  std::snprintf(sub, sizeof(sub), "%zu correspondences, %u true and %zu false; clique of %u, %u of them true; %s%s",
                corr.size(), n_true, corr.size() - n_true, n_clique, clique_true, outcome,
                r.in_zone ? "; in the repetitive zone" : "");
  draw_title(svg, title, sub);
}

// The legends: the classes drawn (map dot, query ring), then the kinds of line and the pose marks.
void draw_correspondence_legends(SvgPicture& svg, double w, double h, const std::vector<uint32_t>& classes,
                                 bool has_pose) {
  draw_legends(svg, w, h,
               class_legend(classes,
                            [](const std::string& c, const std::string& label) {
                              return LegendEntry{[c](SvgPicture& s, double cx, double cy) {
                                                   s.circle(cx - 6, cy, 3.5, c, 0.5);
                                                   s.circle(cx + 6, cy, 5, "none", 1.0, c, 1.8);
                                                 },
                                                 label};
                            }),
               "classes: map instance (dot), query (ring)",
               {legend_line(kRight, 2.0, "true: the pair is < 2 m apart under the true pose", "", 0.95),
                legend_line(kWrong, 0.7, "false (thin, faint outside the clique)", "", 0.6),
                legend_line(kRight, kCliqueWidth, "thick: in the clique (green true, red false)", "", 0.95),
                {[](SvgPicture& s, double cx, double cy) {
                   s.line(cx, cy, cx + 10, cy, "#000000", 2.5);
                   s.circle(cx - 2, cy, 5.5, "#000000");
                 },
                 has_pose ? "estimated pose and heading" : "true pose (no estimate)"},
                legend_cross(kRight, 7, "true pose", 2.5)},
               "correspondences");
}

// One query's correspondences in one mode: its instances placed at the mode's estimated pose (the true
// pose when it has none) over the map's instances, each correspondence a line from the placed query
// instance to its map instance, green when the ground truth agrees (the pair is within 2 m under the true
// pose), red when not, thick when in the clique. True pairs under a right pose are short green lines.
void write_correspondence_svg(const EvalOptions& o, const MapView& map, const ModeRun& run, size_t q,
                              std::vector<std::string>* written) {
  const QueryRecord& r = run.records[q];
  const std::vector<Localizer::Correspondence>& corr = run.corr[q];
  const std::vector<PictureInstance> none;
  const std::vector<PictureInstance>& inst = q < run.instances.size() ? run.instances[q] : none;
  const Eigen::Isometry3d place = r.has_pose ? r.result.map_T_scan : r.truth_local;
  const std::vector<bool> truthful = judge_correspondences(map, r, corr);
  const WorldBox box = correspondence_box(map, r, place, inst, corr);
  const MapProjection p = fit_projection(box.min_x, box.min_y, box.max_x, box.max_y, 1400, 850);
  const double w = p.px(box.max_x), h = p.py(box.min_y);
  SvgPicture svg;
  svg.rect(0, 0, w, h, "#fcfcfc", 1.0, "#bbbbbb");
  std::vector<uint32_t> classes(kNumClasses, 0);
  draw_instance_layers(svg, p, box, map, place, inst, &classes);
  draw_pose_marks(svg, p, place, r.truth_local);
  draw_correspondence_lines(svg, p, map, place, corr, truthful);
  draw_correspondence_title(svg, run, r, corr, truthful);
  draw_correspondence_legends(svg, w, h, classes, r.has_pose);
  draw_scale_bar(svg, 0, h + 14, p.scale);
  const std::string path = o.svg_dir + "/correspondences_" + run.mode + ".svg";
  if (svg.save(path)) written->push_back(path);
}

// Correspondences of instance-only and GSF for one repetitive-zone query (paper Fig. 3): one where GSF
// succeeds and instance-only fails if there is one, else the first zone query.
void write_correspondence_svgs(const EvalOptions& o, const MapView& map, const ModeRun& inst, const ModeRun& gsf,
                               std::vector<std::string>* written) {
  int pick = -1;
  for (size_t q = 0; q < gsf.records.size(); ++q)
    if (gsf.records[q].in_zone && gsf.records[q].success && !inst.records[q].success) {
      pick = int(q);
      break;
    }
  for (size_t q = 0; q < gsf.records.size() && pick < 0; ++q)
    if (gsf.records[q].in_zone) pick = int(q);
  if (pick < 0) return;
  for (const ModeRun* run : {&inst, &gsf}) write_correspondence_svg(o, map, *run, size_t(pick), written);
}

// Each written SVG as a PNG beside it (rsvg-convert, librsvg2-bin); false if any could not be written.
bool write_pngs(const std::vector<std::string>& svgs) {
  const std::string rsvg = find_rsvg_convert();
  if (rsvg.empty()) {
    std::fprintf(stderr,
                 "gsf evaluate: --png: rsvg-convert not found on PATH (Debian: apt-get install librsvg2-bin); wrote "
                 "the SVGs only\n");
    return false;
  }
  bool ok = true;
  for (const std::string& svg : svgs) {
    std::string err;
    if (!svg_to_png(rsvg, svg, png_path_for(svg), &err)) {
      std::fprintf(stderr, "gsf evaluate: --png: %s\n", err.c_str());
      ok = false;
    }
  }
  return ok;
}

// The pictures (and with --png their PNGs); false if a PNG could not be written.
bool write_svgs(const EvalOptions& o, const MapView& map, const std::vector<ModeRun>& runs,
                const std::vector<ModeSummary>& sums) {
  std::filesystem::create_directories(o.svg_dir);
  std::vector<std::string> written;
  write_reliability_svg(o, sums, &written);
  const ModeRun* gsf = nullptr;
  const ModeRun* inst = nullptr;
  for (const auto& r : runs) {
    if (r.mode == "gsf") gsf = &r;
    if (r.mode == "instance") inst = &r;
  }
  const ModeRun* shown = gsf ? gsf : (runs.empty() ? nullptr : &runs[0]);
  if (shown) write_map_trajectory_svg(o, map, *shown, &written);
  if (gsf && inst) write_correspondence_svgs(o, map, *inst, *gsf, &written);
  return !o.png || write_pngs(written);
}

// One localizer mode: its config, workspace and localizer (the modes run interleaved, query by query).
struct LocalizerMode {
  size_t run;
  bool without_prior = false;  // the "-one-shot" twin of a mode (--one-shot-too)
  LocalizerConfig cfg;
  std::vector<uint64_t> workspace;
  std::unique_ptr<Localizer> loc;
};

// The decision rule's threshold: --min-confidence when given, else the config's (defaults + --set), so
// the library's `confident` and the evaluation agree.
bool resolve_min_confidence(const EvalOptions& o, float* out, std::string* error) {
  LocalizerConfig cfg = default_config();
  if (!apply_overrides(&cfg, o.overrides, error)) return false;
  *out = o.min_confidence >= 0 ? static_cast<float>(o.min_confidence) : cfg.confidence.min_probability;
  return true;
}

// Sets up a localizer mode (instance, gsf, gsf+refine); returns 0 or the process exit code.
int init_localizer_mode(const EvalOptions& o, const std::string& mode, float min_confidence, const LabelSet& labels,
                        const MapView& map, Clock* clock, LocalizerMode* lm) {
  lm->cfg = default_config();
  std::string err;
  if (!apply_overrides(&lm->cfg, o.overrides, &err)) {
    std::fprintf(stderr, "gsf evaluate: %s\n", err.c_str());
    return 2;
  }
  lm->cfg.confidence.min_probability = min_confidence;
  lm->cfg.classes = labels.config_table();
  lm->cfg.gsf.enabled = mode != "instance";  // the GSF-off (Outram) column
  lm->cfg.refine.enabled = mode == "gsf+refine";
  const size_t need = Localizer::required_bytes(lm->cfg);
  lm->workspace.assign(need / 8 + 2, 0);
  lm->loc = std::make_unique<Localizer>();
  const Status s = lm->loc->init(lm->cfg, map, lm->workspace.data(), lm->workspace.size() * 8, clock);
  if (s != Status::Ok) {
    std::fprintf(stderr, "gsf evaluate: localizer init failed for mode %s: %s\n", mode.c_str(), to_string(s));
    return 1;
  }
  return 0;
}

// The run of a localizer mode (instance, gsf, gsf+refine) and its localizer; with a prior and
// --one-shot-too also its "-one-shot" run, localized without the prior. Returns 0 or the exit code.
int add_localizer_runs(const EvalOptions& o, const std::string& mode, float min_confidence, const LabelSet& labels,
                       const MapView& map, Clock* clock, std::vector<ModeRun>* runs, std::vector<LocalizerMode>* locs) {
  const bool one_shot_too = o.prior.enabled && o.one_shot_too;
  for (const bool without_prior : {false, true}) {
    if (without_prior && !one_shot_too) break;
    LocalizerMode lm;
    lm.run = runs->size();
    lm.without_prior = without_prior;
    if (const int rc = init_localizer_mode(o, mode, min_confidence, labels, map, clock, &lm)) return rc;
    ModeRun run;
    run.mode = without_prior ? mode + "-one-shot" : mode;
    run.workspace_bytes = Localizer::required_bytes(lm.cfg);
    runs->push_back(std::move(run));
    locs->push_back(std::move(lm));
  }
  return 0;
}

// A run per mode in o.modes, and a localizer for each localizer mode; returns 0 or the process exit code.
int init_modes(const EvalOptions& o, float min_confidence, const LabelSet& labels, const MapView& map, Clock* clock,
               std::vector<ModeRun>* runs, std::vector<LocalizerMode>* locs) {
  for (const std::string& mode : o.modes) {
    if (mode == "instance" || mode == "gsf" || mode == "gsf+refine") {
      if (const int rc = add_localizer_runs(o, mode, min_confidence, labels, map, clock, runs, locs)) return rc;
    } else if (mode == "scan-context") {
      ModeRun run;
      run.mode = mode;
      runs->push_back(std::move(run));
    } else {
      std::fprintf(stderr, "gsf evaluate: unknown mode '%s'\n", mode.c_str());
      return 2;
    }
  }
  return 0;
}

// Summaries, with time ratios against the instance-only row of the same run.
std::vector<ModeSummary> summarize_runs(const std::vector<ModeRun>& runs, double min_confidence) {
  std::vector<ModeSummary> sums;
  for (const auto& r : runs) sums.push_back(summarize(r.mode, r.records, min_confidence));
  double base = 0;
  for (const auto& s : sums)
    if (s.mode == "instance") base = s.median_ms;
  for (auto& s : sums) s.time_ratio_to_gsf_off = base > 0 ? s.median_ms / base : 0;
  return sums;
}

// A record with the query's identity and ground truth filled in.
QueryRecord new_record(port::ScanSource& src, uint32_t q, const Meta& meta, const MapView& map) {
  QueryRecord r;
  r.index = q;
  r.frame = src.frame_id(q);
  r.in_zone = q < meta.query_in_zone.size() && meta.query_in_zone[q];
  r.near_zone = q < meta.query_near_zone.size() && meta.query_near_zone[q];
  src.pose(q, &r.truth);
  // The map's coordinates are relative to its origin; the dataset's poses are in the map's frame.
  r.truth_local = to_map_local(map.georef, r.truth);
  return r;
}

// Success is judged on every query with a pose, answered or not.
void judge(QueryRecord* r) {
  if (!r->has_pose) return;
  r->error = pose_error(r->estimate, r->truth);
  r->success = is_success(r->error);
}

// The query instances with a map instance of the same label within 2 m under map_T_scan (map-local).
uint32_t repeatable_under(const MapView& map, const float* qxyz, const uint8_t* qlab, uint32_t n,
                          const Eigen::Isometry3d& map_T_scan) {
  uint32_t count = 0;
  for (uint32_t i = 0; i < n; ++i) {
    const Eigen::Vector3d qw = map_T_scan * Eigen::Vector3d(qxyz[3 * i], qxyz[3 * i + 1], qxyz[3 * i + 2]);
    for (uint32_t m = 0; m < map.counts.instances; ++m) {  // host tool: a linear scan is fine
      const float* c = map.instances[m].centroid;
      if (map.instances[m].label == qlab[i] && (qw - Eigen::Vector3d(c[0], c[1], c[2])).norm() < 2.0) {
        ++count;
        break;
      }
    }
  }
  return count;
}

// The query instances that land on (or beside) a cell of the map's semantic layer holding their class.
uint32_t on_own_class_cells(const MapView& map, const float* qxyz, const uint8_t* qlab, uint32_t n,
                            const Eigen::Isometry3d& map_T_scan) {
  const SemanticGridView grid = semantic_grid_view(map);
  if (grid.empty()) return 0;
  uint32_t count = 0, hint = 0;
  for (uint32_t i = 0; i < n; ++i) {
    const Eigen::Vector3d p = map_T_scan * Eigen::Vector3d(qxyz[3 * i], qxyz[3 * i + 1], qxyz[3 * i + 2]);
    const uint32_t near =
        grid.cell_at(float(p.x()), float(p.y()), &hint) | grid.neighbours_at(float(p.x()), float(p.y()));
    if (near & class_bit(qlab[i])) ++count;
  }
  return count;
}

// Counts the selected correspondences and query instances the ground truth agrees with (< 2 m), and the
// query instances the answer puts on a map instance the same way.
void add_truth_diagnostics(const Localizer& loc, const MapView& map, const std::vector<Localizer::Correspondence>& corr,
                           QueryRecord* r) {
  for (const auto& k : corr) {
    const Eigen::Vector3d qw = r->truth_local * Eigen::Vector3d(k.query_xyz[0], k.query_xyz[1], k.query_xyz[2]);
    const float* m = map.instances[k.map_instance].centroid;
    if ((qw - Eigen::Vector3d(m[0], m[1], m[2])).norm() >= 2.0) continue;
    ++r->true_correspondences;
    r->true_pairs.push_back({k.weight, std::hypot(k.query_xyz[0], k.query_xyz[1])});
  }
  float qxyz[3 * 1024];
  uint8_t qlab[1024];
  const uint32_t ni = std::min<uint32_t>(loc.last_instances(qxyz, qlab, 1024), 1024);
  r->repeatable_instances = repeatable_under(map, qxyz, qlab, ni, r->truth_local);
  if (r->has_pose) {
    const Eigen::Isometry3d answer = to_map_local(map.georef, r->estimate);
    r->answer_repeatable_instances = repeatable_under(map, qxyz, qlab, ni, answer);
    r->answer_layer_instances = on_own_class_cells(map, qxyz, qlab, ni, answer);
  }
}

// The last query's instances, for the correspondence picture.
std::vector<PictureInstance> picture_instances(const Localizer& loc) {
  std::vector<float> xyz(3 * 1024);
  std::vector<uint8_t> labels(1024);
  const uint32_t n = std::min<uint32_t>(loc.last_instances(xyz.data(), labels.data(), 1024), 1024);
  std::vector<PictureInstance> out(n);
  for (uint32_t i = 0; i < n; ++i) out[i] = {{xyz[3 * i], xyz[3 * i + 1], xyz[3 * i + 2]}, labels[i]};
  return out;
}

// Whether two runs of one query gave the same answer (--repeat: the library is deterministic).
bool same_outcome(const LocalizeResult& a, const LocalizeResult& b) {
  return a.status == b.status && a.confidence == b.confidence && a.inliers == b.inliers &&
         a.map_frame_T_scan.matrix() == b.map_frame_T_scan.matrix();
}

// Localizes one query (already read into `scan`, or failed with `read_status`) in one mode, `repeat`
// times keeping the fastest run (--repeat); corr_buf is scratch for the correspondences.
void localize_query(LocalizerMode& lm, const ScanView& scan, Status read_status, const MapView& map,
                    std::vector<Localizer::Correspondence>& corr_buf, const PositionPrior* prior, uint32_t repeat,
                    QueryRecord r, ModeRun* run) {
  LocalizeResult res;
  if (read_status != Status::Ok) res.status = read_status;
  for (uint32_t k = 0; k < repeat && read_status == Status::Ok; ++k) {  // the fastest of `repeat` runs
    LocalizeResult again;
    if (prior) lm.loc->localize(scan, *prior, &again);
    else lm.loc->localize(scan, &again);
    if (k > 0 && !same_outcome(res, again))
      std::fprintf(stderr, "gsf evaluate: query %u answered differently when repeated (mode %s)\n", r.index,
                   run->mode.c_str());
    if (k == 0 || again.times.total < res.times.total) res = again;
  }
  r.status = to_string(res.status);
  r.has_pose = res.status == Status::Ok;
  r.answered = r.has_pose && res.confident;  // the library's decision rule
  r.estimate = res.map_frame_T_scan;
  r.confidence = r.has_pose ? res.confidence : 0.0;
  r.inliers = res.inliers;
  r.result = res;
  r.time_ms = ms(res.times.total);
  r.stages = stage_ms(res.times);
  judge(&r);
  const uint32_t nc = lm.loc->last_correspondences(corr_buf.data(), static_cast<uint32_t>(corr_buf.size()));
  std::vector<Localizer::Correspondence> corr(corr_buf.begin(),
                                              corr_buf.begin() + std::min<size_t>(nc, corr_buf.size()));
  add_truth_diagnostics(*lm.loc, map, corr, &r);
  if (res.status == Status::Ok) {
    const PoseVerification at_truth = lm.loc->score_pose(r.truth_local);
    r.truth_verified_score = at_truth.score;
    const uint32_t sampled = at_truth.scored + at_truth.unknown;
    r.truth_known_share = sampled > 0 ? double(at_truth.scored) / sampled : 0.0;
  }
  run->instances.push_back(picture_instances(*lm.loc));
  run->corr.push_back(std::move(corr));
  run->records.push_back(std::move(r));
}
// The Scan Context peer: a database of the map drive's scans, one nearest-place query per scan. It has
// no calibrated confidence; its stand-in is 1 - its distance ratio to the best place at least 10 m
// away, under the same threshold. Returns 0 or the process exit code.
int run_scan_context(const EvalOptions& o, const LabelSet& labels, port::ScanSource& src, const MapView& map,
                     const Meta& meta, uint32_t nq, double min_confidence, port::ScanBuffer& buf, ModeRun* run) {
  Status s;
  auto map_src = open_source(o.dataset, o.map_sequence, &s, &labels);
  if (s != Status::Ok) {
    std::fprintf(stderr, "gsf evaluate: scan-context needs the map sequence '%s': %s\n", o.map_sequence.c_str(),
                 to_string(s));
    return 1;
  }
  bench::ScanContextConfig sc;
  bench::ScanContextDatabase db(sc);
  for (uint32_t i = 0; i < map_src->size(); ++i) {
    Eigen::Isometry3d pose;
    if (map_src->pose(i, &pose) != Status::Ok || map_src->read(i, buf) != Status::Ok) continue;
    db.add(bench::make_scan_context(sc, buf.points, 4, buf.count), pose);
  }
  run->workspace_bytes = db.size() * (sizeof(float) * (sc.rings * sc.sectors + sc.rings) + sizeof(Eigen::Isometry3d));
  for (uint32_t q = 0; q < nq; ++q) {
    QueryRecord r = new_record(src, q, meta, map);
    r.status = "IoError";
    if (src.read(q, buf) == Status::Ok) {
      const auto t0 = std::chrono::steady_clock::now();
      const auto m = db.query(bench::make_scan_context(sc, buf.points, 4, buf.count));
      r.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      r.status = m.found ? "Ok" : "NoSolution";
      r.has_pose = m.found;
      r.estimate = m.pose;
      const double ratio = m.second_distance > 0 ? std::min(1.0, double(m.distance) / m.second_distance) : 1.0;
      r.confidence = r.has_pose ? 1.0 - ratio : 0.0;
      r.answered = r.has_pose && r.confidence >= min_confidence;
      judge(&r);
    }
    run->corr.emplace_back();
    run->records.push_back(r);
  }
  return 0;
}

void print_header(const MapView& map, const Meta& meta, const std::vector<ModeSummary>& sums, uint32_t nq,
                  const ScanLabelErrors& label_errors) {
  const double km = map.counts.road_length_m / 1000.0;
  if (label_errors.rates.any())
    std::printf("\nsimulated network errors on the query scans' labels: %s\n", describe(label_errors).c_str());
  std::printf(
      "\nmap: %zu bytes, %u instances, %u triangles, %.0f m of road -> %.2f MB/km; origin %.3f, %.3f, %.3f in '%s'\n",
      map.total_bytes, map.counts.instances, map.counts.triangles, map.counts.road_length_m,
      km > 0 ? map.total_bytes / 1e6 / km : 0.0, map.georef.origin[0], map.georef.origin[1], map.georef.origin[2],
      map.georef.frame);
  std::printf(
      "queries: %u (%u in the repetitive zone%s%s, %u near it, %u elsewhere); success = t < %.0f m and r < %.0f "
      "deg\n\n",
      nq, sums.empty() ? 0 : sums[0].zone_queries, meta.zone_type.empty() ? "" : ": ", meta.zone_type.c_str(),
      sums.empty() ? 0 : sums[0].near_zone_queries, sums.empty() ? 0 : sums[0].elsewhere_queries, kSuccessTranslation,
      kSuccessRotationDeg);
}

void print_table(const std::vector<ModeSummary>& sums, const std::vector<ModeRun>& runs) {
  std::printf("%-13s %8s %8s %8s %8s %7s %7s %9s %9s %7s %10s %9s %9s\n", "mode", "success", "repet.", "near", "else",
              "ATE m", "ARE deg", "median ms", "p95 ms", "x off", "workspace", "prec@rule", "answered");
  for (size_t m = 0; m < sums.size(); ++m) {
    const ModeSummary& x = sums[m];
    std::printf("%-13s %7.1f%% %7.1f%% %7.1f%% %7.1f%% %7.2f %7.2f %9.1f %9.1f %7.2f %8.1fMB %8.1f%% %8.1f%%\n",
                x.mode.c_str(), 100 * x.success_rate, 100 * x.zone_success_rate, 100 * x.near_zone_success_rate,
                100 * x.elsewhere_success_rate, x.ate_m, x.are_deg, x.median_ms, x.p95_ms, x.time_ratio_to_gsf_off,
                runs[m].workspace_bytes / 1e6, 100 * x.rule.precision, 100 * x.rule.answered_share);
  }
  for (const auto& x : sums)
    if (x.mode != "scan-context")
      std::printf(
          "  %s median stage ms: voxel %.1f  cluster %.1f  field %.1f  triangle %.1f  match %.1f  gsf %.1f  "
          "clique %.1f  pose %.1f  confidence %.1f  refine %.1f\n",
          x.mode.c_str(), x.median_stage.voxel, x.median_stage.cluster, x.median_stage.field, x.median_stage.triangle,
          x.median_stage.match, x.median_stage.gsf, x.median_stage.clique, x.median_stage.pose,
          x.median_stage.confidence, x.median_stage.refine);
  std::printf(
      "  (prec@rule / answered: precision and share answered under the decision rule, status Ok and confidence "
      ">= %.2f)\n",
      sums.empty() ? 0.0 : sums[0].min_confidence);
}

// printf into a string (for table rows built cell by cell).
template <typename... T>
std::string cell(const char* format, T... values) {
  char b[96];
  std::snprintf(b, sizeof(b), format, values...);
  return b;
}

void print_line(std::string line) {
  while (!line.empty() && line.back() == ' ') line.pop_back();
  std::printf("%s\n", line.c_str());
}

// Per mode: the decision rule's counts, the calibration error (ECE) and the Brier score.
void print_calibration(const std::vector<ModeSummary>& sums) {
  std::printf("\ncalibration (all queries; no pose = confidence 0 and a failure):\n");
  std::printf("%-13s %6s %7s %6s %6s %9s %9s %6s %14s\n", "mode", "n", "success", "ECE", "Brier", "prec@rule",
              "answered", "wrong", "declined-right");
  for (const ModeSummary& x : sums)
    std::printf("%-13s %6u %6.1f%% %5.1f%% %6.3f %8.1f%% %8.1f%% %6u %14u\n", x.mode.c_str(), x.queries,
                100 * x.success_rate, 100 * x.calibration.ece, x.calibration.brier, 100 * x.rule.precision,
                100 * x.rule.answered_share, x.rule.wrong, x.rule.declined_right);
}

// Per confidence bin (rows) and mode (columns): queries, mean confidence -> observed success.
void print_reliability(const std::vector<ModeSummary>& sums) {
  std::printf("reliability: per confidence bin, queries  mean confidence -> observed success\n");
  std::string head = cell("%-9s", "bin");
  for (const ModeSummary& x : sums) head += cell("  %-18s", x.mode.c_str());
  print_line(head);
  for (int b = 0; b < kReliabilityBins; ++b) {
    const ReliabilityBin& first = sums.front().calibration.bins[b];
    std::string line = cell("[%.1f,%.1f%c", first.lo, first.hi, b + 1 == kReliabilityBins ? ']' : ')');
    for (const ModeSummary& x : sums) {
      const ReliabilityBin& bin = x.calibration.bins[b];
      line += bin.count == 0 ? cell("  %5s %12s", "-", "")
                             : cell("  %5u %4.2f -> %4.2f", bin.count, bin.mean_confidence, bin.success_rate);
    }
    print_line(line);
  }
}

// What the options name: the label set, the decision rule's threshold, the label errors of the query
// scans (printing its note). False: a usage error, in *error.
bool resolve_inputs(const EvalOptions& o, LabelSet* labels, float* min_confidence, ScanLabelErrors* errors,
                    std::string* error) {
  std::string note;
  if (!resolve_label_set(o.classes, o.dataset, o.sequence, labels, error) ||
      !resolve_min_confidence(o, min_confidence, error) ||
      !resolve_scan_label_errors(o.label_errors, *labels, o.sequence, errors, &note, error))
    return false;
  if (!note.empty()) std::fprintf(stderr, "gsf evaluate: note: %s\n", note.c_str());
  return true;
}

}  // namespace

int run_evaluation(const EvalOptions& o) {
  MapFile file;
  std::string err;
  if (read_map_file(o.map_path, &file, &err) != Status::Ok) {
    std::fprintf(stderr, "gsf evaluate: %s\n", err.c_str());
    return 1;
  }
  MapView map;
  Status s = load_map(file.data(), file.bytes, &map);
  if (s != Status::Ok) {
    std::fprintf(stderr, "gsf evaluate: invalid map '%s': %s\n", o.map_path.c_str(), map_load_error(file, s).c_str());
    return 1;
  }
  LabelSet labels;
  float min_confidence = 0;
  ScanLabelErrors label_errors;
  if (!resolve_inputs(o, &labels, &min_confidence, &label_errors, &err)) {
    std::fprintf(stderr, "gsf evaluate: %s\n", err.c_str());
    return 2;
  }
  auto src = open_source(o.dataset, o.sequence, &s, &labels);
  if (s != Status::Ok || src->size() == 0) {
    std::fprintf(stderr, "gsf evaluate: cannot open query sequence '%s' under '%s': %s\n", o.sequence.c_str(),
                 o.dataset.c_str(), s == Status::Ok ? "no scans" : to_string(s));
    return 1;
  }
  const Meta meta = read_meta(o.dataset);
  const uint32_t nq = o.limit ? std::min<uint32_t>(o.limit, src->size()) : src->size();
  port::OwnedScanBuffer buf(kMaxScanPoints, true);
  port::SteadyClock clock;
  // Localizer modes run interleaved, query by query, so every row sees the same machine conditions
  // (sequential runs showed the same voxel stage differing by 35% between rows).
  std::vector<ModeRun> runs;
  std::vector<LocalizerMode> locs;
  if (const int rc = init_modes(o, min_confidence, labels, map, &clock, &runs, &locs)) return rc;
  std::vector<Localizer::Correspondence> corr(4096);
  for (uint32_t q = 0; q < nq && !locs.empty(); ++q) {
    const QueryRecord blank = new_record(*src, q, meta, map);
    const Status rs =
        read_scan(*src, q, buf.buffer(), o.logits, 2000000u + src->frame_id(q), labels.config_table(), &label_errors);
    // --prior-sigma: every mode gets the same prior, drawn around the query's truth (map frame).
    const PositionPrior prior = draw_prior(o.prior, blank.truth, q);
    const PositionPrior* p = o.prior.enabled ? &prior : nullptr;
    for (LocalizerMode& lm : locs)
      localize_query(lm, buf.buffer().view(), rs, map, corr, lm.without_prior ? nullptr : p, o.repeat, blank,
                     &runs[lm.run]);
    if (o.progress && (q % 10 == 0 || q + 1 == nq)) std::fprintf(stderr, "\r  evaluate: %u / %u queries", q + 1, nq);
  }
  if (o.progress && !locs.empty()) std::fprintf(stderr, "\n");
  for (ModeRun& run : runs)
    if (run.mode == "scan-context")
      if (const int rc = run_scan_context(o, labels, *src, map, meta, nq, min_confidence, buf.buffer(), &run))
        return rc;
  const std::vector<ModeSummary> sums = summarize_runs(runs, min_confidence);
  print_header(map, meta, sums, nq, label_errors);
  if (o.prior.enabled)
    std::printf(
        "position prior: drawn around each query's truth, sigma %.1f m, bias %.1f m, radius %.1f m, heading "
        "tolerance %.0f deg (0: none), seed %llu\n\n",
        o.prior.sigma, o.prior.bias, o.prior.radius, o.prior.heading_tolerance_deg,
        static_cast<unsigned long long>(o.prior.seed));
  print_table(sums, runs);
  if (!sums.empty()) {
    print_calibration(sums);
    print_reliability(sums);
  }
  if (!o.json_out.empty()) write_json(o.json_out, o, map, runs, sums, meta, label_errors);
  if (!o.svg_dir.empty() && !write_svgs(o, map, runs, sums)) return 1;  // a PNG could not be written
  return 0;
}

}  // namespace gsf::cli
