// A position prior for one-shot localization: where the vehicle roughly is (a GNSS fix, the last known
// pose), as a disc in the map's frame and optionally a heading (docs/vehicle-modes.md).
//
// With a prior, Localizer::localize(scan, prior, out) restricts the candidate search itself: a map
// triangle is offered to the matcher only when each of its vertices lies within radius + the range of
// the query vertex it would match (+ kPriorVertexSlackM) of the prior's centre, and pose hypotheses
// outside the disc (or the heading tolerance) are dropped before verification. The confidence is the
// same statistic as without a prior: its shifted and turned probes are geometric and need no other
// candidate; a wrong prior (the truth outside the disc) leaves only wrong hypotheses, which the probes
// and the inlier share judge as they judge any wrong answer, and a thin margin is checked against the
// whole map (Localizer::check_outside_prior). Not caught: a disc holding a turned copy of a repetitive
// scene whose rivals there are weak (2 of 2,044 suite queries with the prior 50 m off); a heading rules
// such a copy out.
#pragma once
#include <Eigen/Geometry>

#include "gsf/georeference.h"
#include "gsf/status.h"

namespace gsf {

struct PositionPrior {
  double x = 0.0, y = 0.0;  // m: the disc's centre in the map's frame (MapView::georef, e.g. UTM metres)
  float radius_m = 0.0f;    // m, > 0: the scan's sensor position lies within this of (x, y)
  bool has_heading = false;
  float heading_deg = 0.0f;              // yaw of map_T_scan (the scan's x axis from the map's x axis, CCW)
  float heading_tolerance_deg = 180.0f;  // [0, 180]: the true yaw lies within this of heading_deg
};

// Query centroids differ from their map instances' by up to about a metre (a partly seen pole, a moved
// car); a map vertex is kept within this much beyond the disc + the query vertex's range.
constexpr float kPriorVertexSlackM = 2.0f;

// InvalidArgument for a non-finite centre, radius or heading, a radius <= 0, or a heading tolerance
// outside [0, 180] deg.
Status validate(const PositionPrior& prior);

// The prior in the map-local frame (what the stages compute in), float metres and radians.
struct PriorRegion {
  float cx = 0.0f, cy = 0.0f;  // map-local centre
  float radius = 0.0f;         // m
  bool has_heading = false;
  float heading = 0.0f, tolerance = 0.0f;  // rad

  // True when a map point (map-local x, y) can be the match of a query point `range` metres (bird's-eye)
  // from the sensor: within radius + range + kPriorVertexSlackM of the centre.
  bool reaches(float x, float y, float range) const {
    const float dx = x - cx, dy = y - cy, r = radius + range + kPriorVertexSlackM;
    return dx * dx + dy * dy <= r * r;
  }
  // True when a pose (map_T_scan, map-local) lies in the disc and heading tolerance, widened by
  // slack_m and slack_deg (a hypothesis is good to about hypotheses.same_pose_m / same_pose_deg).
  bool contains(const Eigen::Isometry3d& map_T_scan, double slack_m, double slack_deg) const;
};

// The prior relative to the map's origin (georef). The prior must be valid.
PriorRegion prior_region(const PositionPrior& prior, const MapGeoreference& georef);

}  // namespace gsf
