#include "svg.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>

#include "gsf/semantic_classes.h"

namespace gsf::cli {

SvgCanvas::SvgCanvas(double min_x, double min_y, double max_x, double max_y, double width_px)
    : min_x_(min_x), max_y_(max_y) {
  const double w = std::max(max_x - min_x, 1e-6), h = std::max(max_y - min_y, 1e-6);
  scale_ = (width_px - 2 * margin_) / w;
  width_ = width_px;
  height_ = h * scale_ + 2 * margin_;
}

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

void SvgCanvas::circle(double x, double y, double r, const std::string& fill, double opacity) {
  body_ += "<circle cx=\"" + fmt(px(x)) + "\" cy=\"" + fmt(py(y)) + "\" r=\"" + fmt(r) + "\" fill=\"" + fill +
           "\" fill-opacity=\"" + fmt(opacity) + "\"/>\n";
}
void SvgCanvas::line(double x0, double y0, double x1, double y1, const std::string& stroke, double w, double opacity) {
  body_ += "<line x1=\"" + fmt(px(x0)) + "\" y1=\"" + fmt(py(y0)) + "\" x2=\"" + fmt(px(x1)) + "\" y2=\"" +
           fmt(py(y1)) + "\" stroke=\"" + stroke + "\" stroke-width=\"" + fmt(w) + "\" stroke-opacity=\"" +
           fmt(opacity) + "\"/>\n";
}
void SvgCanvas::text(double x, double y, const std::string& s, double size, const std::string& fill) {
  text_px(px(x), py(y), s, size, fill);
}
void SvgCanvas::text_px(double x, double y, const std::string& s, double size, const std::string& fill) {
  body_ += "<text x=\"" + fmt(x) + "\" y=\"" + fmt(y) + "\" font-family=\"sans-serif\" font-size=\"" + fmt(size) +
           "\" fill=\"" + fill + "\">" + escape_xml(s) + "</text>\n";
}
void SvgCanvas::rect_px(double x, double y, double w, double h, const std::string& fill) {
  body_ += "<rect x=\"" + fmt(x) + "\" y=\"" + fmt(y) + "\" width=\"" + fmt(w) + "\" height=\"" + fmt(h) +
           "\" fill=\"" + fill + "\"/>\n";
}
std::string SvgCanvas::finish() const {
  return "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + fmt(width_) + "\" height=\"" + fmt(height_) +
         "\" viewBox=\"0 0 " + fmt(width_) + " " + fmt(height_) +
         "\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n" + body_ + "</svg>\n";
}
bool SvgCanvas::save(const std::string& path) const {
  std::ofstream f(path);
  f << finish();
  return static_cast<bool>(f);
}

void SvgPicture::include(double x, double y) {
  min_x_ = std::min(min_x_, x);
  max_x_ = std::max(max_x_, x);
  min_y_ = std::min(min_y_, y);
  max_y_ = std::max(max_y_, y);
}
void SvgPicture::line(double x0, double y0, double x1, double y1, const std::string& stroke, double width,
                      const std::string& dash) {
  include(x0, y0);
  include(x1, y1);
  body_ += "<line x1=\"" + fmt(x0) + "\" y1=\"" + fmt(y0) + "\" x2=\"" + fmt(x1) + "\" y2=\"" + fmt(y1) +
           "\" stroke=\"" + stroke + "\" stroke-width=\"" + fmt(width) + "\"" +
           (dash.empty() ? "" : " stroke-dasharray=\"" + dash + "\"") + "/>\n";
}
void SvgPicture::polyline(const std::vector<std::array<double, 2>>& points, const std::string& stroke, double width) {
  std::string pts;
  for (const auto& p : points) {
    include(p[0], p[1]);
    pts += (pts.empty() ? "" : " ") + fmt(p[0]) + "," + fmt(p[1]);
  }
  body_ += "<polyline points=\"" + pts + "\" fill=\"none\" stroke=\"" + stroke + "\" stroke-width=\"" + fmt(width) +
           "\"/>\n";
}
void SvgPicture::rect(double x, double y, double w, double h, const std::string& fill, double opacity,
                      const std::string& stroke) {
  include(x, y);
  include(x + w, y + h);
  body_ += "<rect x=\"" + fmt(x) + "\" y=\"" + fmt(y) + "\" width=\"" + fmt(w) + "\" height=\"" + fmt(h) +
           "\" fill=\"" + fill + "\" fill-opacity=\"" + fmt(opacity) + "\"" +
           (stroke.empty() ? "" : " stroke=\"" + stroke + "\"") + "/>\n";
}
void SvgPicture::circle(double x, double y, double r, const std::string& fill) {
  include(x - r, y - r);
  include(x + r, y + r);
  body_ += "<circle cx=\"" + fmt(x) + "\" cy=\"" + fmt(y) + "\" r=\"" + fmt(r) + "\" fill=\"" + fill + "\"/>\n";
}
void SvgPicture::text(double x, double y, const std::string& s, double size, const std::string& anchor,
                      double rotate_deg, const std::string& fill) {
  // The unrotated box relative to (x, y): 0.6 em per character, ascent 1 em, descent 0.25 em.
  const double w = 0.6 * size * static_cast<double>(s.size());
  const double left = anchor == "middle" ? -w / 2 : anchor == "end" ? -w : 0.0;
  const double c = std::cos(rotate_deg * M_PI / 180), sn = std::sin(rotate_deg * M_PI / 180);
  for (double dx : {left, left + w})
    for (double dy : {-size, 0.25 * size}) include(x + c * dx - sn * dy, y + sn * dx + c * dy);
  body_ += "<text x=\"" + fmt(x) + "\" y=\"" + fmt(y) + "\" font-family=\"sans-serif\" font-size=\"" + fmt(size) +
           "\" text-anchor=\"" + anchor + "\" fill=\"" + fill + "\"" +
           (rotate_deg != 0 ? " transform=\"rotate(" + fmt(rotate_deg) + " " + fmt(x) + " " + fmt(y) + ")\"" : "") +
           ">" + escape_xml(s) + "</text>\n";
}
std::string SvgPicture::finish(double margin) const {
  const bool empty = !(min_x_ <= max_x_);
  const double x = empty ? 0 : min_x_ - margin, y = empty ? 0 : min_y_ - margin;
  const double w = empty ? 1 : max_x_ - min_x_ + 2 * margin, h = empty ? 1 : max_y_ - min_y_ + 2 * margin;
  return "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + fmt(w) + "\" height=\"" + fmt(h) + "\" viewBox=\"" +
         fmt(x) + " " + fmt(y) + " " + fmt(w) + " " + fmt(h) + "\">\n<rect x=\"" + fmt(x) + "\" y=\"" + fmt(y) +
         "\" width=\"" + fmt(w) + "\" height=\"" + fmt(h) + "\" fill=\"white\"/>\n" + body_ + "</svg>\n";
}
bool SvgPicture::save(const std::string& path) const {
  std::ofstream f(path);
  f << finish();
  return static_cast<bool>(f);
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
    case kBuilding: return "#ffc800";
    case kFence: return "#ff7832";
    case kVegetation: return "#00af00";
    case kTrunk: return "#873c00";
    case kTerrain: return "#96f050";
    case kPole: return "#0080ff";  // darker than SemanticKITTI's pale blue, readable on white
    case kTrafficSign: return "#ff0000";
    default: return "#888888";
  }
}

}  // namespace gsf::cli
