#include "gsf/position_prior.h"

#include <cmath>

#include "gsf/detail/angles.h"

namespace gsf {
namespace {

// |a - b| wrapped to [0, pi].
double angle_between(double a, double b) {
  double d = std::fmod(std::fabs(a - b), 2.0 * kPi);
  return d > kPi ? 2.0 * kPi - d : d;
}

}  // namespace

Status validate(const PositionPrior& p) {
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.radius_m) || !(p.radius_m > 0.0f))
    return Status::InvalidArgument;
  if (p.has_heading &&
      (!std::isfinite(p.heading_deg) || !(p.heading_tolerance_deg >= 0.0f) || !(p.heading_tolerance_deg <= 180.0f)))
    return Status::InvalidArgument;
  return Status::Ok;
}

PriorRegion prior_region(const PositionPrior& p, const MapGeoreference& georef) {
  PriorRegion r;
  // The centre relative to the origin in double, then float: what the map's own coordinates are.
  r.cx = static_cast<float>(p.x - georef.origin[0]);
  r.cy = static_cast<float>(p.y - georef.origin[1]);
  r.radius = p.radius_m;
  r.has_heading = p.has_heading;
  r.heading = static_cast<float>(double(p.heading_deg) * kRadPerDeg);
  r.tolerance = static_cast<float>(double(p.heading_tolerance_deg) * kRadPerDeg);
  return r;
}

bool PriorRegion::contains(const Eigen::Isometry3d& T, double slack_m, double slack_deg) const {
  const double dx = T.translation().x() - cx, dy = T.translation().y() - cy, r = double(radius) + slack_m;
  if (dx * dx + dy * dy > r * r) return false;
  if (!has_heading) return true;
  const double yaw = std::atan2(T.linear()(1, 0), T.linear()(0, 0));
  return angle_between(yaw, heading) <= double(tolerance) + slack_deg * kRadPerDeg;
}

}  // namespace gsf
