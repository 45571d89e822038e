// Internal to libgsf: a deterministic float exp for non-positive arguments.
#pragma once

#include <cstdint>
#include <cstring>

namespace gsf {
namespace detail {

// exp(x) for x <= 0 (a softmax term l - max, a kernel's -r / l), within 1.4 ulp: Cody-Waite reduction by ln 2 and
// Cephes' degree-5 polynomial in float, with no library call and no branch (the clamp is an integer
// min on the bits), so a loop over it vectorises (glibc's expf was half the voxel layer's and of the
// field probes' instructions). Only +, -, * in a fixed order, and the files using it are compiled
// with -ffp-contract=off (core/CMakeLists.txt): the same bits on x86-64 and ARM64. Below -87 it returns exp(-87)
// = 1.6e-38 (glibc: a smaller subnormal), nothing next to the softmax sum's 1.
inline float exp_nonpositive(float x) {
  uint32_t bits;
  std::memcpy(&bits, &x, sizeof bits);
  const uint32_t minus_87 = 0xC2AE0000u;  // for x <= 0 (sign bit set or +0) a larger pattern is a smaller x
  bits = bits < minus_87 ? bits : minus_87;
  float xc;
  std::memcpy(&xc, &bits, sizeof xc);
  // n = round(x / ln 2) by the 1.5 * 2^23 shifter: its low mantissa bits then hold n as an integer.
  const float shifter = 12582912.0f;
  const float t = xc * 1.44269504088896341f + shifter;
  const float n = t - shifter;
  int32_t t_bits;
  std::memcpy(&t_bits, &t, sizeof t_bits);
  // r = x - n ln 2 with ln 2 split in two (n * 0.693359375 is exact for |n| < 2^15): |r| <= ln 2 / 2.
  float r = xc - n * 0.693359375f;
  r = r - n * -2.12194440e-4f;
  const float r2 = r * r;
  float p = 1.9875691500e-4f;
  p = p * r + 1.3981999507e-3f;
  p = p * r + 8.3334519073e-3f;
  p = p * r + 4.1665795894e-2f;
  p = p * r + 1.6666665459e-1f;
  p = p * r + 5.0000001201e-1f;
  const float e = p * r2 + r + 1.0f;
  const int32_t scale_bits = (t_bits - 0x4B400000 + 127) << 23;  // 2^n, n in [-126, 0]: a normal float
  float scale;
  std::memcpy(&scale, &scale_bits, sizeof scale);
  return e * scale;
}

}  // namespace detail
}  // namespace gsf
