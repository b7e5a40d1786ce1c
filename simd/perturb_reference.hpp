#pragma once
// Building blocks of the perturbation kernel (see perturb.hpp): the random streams, and the
// normal draws written once over a lane type, which the scalar reference and every SIMD twin
// instantiate with their own operations.
// Internal linkage (an unnamed namespace): each translation unit, compiled with its own
// instruction-set flags, keeps its own copy (see nearest_two_reference.hpp).
#include <cstddef>
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

// xoshiro128+ one step in every lane (Ops as below, with its integer operations).
template <class Ops>
typename Ops::U next_of(typename Ops::U s[4]) {
  const typename Ops::U result = Ops::add_u(s[0], s[3]);
  const typename Ops::U t = Ops::template shift_left<9>(s[1]);
  s[2] = Ops::xor_u(s[2], s[0]);
  s[3] = Ops::xor_u(s[3], s[1]);
  s[1] = Ops::xor_u(s[1], s[2]);
  s[0] = Ops::xor_u(s[0], s[3]);
  s[2] = Ops::xor_u(s[2], t);
  s[3] = Ops::or_u(Ops::template shift_left<11>(s[3]), Ops::template shift_right<21>(s[3]));
  return result;
}

// The normal draws, written once for every lane type: `Ops` gives a kernel set's lanes (F floats,
// U uint32s, M masks) these operations, each one IEEE operation per lane (a set without a vector
// divide or square root says how it comes close):
//   F set(float); F add(F, F); F sub(F, F); F mul(F, F); F div(F, F); F sqrt(F) (of x >= 0);
//   M greater(F, F); M less(F, F); M either(M, M); F select(M, F where_true, F where_false);
//   F unit(U): the top 23 bits to (0, 1) (to_unit below);
//   U add_u(U, U); U xor_u(U, U); U or_u(U, U); U shift_left<N>(U); U shift_right<N>(U) (next_of);
//   void split(F u, F& exponent, F& mantissa): u's exponent as a float and its mantissa in [1, 2).
// The scalar reference is the same code with ScalarOps: the twins agree with it operation by
// operation, in the same order.

// The series' coefficients, innermost first (Horner: acc = c + x2 acc).
inline constexpr float kLogSeries[] = {0.111111111f, 0.142857143f, 0.2f, 0.333333333f, 1.0f};
inline constexpr float kSinSeries[] = {-2.50521084e-8f, 2.75573192e-6f, -1.98412698e-4f, 8.33333333e-3f,
                                       -1.66666667e-1f, 1.0f};
inline constexpr float kCosSeries[] = {2.08767570e-9f, -2.75573192e-7f, 2.48015873e-5f, -1.38888889e-3f,
                                       4.16666667e-2f, -0.5f, 1.0f};

template <class Ops, std::size_t N>
typename Ops::F horner(typename Ops::F x2, const float (&c)[N]) {
  typename Ops::F acc = Ops::set(c[0]);
  for (std::size_t i = 1; i < N; ++i) acc = Ops::add(Ops::set(c[i]), Ops::mul(x2, acc));
  return acc;
}

// Natural log on (0, 1): exponent from the bits, mantissa folded into [sqrt(1/2), sqrt(2)),
// ln m = 2 atanh(s) with s = (m - 1) / (m + 1), |s| < 0.172, series to s^9 (error < 1e-9).
template <class Ops>
typename Ops::F log_unit_of(typename Ops::F u) {
  using F = typename Ops::F;
  F e, m;
  Ops::split(u, e, m);
  const auto fold = Ops::greater(m, Ops::set(1.41421356f));
  m = Ops::select(fold, Ops::mul(m, Ops::set(0.5f)), m);
  e = Ops::select(fold, Ops::add(e, Ops::set(1.0f)), e);
  const F one = Ops::set(1.0f);
  const F s = Ops::div(Ops::sub(m, one), Ops::add(m, one));
  const F series = horner<Ops>(Ops::mul(s, s), kLogSeries);
  return Ops::add(Ops::mul(e, Ops::set(0.693147181f)), Ops::mul(Ops::mul(Ops::set(2.0f), s), series));
}

// sin and cos of 2 pi t for t in (-1/2, 1/2), folded to |x| <= pi/2 (Taylor to x^11 / x^12).
template <class Ops>
void sincos_turns_of(typename Ops::F t, typename Ops::F& sin_out, typename Ops::F& cos_out) {
  using F = typename Ops::F;
  const auto upper = Ops::greater(t, Ops::set(0.25f));
  const auto lower = Ops::less(t, Ops::set(-0.25f));
  const F sign = Ops::select(Ops::either(upper, lower), Ops::set(-1.0f), Ops::set(1.0f));
  t = Ops::select(upper, Ops::sub(Ops::set(0.5f), t), t);
  t = Ops::select(lower, Ops::sub(Ops::set(-0.5f), t), t);
  const F x = Ops::mul(t, Ops::set(6.28318531f));
  const F x2 = Ops::mul(x, x);
  sin_out = Ops::mul(x, horner<Ops>(x2, kSinSeries));
  cos_out = Ops::mul(sign, horner<Ops>(x2, kCosSeries));
}

