// Dependency-free SVG output for the evaluation pictures (map + trajectory, correspondences, the
// confidence's reliability diagram).
#pragma once
#include <array>
#include <limits>
#include <string>
#include <vector>

namespace gsf::cli {

// World-to-picture mapping for a bounding box; y is flipped so north is up.
class SvgCanvas {
 public:
  SvgCanvas(double min_x, double min_y, double max_x, double max_y, double width_px);
  void circle(double x, double y, double r_px, const std::string& fill, double opacity = 1.0);
  void line(double x0, double y0, double x1, double y1, const std::string& stroke, double width_px,
            double opacity = 1.0);
  void text(double x, double y, const std::string& s, double size_px, const std::string& fill = "#222");
  // Text at pixel coordinates (legends, titles).
  void text_px(double px, double py, const std::string& s, double size_px, const std::string& fill = "#222");
  void rect_px(double px, double py, double w, double h, const std::string& fill);
  std::string finish() const;
  bool save(const std::string& path) const;
  double width() const { return width_; }
  double height() const { return height_; }

 private:
  double px(double x) const { return (x - min_x_) * scale_ + margin_; }
  double py(double y) const { return (max_y_ - y) * scale_ + margin_; }
  double min_x_, max_y_, scale_, width_, height_, margin_ = 20;
  std::string body_;
};

// Charts in pixel coordinates (y grows downwards). The viewBox is computed from what was drawn: the
// bounding box of every element (text estimated at 0.6 em per character, rotation included) plus a
// margin, so the picture always fits its content.
class SvgPicture {
 public:
  // dash: an SVG stroke-dasharray such as "6 4" (empty: solid).
  void line(double x0, double y0, double x1, double y1, const std::string& stroke, double width,
            const std::string& dash = "");
  void polyline(const std::vector<std::array<double, 2>>& points, const std::string& stroke, double width);
  void rect(double x, double y, double w, double h, const std::string& fill, double opacity = 1.0,
            const std::string& stroke = "");
  void circle(double x, double y, double r, const std::string& fill);
  // anchor: start, middle or end; rotate_deg turns the text about (x, y) (-90: reads upwards).
  void text(double x, double y, const std::string& s, double size, const std::string& anchor = "start",
            double rotate_deg = 0, const std::string& fill = "#222");
  std::string finish(double margin = 10) const;
  bool save(const std::string& path) const;

 private:
  void include(double x, double y);
  std::string body_;
  double min_x_ = std::numeric_limits<double>::infinity(), min_y_ = min_x_;
  double max_x_ = -std::numeric_limits<double>::infinity(), max_y_ = max_x_;
};

// A colour per dense semantic class (SemanticKITTI's palette where it has one).
std::string class_colour(int dense_class);

}  // namespace gsf::cli
