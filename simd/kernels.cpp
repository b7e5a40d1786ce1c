#include "rgbd_odometry/simd/kernels.hpp"

#include <cstdlib>
#include <string>
#include <string_view>

#if defined(__arm__) || defined(__aarch64__)
#include <sys/auxv.h>
#endif

namespace rgbdo::simd {
namespace {

// Best first; the scalar reference always last.
constexpr KernelSet kSets[] = {
#if defined(RGBDO_X86_KERNELS)
    {"avx2", nearest_two_hamming_avx2, hamming_rows_popcnt, perturbation_sums_avx2, score_rigid_avx2, fast9_row_avx2,
     fast9_score_scalar, blend_rows_sse41, resample_row_sse41, box5_row_sse41, depth_in_range_row_sse41, disc_moments_sse41,
     colour_to_gray_row_scalar, depth_to_metres_row_scalar, track_sample8_scalar, track_sums8x8_scalar, associate_avx2, surface_mean5_scalar},
    {"sse42", nearest_two_hamming_popcnt, hamming_rows_popcnt, perturbation_sums_scalar, score_rigid_scalar, fast9_row_scalar,
     fast9_score_scalar, blend_rows_sse41, resample_row_sse41, box5_row_sse41, depth_in_range_row_sse41, disc_moments_sse41,
     colour_to_gray_row_scalar, depth_to_metres_row_scalar, track_sample8_scalar, track_sums8x8_scalar, associate_scalar, surface_mean5_scalar},
#endif
#if defined(RGBDO_NEON_KERNELS)
    {"neon", nearest_two_hamming_neon, hamming_rows_neon, perturbation_sums_neon, score_rigid_neon, fast9_row_neon,
     fast9_score_neon, blend_rows_neon, resample_row_neon, box5_row_neon, depth_in_range_row_neon, disc_moments_neon,
     colour_to_gray_row_neon, depth_to_metres_row_neon, track_sample8_neon, track_sums8x8_neon, associate_neon, surface_mean5_neon},
#endif
    {"scalar", nearest_two_hamming_scalar, hamming_rows_scalar, perturbation_sums_scalar, score_rigid_scalar, fast9_row_scalar,
     fast9_score_scalar, blend_rows_scalar, resample_row_scalar, box5_row_scalar, depth_in_range_row_scalar, disc_moments_scalar,
     colour_to_gray_row_scalar, depth_to_metres_row_scalar, track_sample8_scalar, track_sums8x8_scalar, associate_scalar, surface_mean5_scalar},
};

}  // namespace

std::span<const KernelSet> compiled_kernel_sets() { return kSets; }

bool cpu_supports(const KernelSet& set) {
  const std::string_view name = set.name;
  if (name == "scalar") return true;
#if defined(RGBDO_X86_KERNELS)
  if (name == "avx2") return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("popcnt");
  if (name == "sse42") return __builtin_cpu_supports("sse4.2") && __builtin_cpu_supports("popcnt");
#endif
#if defined(RGBDO_NEON_KERNELS)
#if defined(__aarch64__)
  if (name == "neon") return true;  // Advanced SIMD is mandatory on AArch64
#else
  if (name == "neon") return (getauxval(AT_HWCAP) & (1UL << 12)) != 0;  // HWCAP_NEON
#endif
#endif
  return false;
}

std::string requested_kernels() {
  if (const char* named = std::getenv("RGBDO_KERNELS"); named != nullptr && *named != '\0') return named;
  const char* v = std::getenv("RGBDO_FORCE_SCALAR");
  if (v != nullptr && *v != '\0' && std::string_view(v) != "0") return "scalar";
  return {};
}

namespace {

const KernelSet* find_compiled(std::string_view name) {
  for (const auto& s : compiled_kernel_sets())
    if (name == s.name) return &s;
  return nullptr;
}

std::string runnable_names() {
  std::string names;
  for (const auto& s : compiled_kernel_sets())
    if (cpu_supports(s)) names += (names.empty() ? "" : ", ") + std::string(s.name);
  return names;
}

}  // namespace

std::string kernel_request_problem() {
  const std::string wanted = requested_kernels();
  if (wanted.empty()) return {};
  const KernelSet* set = find_compiled(wanted);
  if (set == nullptr)
    return "RGBDO_KERNELS=" + wanted + ": no such kernel set in this " + build_architecture() +
           " build (it has: " + runnable_names() + ")";
  if (!cpu_supports(*set))
    return "RGBDO_KERNELS=" + wanted + ": this CPU cannot run that set (it can run: " + runnable_names() + ")";
  return {};
}

const KernelSet& active_kernels() {
  static const KernelSet& chosen = []() -> const KernelSet& {
    if (kernel_request_problem().empty())
      if (const KernelSet* named = find_compiled(requested_kernels())) return *named;
    for (const auto& s : compiled_kernel_sets())
      if (cpu_supports(s)) return s;
    return compiled_kernel_sets().back();
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
