#include "reliability_svg.h"

#include <algorithm>
#include <cstdio>

#include "svg.h"

namespace gsf::cli {
namespace {

// Layout in pixels: the curves' square, the count bars under it, on one confidence axis.
constexpr double kLeft = 70, kTop = 50, kSide = 420;               // curves: [kLeft, kLeft + kSide]^2
constexpr double kBarsTop = kTop + kSide + 18, kBarsHeight = 120;  // counts panel below
constexpr double kBarsLabelRoom = 26;                              // above the tallest bar, for its number
const char* const kColours[] = {"#4477aa", "#ee6677", "#228833", "#ccbb44", "#aa3377", "#66ccee"};

double x_of(double confidence) { return kLeft + kSide * confidence; }
double y_of(double success) { return kTop + kSide * (1 - success); }
std::string colour(size_t mode) { return kColours[mode % (sizeof(kColours) / sizeof(kColours[0]))]; }
std::string format(const char* f, double v) {
  char b[64];
  std::snprintf(b, sizeof(b), f, v);
  return b;
}

void draw_axes(SvgPicture& svg) {
  const double bars_bottom = kBarsTop + kBarsHeight;
  svg.rect(kLeft, kTop, kSide, kSide, "#ffffff", 1.0, "#444444");
  svg.rect(kLeft, kBarsTop, kSide, kBarsHeight, "#ffffff", 1.0, "#444444");
  for (int k = 1; k < kReliabilityBins; ++k) {  // bin edges
    const double x = x_of(double(k) / kReliabilityBins);
    svg.line(x, kTop, x, kTop + kSide, "#e4e4e4", 0.8);
    svg.line(x, kBarsTop, x, bars_bottom, "#e4e4e4", 0.8);
  }
  for (int k = 0; k <= 5; ++k) {  // ticks every 0.2
    const double v = k / 5.0;
    svg.line(x_of(v), bars_bottom, x_of(v), bars_bottom + 5, "#444444", 1);
    svg.text(x_of(v), bars_bottom + 18, format("%.1f", v), 12, "middle");
    svg.line(kLeft - 5, y_of(v), kLeft, y_of(v), "#444444", 1);
    svg.text(kLeft - 8, y_of(v) + 4, format("%.1f", v), 12, "end");
  }
  svg.line(x_of(0), y_of(0), x_of(1), y_of(1), "#888888", 1.2, "5 4");  // perfect calibration
  svg.text(kLeft + kSide / 2, bars_bottom + 38, "predicted confidence (bin mean; bins of 0.1)", 13, "middle");
  svg.text(kLeft - 42, kTop + kSide / 2, "observed success rate (t < 5 m, r < 10 deg)", 13, "middle", -90);
  svg.text(kLeft - 42, kBarsTop + kBarsHeight / 2, "queries", 13, "middle", -90);
  svg.text(kLeft, kTop - 28, "Reliability of the localizer's confidence", 15);
  svg.text(kLeft, kTop - 10, "all queries; a query without a pose counts as confidence 0 and a failure", 11, "start", 0,
           "#555555");
}

void draw_threshold(SvgPicture& svg, double min_confidence) {
  const double x = x_of(min_confidence);
  svg.line(x, kTop, x, kBarsTop + kBarsHeight, "#cc3311", 1.4, "3 3");
  svg.text(x + 4, kTop + kSide - 8, format("rule: confidence >= %.2f", min_confidence), 11, "start", 0, "#cc3311");
}

// Bars of each bin's count per mode, side by side within the bin, with the count written above.
void draw_counts(SvgPicture& svg, const std::vector<ModeSummary>& modes) {
  uint32_t most = 1;
  for (const auto& m : modes)
    for (const auto& b : m.calibration.bins) most = std::max(most, b.count);
  const double bin_px = kSide / kReliabilityBins, bar_px = (bin_px - 6) / double(modes.size());
  const double bottom = kBarsTop + kBarsHeight, scale = (kBarsHeight - kBarsLabelRoom) / most;
  for (size_t m = 0; m < modes.size(); ++m)
    for (int b = 0; b < kReliabilityBins; ++b) {
      const uint32_t n = modes[m].calibration.bins[b].count;
      if (n == 0) continue;
      const double x = x_of(double(b) / kReliabilityBins) + 3 + bar_px * double(m), h = n * scale;
      svg.rect(x, bottom - h, bar_px - 1, h, colour(m), 0.85);
      svg.text(x + bar_px / 2 + 3, bottom - h - 3, std::to_string(n), 9, "start", -90);
    }
  for (uint32_t tick : {0u, most}) {
    svg.line(kLeft - 5, bottom - tick * scale, kLeft, bottom - tick * scale, "#444444", 1);
    svg.text(kLeft - 8, bottom - tick * scale + 4, std::to_string(tick), 12, "end");
  }
}

// Each mode's bins (mean confidence, observed success), joined in bin order.
void draw_curves(SvgPicture& svg, const std::vector<ModeSummary>& modes) {
  for (size_t m = 0; m < modes.size(); ++m) {
    std::vector<std::array<double, 2>> points;
    for (const auto& b : modes[m].calibration.bins)
      if (b.count > 0) points.push_back({x_of(b.mean_confidence), y_of(b.success_rate)});
    if (points.size() > 1) svg.polyline(points, colour(m), 2);
    for (const auto& p : points) svg.circle(p[0], p[1], 4, colour(m));
  }
}

void draw_mode_legend(SvgPicture& svg, const std::vector<ModeSummary>& modes) {
  std::vector<LegendEntry> rows;
  for (size_t m = 0; m < modes.size(); ++m) {
    const Calibration& c = modes[m].calibration;
    char label[160];
    std::snprintf(label, sizeof(label), "%s: ECE %.1f%%, Brier %.3f, n=%u", modes[m].mode.c_str(), 100 * c.ece, c.brier,
                  c.queries);
    const std::string col = colour(m);
    rows.push_back({[col](SvgPicture& s, double cx, double cy) {
                      s.line(cx - 11, cy, cx + 11, cy, col, 2);
                      s.circle(cx, cy, 4, col);
                    },
                    label});
  }
  rows.push_back(legend_line("#888888", 1.2, "perfect calibration", "5 4"));
  rows.push_back({[](SvgPicture& s, double cx, double cy) { s.line(cx, cy - 8, cx, cy + 8, "#cc3311", 1.4, "3 3"); },
                  "decision rule threshold"});
  rows.push_back({[](SvgPicture& s, double cx, double cy) { s.rect(cx - 5, cy - 6, 10, 12, "#888888", 0.85); },
                  "bars: queries per bin, one per mode"});
  draw_legend(svg, kLeft + kSide + 24, kTop, rows, "modes");
}

}  // namespace

bool save_reliability_svg(const std::string& path, const std::vector<ModeSummary>& modes, double min_confidence) {
  SvgPicture svg;
  draw_axes(svg);
  if (!modes.empty()) draw_counts(svg, modes);
  draw_threshold(svg, min_confidence);
  draw_curves(svg, modes);
  draw_mode_legend(svg, modes);
  return svg.save(path);
}

}  // namespace gsf::cli
