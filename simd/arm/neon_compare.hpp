#pragma once
// Float compares that stay one NEON instruction. GCC 12's arm_neon.h writes vcgtq_f32,
// vcgeq_f32, vcltq_f32 and vcleq_f32 as generic vector compares, and on ARMv7 (whose NEON
// flushes denormals, so is not IEEE) GCC then does them lane by lane on VFP without
// -funsafe-math-optimizations, which would also let it reassociate the twins' arithmetic: 16
// scalar compares and moves for one vcgt. These emit the instruction itself. Like every NEON
// float operation they treat a denormal as zero; NaN compares false, as IEEE's does.
#include <arm_neon.h>

namespace rgbdo::simd::neon {

inline uint32x4_t greater(float32x4_t a, float32x4_t b) {
  uint32x4_t r;
  asm("vcgt.f32 %q0, %q1, %q2" : "=w"(r) : "w"(a), "w"(b));
  return r;
}

inline uint32x4_t greater_equal(float32x4_t a, float32x4_t b) {
  uint32x4_t r;
  asm("vcge.f32 %q0, %q1, %q2" : "=w"(r) : "w"(a), "w"(b));
  return r;
}

inline uint32x4_t less(float32x4_t a, float32x4_t b) { return greater(b, a); }

}  // namespace rgbdo::simd::neon
