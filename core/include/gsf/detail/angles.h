// Internal (gsf/detail): a building block, not part of the stable interface; it may change between versions.
// The library's angle constants, written once. Each call site keeps the arithmetic it had (x * kPi / 180,
// x * kRadPerDeg or x / kDegPerRad round differently in the last bit), so results are bit for bit those
// of before.
#pragma once

namespace gsf {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegPerRad = 180.0 / kPi;  // the double nearest 57.29577951308232
constexpr double kRadPerDeg = kPi / 180.0;
constexpr double kTwoPi = 2.0 * kPi;  // exactly the double 6.283185307179586 (doubling is exact)

// Degrees to radians as (deg * pi) / 180, the form most stages used.
constexpr double deg_to_rad(double deg) { return deg * kPi / 180.0; }

}  // namespace gsf
