#pragma once
// The compiled kernel sets this CPU can run (scalar last): the kernel tests compare each of
// them with the scalar reference.
#include <vector>

#include "rgbd_odometry/simd/kernels.hpp"

namespace rgbdo {

inline std::vector<const simd::KernelSet*> runnable_sets() {
  std::vector<const simd::KernelSet*> sets;
  for (const auto& s : simd::compiled_kernel_sets())
    if (simd::cpu_supports(s)) sets.push_back(&s);
  return sets;
}

}  // namespace rgbdo
