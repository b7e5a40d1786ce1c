// SSE4.2-era twin of simd/scalar/hamming_scalar.cpp: the same loop, compiled with -mpopcnt
// so that each 64-bit word costs one POPCNT instruction instead of a bit-twiddling sequence.
#include "nearest_two_reference.hpp"

namespace rgbdo::simd {

RGBDO_HAMMING_KERNELS_FROM_REFERENCE(popcnt)

}  // namespace rgbdo::simd
