// Dependency-free SVG output for the pictures the tools write (map + trajectory, correspondences, the
// confidence's reliability diagram, bench_pole_picture), and their conversion to PNG.
#pragma once
#include <array>
#include <functional>
#include <limits>
#include <string>
#include <vector>

namespace gsf::cli {

// A picture in pixel coordinates (y grows downwards). The viewBox is computed from what was drawn: the
// bounding box of every element (text estimated at 0.6 em per character, rotation included; strokes and
// circle radii included) plus a margin, so the picture always fits its content and crops nothing.
class SvgPicture {
 public:
  struct Box {
    double min_x = std::numeric_limits<double>::infinity(), min_y = min_x;
    double max_x = -std::numeric_limits<double>::infinity(), max_y = max_x;
    bool empty() const { return !(min_x <= max_x); }
  };
  // dash: an SVG stroke-dasharray such as "6 4" (empty: solid).
  // round: round line caps (a very short line still shows as a dash).
  void line(double x0, double y0, double x1, double y1, const std::string& stroke, double width,
            const std::string& dash = "", double opacity = 1.0, bool round = false);
  void polyline(const std::vector<std::array<double, 2>>& points, const std::string& stroke, double width);
  void polygon(const std::vector<std::array<double, 2>>& points, const std::string& fill,
               const std::string& stroke = "", double stroke_width = 1);
  void rect(double x, double y, double w, double h, const std::string& fill, double opacity = 1.0,
            const std::string& stroke = "");
  // fill "none" with a stroke draws a ring.
  void circle(double x, double y, double r, const std::string& fill, double opacity = 1.0,
              const std::string& stroke = "", double stroke_width = 1);
  // anchor: start, middle or end; rotate_deg turns the text about (x, y) (-90: reads upwards).
  void text(double x, double y, const std::string& s, double size, const std::string& anchor = "start",
            double rotate_deg = 0, const std::string& fill = "#222", bool bold = false);
  // The extent of everything drawn so far (empty before anything is drawn).
  const Box& extent() const { return box_; }
  std::string finish(double margin = 12) const;
  bool save(const std::string& path) const;

 private:
  void include(double x, double y, double pad = 0);
  std::string body_;
  Box box_;
};

// World metres -> picture pixels for a bird's-eye map, north up: px = (x - x0) * scale, py = (y0 - y) * scale.
struct MapProjection {
  double x0 = 0, y0 = 0, scale = 1;  // scale: pixels per metre
  double px(double x) const { return (x - x0) * scale; }
  double py(double y) const { return (y0 - y) * scale; }
};
// The projection that fits the box [min, max] (metres) into max_width x max_height pixels.
MapProjection fit_projection(double min_x, double min_y, double max_x, double max_y, double max_width,
                             double max_height);

// A scale bar of a round length (1, 2 or 5 x 10^k m) close to target_px pixels, its left end at (x, y).
void draw_scale_bar(SvgPicture& svg, double x, double y, double px_per_m, double target_px = 140);

// One legend row: a swatch drawn centred at (cx, cy) and its label.
struct LegendEntry {
  std::function<void(SvgPicture&, double cx, double cy)> swatch;
  std::string label;
};
LegendEntry legend_dot(const std::string& colour, double r, const std::string& label, double opacity = 1.0);
LegendEntry legend_ring(const std::string& colour, double r, const std::string& label, double width = 1.5);
LegendEntry legend_line(const std::string& colour, double width, const std::string& label, const std::string& dash = "",
                        double opacity = 1.0);
LegendEntry legend_cross(const std::string& colour, double half, const std::string& label, double width = 1.5);
LegendEntry legend_square(const std::string& colour, double side, const std::string& label);
// A framed legend with its top-left corner at (x, y): an optional bold title, then one row per entry.
// Returns its frame.
SvgPicture::Box draw_legend(SvgPicture& svg, double x, double y, const std::vector<LegendEntry>& entries,
                            const std::string& title = "", double font = 12);

// A colour per dense semantic class (SemanticKITTI's palette where it has one).
std::string class_colour(int dense_class);

// PNG output through Debian's librsvg2-bin: the path of `rsvg-convert` on PATH, or "" when it is missing.
std::string find_rsvg_convert();
// Runs `rsvg-convert -o png_path svg_path` (no shell). False with *error set on failure.
bool svg_to_png(const std::string& rsvg_convert, const std::string& svg_path, const std::string& png_path,
                std::string* error);
// The PNG next to an SVG: DIR/name.svg -> DIR/name.png.
std::string png_path_for(const std::string& svg_path);

}  // namespace gsf::cli