// Box-Muller: two independent standard normals from two uniforms.
template <class Ops>
void box_muller_of(typename Ops::U a, typename Ops::U b, typename Ops::F& z0, typename Ops::F& z1) {
  const typename Ops::F r = Ops::sqrt(Ops::mul(Ops::set(-2.0f), log_unit_of<Ops>(Ops::unit(a))));
  typename Ops::F s, c;
  sincos_turns_of<Ops>(Ops::sub(Ops::unit(b), Ops::set(0.5f)), s, c);
  z0 = Ops::mul(r, c);
  z1 = Ops::mul(r, s);
}

// One point's contribution to a block of perturbations, one vector of lanes (its random state
// `state`, its weights `w`): six normal draws (the keypoint's two lateral errors and its depth
// along the viewing ray, in each frame), the perturbed points s (current frame) and d
// (previous), and their weighted sums S, D and outer products M.
template <class Ops>
void accumulate_point_of(const PerturbationInput& in, int k, typename Ops::F w, typename Ops::U state[4],
                         typename Ops::F S[3], typename Ops::F D[3], typename Ops::F M[9]) {
  using F = typename Ops::F;
  F n[6];
  for (int pair = 0; pair < 3; ++pair) {
    const typename Ops::U a = next_of<Ops>(state);
    const typename Ops::U c = next_of<Ops>(state);
    box_muller_of<Ops>(a, c, n[2 * pair], n[2 * pair + 1]);
  }
  const auto add_mul = [](F base, float sigma, F x) { return Ops::add(base, Ops::mul(Ops::set(sigma), x)); };
  const F s[3] = {add_mul(add_mul(Ops::set(in.sx[k]), in.sigma_sx[k], n[0]), in.ray_sx[k], n[2]),
                  add_mul(add_mul(Ops::set(in.sy[k]), in.sigma_sy[k], n[1]), in.ray_sy[k], n[2]),
                  add_mul(Ops::set(in.sz[k]), in.ray_sz[k], n[2])};
  const F d[3] = {add_mul(add_mul(Ops::set(in.dx[k]), in.sigma_dx[k], n[3]), in.ray_dx[k], n[5]),
                  add_mul(add_mul(Ops::set(in.dy[k]), in.sigma_dy[k], n[4]), in.ray_dy[k], n[5]),
                  add_mul(Ops::set(in.dz[k]), in.ray_dz[k], n[5])};
  F ws[3];
  for (int j = 0; j < 3; ++j) {
    ws[j] = Ops::mul(w, s[j]);
    S[j] = Ops::add(S[j], ws[j]);
    D[j] = Ops::add(D[j], Ops::mul(w, d[j]));
  }
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) M[3 * i + j] = Ops::add(M[3 * i + j], Ops::mul(d[i], ws[j]));
}

// Top 23 bits to (0, 1), every value exactly representable: never 0 (log) and never 1.
// (With 24 bits, (2^24 - 1) + 0.5 needs 25 significant bits and rounds to exactly 1.)
inline float to_unit(std::uint32_t x) { return (static_cast<float>(x >> 9) + 0.5f) * 0x1.0p-23f; }

struct ScalarOps {
  using F = float;
  using U = std::uint32_t;
  using M = bool;
  static F set(float v) { return v; }
  static F add(F a, F b) { return a + b; }
  static F sub(F a, F b) { return a - b; }
  static F mul(F a, F b) { return a * b; }
  static F div(F a, F b) { return a / b; }
  static F sqrt(F x) { return __builtin_sqrtf(x); }
  static M greater(F a, F b) { return a > b; }
  static M less(F a, F b) { return a < b; }
  static M either(M a, M b) { return a || b; }
  static F select(M m, F where_true, F where_false) { return m ? where_true : where_false; }
  static F unit(U x) { return to_unit(x); }
  static U add_u(U a, U b) { return a + b; }
  static U xor_u(U a, U b) { return a ^ b; }
  static U or_u(U a, U b) { return a | b; }
  template <int N>
  static U shift_left(U x) { return x << N; }
  template <int N>
  static U shift_right(U x) { return x >> N; }
  static void split(F u, F& exponent, F& mantissa) {
    std::uint32_t bits;
    std::memcpy(&bits, &u, 4);
    exponent = static_cast<float>(static_cast<std::int32_t>(bits >> 23) - 127);
    const std::uint32_t mbits = (bits & 0x007FFFFFu) | 0x3F800000u;
    std::memcpy(&mantissa, &mbits, 4);
  }
};

inline std::uint32_t next(std::uint32_t s[4]) { return next_of<ScalarOps>(s); }

inline float log_unit(float u) { return log_unit_of<ScalarOps>(u); }

inline void box_muller(std::uint32_t a, std::uint32_t b, float& z0, float& z1) {
  box_muller_of<ScalarOps>(a, b, z0, z1);
}

}  // namespace
}  // namespace rgbdo::simd::reference
