#pragma once
// The project's random numbers: bit-identical on every architecture, cheap on ARMv7.
// std::uniform_int_distribution and friends are implementation-defined (libstdc++ takes a
// 128-bit multiply path on x86-64 and a division path on 32-bit ARM), so a replay would
// not reproduce across the x86 CI and the Odroid. xoshiro128** uses only 32-bit operations.
#include <array>
#include <cmath>
#include <cstdint>

#include "rgbd_odometry/core/splitmix64.hpp"

namespace rgbdo {

class Rng {
 public:
  explicit Rng(std::uint64_t seed) {
    // splitmix64 expands the seed (never an all-zero state).
    for (auto& s : state_) s = static_cast<std::uint32_t>(splitmix64_next(seed) >> 32);
  }
  // The generator's raw state, as the reference implementation takes it (must not be all zero).
  explicit Rng(const std::array<std::uint32_t, 4>& state) : state_{state[0], state[1], state[2], state[3]} {}

  std::uint32_t next_u32() {  // xoshiro128** 1.1 (Blackman & Vigna)
    const std::uint32_t result = rotl(state_[1] * 5, 7) * 9;
    const std::uint32_t t = state_[1] << 9;
    state_[2] ^= state_[0];
    state_[3] ^= state_[1];
    state_[1] ^= state_[2];
    state_[0] ^= state_[3];
    state_[2] ^= t;
    state_[3] = rotl(state_[3], 11);
    return result;
  }

  // Uniform in [0, n), n > 0, without modulo bias (Lemire's multiply-shift with rejection).
  std::uint32_t below(std::uint32_t n) {
    std::uint64_t m = static_cast<std::uint64_t>(next_u32()) * n;
    auto low = static_cast<std::uint32_t>(m);
    if (low < n) {
      const std::uint32_t threshold = (0u - n) % n;
      while (low < threshold) {
        m = static_cast<std::uint64_t>(next_u32()) * n;
        low = static_cast<std::uint32_t>(m);
      }
    }
    return static_cast<std::uint32_t>(m >> 32);
  }

  // Uniform in [0, 1) with 53 random bits.
  double uniform01() {
    const std::uint64_t hi = next_u32() >> 5, lo = next_u32() >> 6;  // 27 + 26 bits
    return static_cast<double>((hi << 26) | lo) * 0x1.0p-53;
  }

  // Standard normal, Marsaglia's polar method (no trigonometry); the spare value is kept.
  double gaussian() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    double u, v, s;
    do {
      u = 2 * uniform01() - 1;
      v = 2 * uniform01() - 1;
      s = u * u + v * v;
    } while (s >= 1 || s == 0);
    const double f = std::sqrt(-2 * std::log(s) / s);
    spare_ = v * f;
    has_spare_ = true;
    return u * f;
  }

 private:
  static std::uint32_t rotl(std::uint32_t x, int k) { return (x << k) | (x >> (32 - k)); }
  std::uint32_t state_[4];
  double spare_ = 0;
  bool has_spare_ = false;
};

}  // namespace rgbdo
