#pragma once
// Scalar building blocks of the perturbation kernel (see perturb.hpp), shared by the scalar
// reference and as the specification every SIMD twin mirrors operation by operation.
// Internal linkage (an unnamed namespace): each translation unit, compiled with its own
// instruction-set flags, keeps its own copy (see nearest_two_reference.hpp).
#include <cstdint>
#include <cstring>

#include "rgbd_odometry/simd/perturb.hpp"
#include "rgbd_odometry/core/splitmix64.hpp"

namespace rgbdo::simd::reference {
namespace {

// Seeds lane l's xoshiro128+ state from the kernel seed (splitmix64, never all zero).
inline void seed_lane(std::uint64_t seed, int lane, std::uint32_t state[4]) {
  std::uint64_t x = seed ^ (0xD1B54A32D192ED03ULL * static_cast<std::uint64_t>(lane + 1));
  for (int i = 0; i < 4; ++i) state[i] = static_cast<std::uint32_t>(splitmix64_next(x) >> 32) | (i == 0 ? 1u : 0u);
}

inline std::uint32_t next(std::uint32_t s[4]) {  // xoshiro128+
  const std::uint32_t result = s[0] + s[3];
  const std::uint32_t t = s[1] << 9;
  s[2] ^= s[0];
  s[3] ^= s[1];
  s[1] ^= s[2];
  s[0] ^= s[3];
  s[2] ^= t;
  s[3] = (s[3] << 11) | (s[3] >> 21);
  return result;
}

// Top 23 bits to (0, 1), every value exactly representable: never 0 (log) and never 1.
// (With 24 bits, (2^24 - 1) + 0.5 needs 25 significant bits and rounds to exactly 1.)
inline float to_unit(std::uint32_t x) { return (static_cast<float>(x >> 9) + 0.5f) * 0x1.0p-23f; }

// Natural log on (0, 1): exponent from the bits, mantissa folded into [sqrt(1/2), sqrt(2)),
// ln m = 2 atanh(s) with s = (m - 1) / (m + 1), |s| < 0.172, series to s^9 (error < 1e-9).
inline float log_unit(float u) {
  std::uint32_t bits;
  std::memcpy(&bits, &u, 4);
  float e = static_cast<float>(static_cast<std::int32_t>(bits >> 23) - 127);
  const std::uint32_t mbits = (bits & 0x007FFFFFu) | 0x3F800000u;
  float m;
  std::memcpy(&m, &mbits, 4);
  if (m > 1.41421356f) {
    m = m * 0.5f;
    e = e + 1.0f;
  }
  const float s = (m - 1.0f) / (m + 1.0f);
  const float s2 = s * s;
  const float series = 1.0f + s2 * (0.333333333f + s2 * (0.2f + s2 * (0.142857143f + s2 * 0.111111111f)));
  return e * 0.693147181f + 2.0f * s * series;
}

// sin and cos of 2 pi t for t in (-1/2, 1/2), folded to |x| <= pi/2 (Taylor to x^11 / x^12).
inline void sincos_turns(float t, float& sin_out, float& cos_out) {
  float sign = 1.0f;
  if (t > 0.25f) {
    t = 0.5f - t;
    sign = -1.0f;
  } else if (t < -0.25f) {
    t = -0.5f - t;
    sign = -1.0f;
  }
  const float x = t * 6.28318531f;
  const float x2 = x * x;
  sin_out = x * (1.0f + x2 * (-1.66666667e-1f + x2 * (8.33333333e-3f + x2 * (-1.98412698e-4f +
                                                                            x2 * (2.75573192e-6f + x2 * -2.50521084e-8f)))));
  cos_out = sign * (1.0f + x2 * (-0.5f + x2 * (4.16666667e-2f + x2 * (-1.38888889e-3f + x2 * (2.48015873e-5f +
                                                                                            x2 * (-2.75573192e-7f + x2 * 2.08767570e-9f))))));
}

// Box-Muller: two independent standard normals from two uniforms.
inline void box_muller(std::uint32_t a, std::uint32_t b, float& z0, float& z1) {
  const float r = __builtin_sqrtf(-2.0f * log_unit(to_unit(a)));
  float s, c;
  sincos_turns(to_unit(b) - 0.5f, s, c);
  z0 = r * c;
  z1 = r * s;
}

}  // namespace
}  // namespace rgbdo::simd::reference
