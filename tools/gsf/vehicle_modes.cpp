#include "vehicle_modes.h"

#include <cmath>
#include <cstdlib>
#include <sstream>
#include <vector>

namespace gsf::cli {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A small seeded generator (splitmix64): the same draws on every platform and standard library.
struct Draws {
  uint64_t state;
  uint64_t next() {
    uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double uniform() { return (double(next() >> 11) + 0.5) / 9007199254740992.0; }  // (0, 1)
  double normal() { return std::sqrt(-2.0 * std::log(uniform())) * std::cos(2.0 * kPi * uniform()); }
};

Draws draws_for(uint64_t seed, uint64_t salt, uint32_t index) {
  Draws d{seed * 0x2545F4914F6CDD1Dull ^ (salt << 32) ^ index};
  d.next();
  return d;
}

}  // namespace

bool parse_prior(const std::string& text, PositionPrior* out, std::string* error) {
  std::vector<double> v;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    char* end = nullptr;
    const double x = std::strtod(item.c_str(), &end);
    if (item.empty() || end == item.c_str() || *end != '\0') {
      *error = "--prior: '" + item + "' is not a number";
      return false;
    }
    v.push_back(x);
  }
  if (v.size() != 3 && v.size() != 5) {
    *error = "--prior must be x,y,radius or x,y,radius,heading_deg,tolerance_deg";
    return false;
  }
  PositionPrior p;
  p.x = v[0];
  p.y = v[1];
  p.radius_m = static_cast<float>(v[2]);
  if (v.size() == 5) {
    p.has_heading = true;
    p.heading_deg = static_cast<float>(v[3]);
    p.heading_tolerance_deg = static_cast<float>(v[4]);
  }
  if (validate(p) != Status::Ok) {
    *error = "--prior: invalid (finite values, radius > 0, tolerance in [0, 180])";
    return false;
  }
  *out = p;
  return true;
}

PositionPrior draw_prior(const PriorDraw& d, const Eigen::Isometry3d& truth, uint32_t query) {
  Draws r = draws_for(d.seed, 0x5052, query);
  const double direction = 2.0 * kPi * r.uniform();
  PositionPrior p;
  p.x = truth.translation().x() + d.bias * std::cos(direction) + d.sigma * r.normal();
  p.y = truth.translation().y() + d.bias * std::sin(direction) + d.sigma * r.normal();
  p.radius_m = static_cast<float>(d.radius);
  if (d.heading_tolerance_deg > 0) {  // drawn after the position, so the positions do not change with it
    const Eigen::Matrix3d R = truth.linear();
    const double yaw = std::atan2(R(1, 0), R(0, 0)) * 180.0 / kPi + d.heading_tolerance_deg / 3.0 * r.normal();
    p.has_heading = true;
    p.heading_deg = static_cast<float>(std::remainder(yaw, 360.0));
    p.heading_tolerance_deg = static_cast<float>(d.heading_tolerance_deg);
  }
  return p;
}

Eigen::Isometry3d noisy_odometry(const Eigen::Isometry3d& from, const Eigen::Isometry3d& to, double noise,
                                 uint64_t seed, uint32_t scan) {
  Eigen::Isometry3d odo = from.inverse() * to;
  if (noise <= 0) return odo;
  Draws r = draws_for(seed, 0x4F44, scan);
  const double step = odo.translation().norm();
  odo.translation().x() += noise * step * r.normal();
  odo.translation().y() += noise * step * r.normal();
  const double yaw = noise * step * (10.0 * kPi / 180.0) * r.normal();
  odo.linear() = odo.linear() * Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return odo;
}

Eigen::Isometry3d offset_prediction(const Eigen::Isometry3d& predicted, double offset, uint64_t seed, uint32_t scan) {
  if (offset <= 0) return predicted;
  Draws r = draws_for(seed, 0x4B4E, scan);
  const double direction = 2.0 * kPi * r.uniform();
  const double distance = offset * r.uniform();
  const double yaw = offset * (2.0 * r.uniform() - 1.0) * kPi / 180.0;
  Eigen::Isometry3d p = predicted;
  p.translation().x() += distance * std::cos(direction);
  p.translation().y() += distance * std::sin(direction);
  p.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix() * p.linear();
  return p;
}

}  // namespace gsf::cli
