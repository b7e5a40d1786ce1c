#pragma once
// The table of hot-path kernels, chosen once when the pipeline is built (never per call).
// Each instruction set this build was compiled with contributes one KernelSet; the best one
// the running CPU supports is active unless RGBDO_FORCE_SCALAR=1 forces the scalar
// references (libjpeg-turbo's JSIMD_FORCENONE, simdjson's SIMDJSON_FORCE_IMPLEMENTATION).
#include <span>

#include "nearest_two.hpp"
#include "perturb.hpp"
#include "score.hpp"

namespace rgbdo::simd {

using NearestTwoHammingFn = void (*)(const std::uint8_t* query, int n_query, std::size_t query_stride,
                                     const std::uint8_t* train, int n_train, std::size_t train_stride, int bytes,
                                     NearestTwo* query_out, NearestTwo* train_out);

using PerturbationSumsFn = void (*)(const PerturbationInput& in, const PerturbationSums& out);

using ScoreRigidFn = void (*)(const RigidScoreInput& in, int& count, float& cost);

struct KernelSet {
  const char* name;  // "scalar", "neon", "avx2", ...
  NearestTwoHammingFn nearest_two_hamming;
  PerturbationSumsFn perturbation_sums;
  ScoreRigidFn score_rigid;
};

// Every kernel set compiled into this build, the scalar reference last.
std::span<const KernelSet> compiled_kernel_sets();

// Whether the running CPU can execute a compiled set.
bool cpu_supports(const KernelSet& set);

// The set in use: decided at the first call and fixed for the life of the process.
const KernelSet& active_kernels();

// True when RGBDO_FORCE_SCALAR is set to a non-empty value other than "0".
bool scalar_forced();

// The architecture this binary was compiled for ("x86_64", "armv7-a+neon", ...).
const char* build_architecture();

}  // namespace rgbdo::simd
