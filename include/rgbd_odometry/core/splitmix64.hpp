#pragma once
// SplitMix64 (Steele, Lea & Flood 2014; the seeding generator Vigna recommends for the
// xoshiro family): one home for its constants, used to expand seeds wherever the project
// seeds a generator (core/rng.hpp, the per-pair streams, the SIMD perturbation lanes).
#include <cstdint>

namespace rgbdo {

inline constexpr std::uint64_t kSplitMix64Increment = 0x9E3779B97F4A7C15ULL;

// The output function: a bijective mix of all 64 bits.
constexpr std::uint64_t splitmix64_mix(std::uint64_t z) {
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

// One step of the generator: advances `state` and returns the next output.
constexpr std::uint64_t splitmix64_next(std::uint64_t& state) {
  state += kSplitMix64Increment;
  return splitmix64_mix(state);
}

}  // namespace rgbdo
