// Reference Hamming nearest-two kernel: the plain loop of nearest_two_reference.hpp,
// compiled for the baseline instruction set. The SIMD twins (simd/arm, simd/x86) must
// reproduce its output bit for bit.
#include "nearest_two_reference.hpp"

namespace rgbdo::simd {

RGBDO_HAMMING_KERNELS_FROM_REFERENCE(scalar)

}  // namespace rgbdo::simd
