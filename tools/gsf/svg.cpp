#include "svg.h"

#include <algorithm>
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
  std::string esc;
  for (char c : s) esc += c == '<' ? std::string("&lt;") : c == '&' ? std::string("&amp;") : std::string(1, c);
  body_ += "<text x=\"" + fmt(x) + "\" y=\"" + fmt(y) + "\" font-family=\"sans-serif\" font-size=\"" + fmt(size) +
           "\" fill=\"" + fill + "\">" + esc + "</text>\n";
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
