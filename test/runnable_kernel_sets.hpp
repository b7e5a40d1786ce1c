#pragma once
// The compiled kernel sets this CPU can run (scalar last).
#include <string_view>
#include <vector>

#include "rgbd_odometry/simd/kernels.hpp"

namespace rgbdo {

inline std::vector<const simd::KernelSet*> runnable_sets() {
  std::vector<const simd::KernelSet*> sets;
  for (const auto& s : simd::compiled_kernel_sets())
    if (simd::cpu_supports(s)) sets.push_back(&s);
  return sets;
}

// The runnable sets with code of their own for one kernel (`slot`, e.g. &KernelSet::box5_row):
// the scalar reference first, then every set whose kernel there is not the reference's own
// function. A set that borrows the reference for a kernel has nothing of its own to test
// there: comparing it with the reference would compare the reference with itself.
template <typename Fn>
std::vector<const simd::KernelSet*> sets_with_own(Fn simd::KernelSet::*slot) {
  const auto runnable = runnable_sets();
  const simd::KernelSet* reference = nullptr;
  for (const auto* s : runnable)
    if (std::string_view(s->name) == "scalar") reference = s;
  std::vector<const simd::KernelSet*> sets;
  if (reference != nullptr) sets.push_back(reference);
  for (const auto* s : runnable)
    if (s != reference && (reference == nullptr || s->*slot != reference->*slot)) sets.push_back(s);
  return sets;
}

// The same without the reference, for the tests whose expected values are the reference's.
template <typename Fn>
std::vector<const simd::KernelSet*> twins_of_reference(Fn simd::KernelSet::*slot) {
  auto sets = sets_with_own(slot);
  if (!sets.empty() && std::string_view(sets.front()->name) == "scalar") sets.erase(sets.begin());
  return sets;
}

}  // namespace rgbdo
