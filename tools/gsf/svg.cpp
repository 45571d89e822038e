#include "svg.h"

#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>

#include "gsf/semantic_classes.h"

extern char** environ;

namespace gsf::cli {

static std::string fmt(double v) {
  char b[32];
  std::snprintf(b, sizeof(b), "%.2f", v);
  return b;
}

static std::string escape_xml(const std::string& s) {
  std::string esc;
  for (char c : s) esc += c == '<' ? std::string("&lt;") : c == '&' ? std::string("&amp;") : std::string(1, c);
  return esc;
}

void SvgPicture::include(double x, double y, double pad) {
  box_.min_x = std::min(box_.min_x, x - pad);
  box_.max_x = std::max(box_.max_x, x + pad);
  box_.min_y = std::min(box_.min_y, y - pad);
  box_.max_y = std::max(box_.max_y, y + pad);
}
void SvgPicture::line(double x0, double y0, double x1, double y1, const std::string& stroke, double width,
                      const std::string& dash, double opacity, bool round) {
  include(x0, y0, width / 2);
  include(x1, y1, width / 2);
  body_ += "<line x1=\"" + fmt(x0) + "\" y1=\"" + fmt(y0) + "\" x2=\"" + fmt(x1) + "\" y2=\"" + fmt(y1) +
           "\" stroke=\"" + stroke + "\" stroke-width=\"" + fmt(width) + "\"" +
           (dash.empty() ? "" : " stroke-dasharray=\"" + dash + "\"") +
           (opacity < 1 ? " stroke-opacity=\"" + fmt(opacity) + "\"" : "") +
           (round ? " stroke-linecap=\"round\"" : "") + "/>\n";
}
void SvgPicture::polyline(const std::vector<std::array<double, 2>>& points, const std::string& stroke, double width) {
  std::string pts;
  for (const auto& p : points) {
    include(p[0], p[1], width / 2);
    pts += (pts.empty() ? "" : " ") + fmt(p[0]) + "," + fmt(p[1]);
  }
  body_ += "<polyline points=\"" + pts + "\" fill=\"none\" stroke=\"" + stroke + "\" stroke-width=\"" + fmt(width) +
           "\"/>\n";
}
void SvgPicture::polygon(const std::vector<std::array<double, 2>>& points, const std::string& fill,
                         const std::string& stroke, double stroke_width) {
  std::string pts;
  for (const auto& p : points) {
    include(p[0], p[1], stroke.empty() ? 0 : stroke_width / 2);
    pts += (pts.empty() ? "" : " ") + fmt(p[0]) + "," + fmt(p[1]);
  }
  body_ += "<polygon points=\"" + pts + "\" fill=\"" + fill + "\"" +
           (stroke.empty() ? "" : " stroke=\"" + stroke + "\" stroke-width=\"" + fmt(stroke_width) + "\"") + "/>\n";
}
void SvgPicture::rect(double x, double y, double w, double h, const std::string& fill, double opacity,
                      const std::string& stroke) {
  include(x, y, stroke.empty() ? 0 : 0.5);
  include(x + w, y + h, stroke.empty() ? 0 : 0.5);
  body_ += "<rect x=\"" + fmt(x) + "\" y=\"" + fmt(y) + "\" width=\"" + fmt(w) + "\" height=\"" + fmt(h) +
           "\" fill=\"" + fill + "\"" + (opacity < 1 ? " fill-opacity=\"" + fmt(opacity) + "\"" : "") +
           (stroke.empty() ? "" : " stroke=\"" + stroke + "\"") + "/>\n";
}
void SvgPicture::circle(double x, double y, double r, const std::string& fill, double opacity,
                        const std::string& stroke, double stroke_width) {
  include(x, y, r + (stroke.empty() ? 0 : stroke_width / 2));
  body_ += "<circle cx=\"" + fmt(x) + "\" cy=\"" + fmt(y) + "\" r=\"" + fmt(r) + "\" fill=\"" + fill + "\"" +
           (opacity < 1 ? " opacity=\"" + fmt(opacity) + "\"" : "") +
           (stroke.empty() ? "" : " stroke=\"" + stroke + "\" stroke-width=\"" + fmt(stroke_width) + "\"") + "/>\n";
}
void SvgPicture::text(double x, double y, const std::string& s, double size, const std::string& anchor,
                      double rotate_deg, const std::string& fill, bool bold) {
  // The unrotated box relative to (x, y): 0.6 em per character (0.65 bold), ascent 1 em, descent 0.25 em.
  const double w = (bold ? 0.65 : 0.6) * size * static_cast<double>(s.size());
  const double left = anchor == "middle" ? -w / 2 : anchor == "end" ? -w : 0.0;
  const double c = std::cos(rotate_deg * M_PI / 180), sn = std::sin(rotate_deg * M_PI / 180);
  for (double dx : {left, left + w})
    for (double dy : {-size, 0.25 * size}) include(x + c * dx - sn * dy, y + sn * dx + c * dy);
  body_ += "<text x=\"" + fmt(x) + "\" y=\"" + fmt(y) + "\" font-family=\"sans-serif\" font-size=\"" + fmt(size) +
           "\" text-anchor=\"" + anchor + "\" fill=\"" + fill + "\"" + (bold ? " font-weight=\"bold\"" : "") +
           (rotate_deg != 0 ? " transform=\"rotate(" + fmt(rotate_deg) + " " + fmt(x) + " " + fmt(y) + ")\"" : "") +
           ">" + escape_xml(s) + "</text>\n";
}
std::string SvgPicture::finish(double margin) const {
  const bool empty = box_.empty();
  const double x = empty ? 0 : box_.min_x - margin, y = empty ? 0 : box_.min_y - margin;
  const double w = empty ? 1 : box_.max_x - box_.min_x + 2 * margin;
  const double h = empty ? 1 : box_.max_y - box_.min_y + 2 * margin;
  return "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + fmt(w) + "\" height=\"" + fmt(h) + "\" viewBox=\"" +
         fmt(x) + " " + fmt(y) + " " + fmt(w) + " " + fmt(h) + "\">\n<rect x=\"" + fmt(x) + "\" y=\"" + fmt(y) +
         "\" width=\"" + fmt(w) + "\" height=\"" + fmt(h) + "\" fill=\"white\"/>\n" + body_ + "</svg>\n";
}
bool SvgPicture::save(const std::string& path) const {
  std::ofstream f(path);
  f << finish();
  return static_cast<bool>(f);
}

MapProjection fit_projection(double min_x, double min_y, double max_x, double max_y, double max_width,
                             double max_height) {
  const double w = std::max(max_x - min_x, 1e-3), h = std::max(max_y - min_y, 1e-3);
  MapProjection p;
  p.x0 = min_x;
  p.y0 = max_y;
  p.scale = std::min(max_width / w, max_height / h);
  return p;
}

void draw_scale_bar(SvgPicture& svg, double x, double y, double px_per_m, double target_px) {
  // The round length (1, 2, 5 x 10^k m) nearest to target_px in pixels, never longer than 1.6 x it.
  const double want_m = target_px / px_per_m;
  double m = std::pow(10.0, std::floor(std::log10(want_m)));
  for (double step : {2.0, 2.5, 2.0}) {  // 1 -> 2 -> 5 -> 10
    if (m * step > want_m * 1.25) break;
    m *= step;
  }
  const double len = m * px_per_m;
  const double seg = len / 2;
  svg.rect(x, y, seg, 6, "#222222", 1.0, "#222222");
  svg.rect(x + seg, y, seg, 6, "#ffffff", 1.0, "#222222");
  for (double t : {0.0, seg, len}) svg.line(x + t, y - 3, x + t, y + 6, "#222222", 1);
  char label[32];
  if (m >= 1000) std::snprintf(label, sizeof(label), "%g km", m / 1000);
  else std::snprintf(label, sizeof(label), "%g m", m);
  svg.text(x, y + 20, "0", 11, "middle");
  svg.text(x + len, y + 20, label, 11, "middle");
}

LegendEntry legend_dot(const std::string& colour, double r, const std::string& label, double opacity) {
  return {[=](SvgPicture& s, double cx, double cy) { s.circle(cx, cy, r, colour, opacity); }, label};
}
LegendEntry legend_ring(const std::string& colour, double r, const std::string& label, double width) {
  return {[=](SvgPicture& s, double cx, double cy) { s.circle(cx, cy, r, "none", 1.0, colour, width); }, label};
}
LegendEntry legend_line(const std::string& colour, double width, const std::string& label, const std::string& dash,
                        double opacity) {
  return {[=](SvgPicture& s, double cx, double cy) { s.line(cx - 11, cy, cx + 11, cy, colour, width, dash, opacity); },
          label};
}
LegendEntry legend_cross(const std::string& colour, double half, const std::string& label, double width) {
  return {[=](SvgPicture& s, double cx, double cy) {
            s.line(cx - half, cy - half, cx + half, cy + half, colour, width);
            s.line(cx - half, cy + half, cx + half, cy - half, colour, width);
          },
          label};
}
LegendEntry legend_square(const std::string& colour, double side, const std::string& label) {
  return {[=](SvgPicture& s, double cx, double cy) { s.rect(cx - side / 2, cy - side / 2, side, side, colour); },
          label};
}

SvgPicture::Box draw_legend(SvgPicture& svg, double x, double y, const std::vector<LegendEntry>& entries,
                            const std::string& title, double font) {
  const double row = font * 1.7, pad = 8, swatch = 28;
  double width = title.empty() ? 0 : 0.65 * font * static_cast<double>(title.size());
  for (const auto& e : entries) width = std::max(width, swatch + 0.6 * font * static_cast<double>(e.label.size()));
  const double height = pad * 2 + row * static_cast<double>(entries.size() + (title.empty() ? 0 : 1)) - (row - font);
  svg.rect(x, y, width + 2 * pad, height, "#ffffff", 0.92, "#999999");
  double cy = y + pad + font * 0.8;
  if (!title.empty()) {
    svg.text(x + pad, cy + font * 0.35, title, font, "start", 0, "#222", true);
    cy += row;
  }
  for (const auto& e : entries) {
    if (e.swatch) e.swatch(svg, x + pad + 11, cy);
    svg.text(x + pad + swatch, cy + font * 0.35, e.label, font);
    cy += row;
  }
  SvgPicture::Box frame;
  frame.min_x = x;
  frame.min_y = y;
  frame.max_x = x + width + 2 * pad;
  frame.max_y = y + height;
  return frame;
}

std::string class_colour(int c) {
  switch (c) {
    case kCar: return "#6495ed";
    case kTruck:
    case kOtherVehicle: return "#5050ff";
    case kPerson:
    case kBicyclist:
    case kMotorcyclist: return "#ff1e1e";
    case kBicycle:
    case kMotorcycle: return "#ff6464";
    case kRoad: return "#ff00ff";
    case kParking: return "#ff96ff";
    case kSidewalk: return "#4b004b";
    case kOtherGround: return "#af004b";
    case kBuilding: return "#e0a800";  // darker than SemanticKITTI's yellow, readable on white
    case kFence: return "#ff7832";
    case kVegetation: return "#00af00";
    case kTrunk: return "#873c00";
    case kTerrain: return "#96f050";
    case kPole: return "#1f3fbf";  // darker than SemanticKITTI's pale blue: readable on white, apart from cars
    case kTrafficSign: return "#ff0000";
    default: return "#888888";
  }
}

std::string find_rsvg_convert() {
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "/usr/local/bin:/usr/bin:/bin";
  size_t start = 0;
  while (start <= dirs.size()) {
    const size_t end = std::min(dirs.find(':', start), dirs.size());
    const std::string dir = end > start ? dirs.substr(start, end - start) : ".";
    const std::string candidate = dir + "/rsvg-convert";
    struct stat st;
    if (stat(candidate.c_str(), &st) == 0 && S_ISREG(st.st_mode) && access(candidate.c_str(), X_OK) == 0)
      return candidate;
    start = end + 1;
  }
  return "";
}

bool svg_to_png(const std::string& rsvg_convert, const std::string& svg_path, const std::string& png_path,
                std::string* error) {
  std::vector<std::string> args = {rsvg_convert, "--format", "png", "--output", png_path, svg_path};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, rsvg_convert.c_str(), nullptr, nullptr, argv.data(), environ);
  if (rc != 0) {
    *error = "cannot run " + rsvg_convert + ": " + std::strerror(rc);
    return false;
  }
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) {
      *error = std::string("waitpid: ") + std::strerror(errno);
      return false;
    }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    *error = "rsvg-convert failed on " + svg_path;
    return false;
  }
  return true;
}

std::string png_path_for(const std::string& svg_path) {
  const size_t n = svg_path.size();
  return (n >= 4 && svg_path.compare(n - 4, 4, ".svg") == 0 ? svg_path.substr(0, n - 4) : svg_path) + ".png";
}

}  // namespace gsf::cli
