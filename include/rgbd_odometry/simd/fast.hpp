#pragma once
// Kernel interfaces for the FAST-9 segment test (Rosten & Drummond) over a run of one row:
// for each of the n pixels from `row` on, flags[i] = 1 when 9 contiguous pixels of its
// radius-3 circle are brighter than centre + threshold, 2 when 9 are darker than
// centre - threshold, 3 both (possible only at threshold 0), 0 neither. The caller keeps 3
// pixels of image on every side of the run. Flags are booleans of integer comparisons, so
// every twin is bit-exact against simd/scalar/fast_scalar.cpp.
#include <cstddef>
#include <cstdint>

namespace rgbdo::simd {

#define RGBDO_FAST9_ROW(name) \
  void name(const std::uint8_t* row, std::ptrdiff_t stride, int n, int threshold, std::uint8_t* flags)
RGBDO_FAST9_ROW(fast9_row_scalar);  // simd/scalar/fast_scalar.cpp, the reference
RGBDO_FAST9_ROW(fast9_row_avx2);    // simd/x86/fast_avx2.cpp
RGBDO_FAST9_ROW(fast9_row_neon);    // simd/arm/fast_neon.cpp

// The score of a pixel the segment test flagged (FAST-ER's SAD score): over its 16 circle
// pixels (at p + offsets[k]), the summed excess over centre + threshold of the brighter ones
// when flags has bit 1, over centre - threshold of the darker ones when it has bit 2, the larger
// of the two when both. Integer sums: every twin is bit-exact against the reference.
#define RGBDO_FAST9_SCORE(name) \
  int name(const std::uint8_t* p, const std::ptrdiff_t* offsets, int threshold, int flags)
RGBDO_FAST9_SCORE(fast9_score_scalar);  // simd/scalar/fast_scalar.cpp, the reference
RGBDO_FAST9_SCORE(fast9_score_neon);    // simd/arm/fast_neon.cpp

// FAST's Bresenham circle of radius 3, clockwise from the top: (dx, dy).
inline constexpr int kFastCircle[16][2] = {{0, -3}, {1, -3},  {2, -2},  {3, -1}, {3, 0},   {3, 1},   {2, 2},   {1, 3},
                                           {0, 3},  {-1, 3}, {-2, 2}, {-3, 1}, {-3, 0}, {-3, -1}, {-2, -2}, {-1, -3}};

}  // namespace rgbdo::simd
