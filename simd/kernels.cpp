#include "kernels.hpp"

#include <cstdlib>
#include <string_view>

namespace rgbdo::simd {
namespace {

constexpr KernelSet kSets[] = {
    {"scalar", nearest_two_hamming_scalar},
};

}  // namespace

std::span<const KernelSet> compiled_kernel_sets() { return kSets; }

bool cpu_supports(const KernelSet& set) { return std::string_view(set.name) == "scalar"; }

bool scalar_forced() {
  const char* v = std::getenv("RGBDO_FORCE_SCALAR");
  return v != nullptr && *v != '\0' && std::string_view(v) != "0";
}

const KernelSet& active_kernels() {
  static const KernelSet& chosen = [&]() -> const KernelSet& {
    const auto sets = compiled_kernel_sets();
    if (!scalar_forced())
      for (const auto& s : sets)
        if (cpu_supports(s)) return s;
    return sets.back();
  }();
  return chosen;
}

const char* build_architecture() {
#if defined(__x86_64__)
  return "x86_64";
#elif defined(__aarch64__)
  return "aarch64";
#elif defined(__arm__) && defined(__ARM_NEON)
  return "armv7-a+neon";
#elif defined(__arm__)
  return "arm";
#else
  return "unknown";
#endif
}

}  // namespace rgbdo::simd
