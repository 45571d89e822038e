// The CLI's side of the vehicle modes (docs/vehicle-modes.md): position priors from the command line or
// drawn around the ground truth (gsf evaluate --prior-sigma), noisy odometry from the dataset's poses,
// and the tracking evaluation over the simulator's 10 Hz stretches (gsf evaluate --mode track).
#pragma once
#include <cstdint>
#include <string>

#include <Eigen/Geometry>

#include "gsf/position_prior.h"

namespace gsf::cli {

struct EvalOptions;

// "x,y,radius[,heading_deg,tolerance_deg]" (map frame, metres and degrees). False with *error on bad
// text or an invalid prior.
bool parse_prior(const std::string& text, PositionPrior* out, std::string* error);

// A seeded prior around the truth (map frame): centre = truth + `bias` metres in a direction drawn per
// query + N(0, sigma^2) per axis, radius `radius` (> 0). The same (seed, query) gives the same prior.
struct PriorDraw {
  bool enabled = false;
  double sigma = 0, bias = 0, radius = 0;
  // > 0: the prior also carries a heading (a GNSS course over ground), the truth's yaw with
  // N(0, (tolerance / 3)^2) deg of error, this tolerance; a --prior-bias moves the position only.
  double heading_tolerance_deg = 0;
  uint64_t seed = 1;
};
PositionPrior draw_prior(const PriorDraw& draw, const Eigen::Isometry3d& truth, uint32_t query);

// Odometry between two dataset poses (a_T_b = a^-1 b) with seeded noise: each horizontal axis of the
// translation gets N(0, (noise x step)^2) and the yaw N(0, (noise x 10 deg/m x step)^2), step the
// distance travelled (wheel odometry drifting by `noise` of the distance, e.g. 0.02).
Eigen::Isometry3d noisy_odometry(const Eigen::Isometry3d& from, const Eigen::Isometry3d& to, double noise,
                                 uint64_t seed, uint32_t scan);

// A tracking prediction knocked off by a seeded amount (gsf evaluate --mode track --prediction-offset D):
// moved D x U(0, 1) m in a uniform direction and turned D x U(-1, 1) deg. Wrong predictions of every size
// up to D, for measuring (and fitting) the tracking confidence near and beyond the search's reach; a
// broken odometry alone mostly gives poses far from any peak. D = 0 returns `predicted`.
Eigen::Isometry3d offset_prediction(const Eigen::Isometry3d& predicted, double offset, uint64_t seed, uint32_t scan);

// gsf evaluate --mode track: over every stretch of o.sequence (meta.json "stretches"), the first scan
// one-shot (with a prior when o.prior is enabled), then track from the last pose x odometry; a loss (not
// confident) falls back to one-shot on the same scan. Prints the table, writes o.json_out. Returns the
// process exit code.
int run_tracking(const EvalOptions& o);

// gsf evaluate --sequence-window N (run_window.cpp): every scan of o.sequence's stretches through
// Localizer::localize_sequence with window.scans = o.sequence_window, odometry from the dataset's poses
// with o.odometry_noise; the window restarts at each stretch. Prints the table (all scans, the repetitive
// zone's), writes o.json_out. Returns the process exit code.
int run_window(const EvalOptions& o);

}  // namespace gsf::cli
