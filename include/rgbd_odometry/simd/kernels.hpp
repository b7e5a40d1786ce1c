#pragma once
// The table of hot-path kernels, chosen once when the pipeline is built (never per call).
// Each instruction set this build was compiled with contributes one KernelSet; the best one
// the running CPU supports is active unless RGBDO_KERNELS names another (libjpeg-turbo's
// JSIMD_FORCE*, simdjson's SIMDJSON_FORCE_IMPLEMENTATION):
//   RGBDO_KERNELS=scalar|sse42|avx2|neon   that set, which must be compiled in and supported
//   RGBDO_FORCE_SCALAR=1                   the older spelling of RGBDO_KERNELS=scalar
#include <span>
#include <string>

#include "rgbd_odometry/simd/associate.hpp"
#include "rgbd_odometry/simd/fast.hpp"
#include "rgbd_odometry/simd/image.hpp"
#include "rgbd_odometry/simd/nearest_two.hpp"
#include "rgbd_odometry/simd/perturb.hpp"
#include "rgbd_odometry/simd/score.hpp"
#include "rgbd_odometry/simd/track.hpp"

namespace rgbdo::simd {

using NearestTwoHammingFn = void (*)(const std::uint8_t* query, int n_query, std::size_t query_stride,
                                     const std::uint8_t* train, int n_train, std::size_t train_stride, int bytes,
                                     NearestTwo* query_out, NearestTwo* train_out);

using HammingRowsFn = void (*)(const std::uint8_t* query, const std::uint8_t* train, std::size_t train_stride,
                               const int* rows, int n_rows, int bytes, std::uint32_t* distances);

using PerturbationSumsFn = void (*)(const PerturbationInput& in, const PerturbationSums& out);

using ScoreRigidFn = void (*)(const RigidScoreInput& in, int& count, float& cost);

using Fast9RowFn = void (*)(const std::uint8_t* row, std::ptrdiff_t stride, int n, int threshold, std::uint8_t* flags);
using Fast9ScoreFn = int (*)(const std::uint8_t* p, const std::ptrdiff_t* offsets, int threshold, int flags);

using BlendRowsFn = void (*)(const std::uint8_t* r0, const std::uint8_t* r1, int n, unsigned w, std::uint8_t* out);
using ResampleRowFn = void (*)(const std::uint8_t* src, const ResampleGroup* groups, int n, std::uint8_t* out);
using Box5RowFn = void (*)(const std::uint8_t* centre, std::ptrdiff_t stride, int n, std::uint16_t* out);
using DepthInRangeRowFn = void (*)(const float* depth, int n, float lo, float hi, std::uint8_t* out);
using ColourToGrayRowFn = void (*)(const std::uint8_t* pixels, int n, bool red_first, std::uint8_t* out);
using DepthToMetresRowFn = void (*)(const std::uint16_t* raw, int n, float metres_per_unit, float* out);
using TrackSample8Fn = void (*)(const std::uint8_t* top_left, std::ptrdiff_t stride, int rows, const std::int32_t* w,
                                std::int16_t* out);
using TrackSums8x8Fn = void (*)(const std::int16_t* sampled, const std::int16_t* templ, const std::int16_t* gx,
                               const std::int16_t* gy, std::int32_t* sums);
using AssociateFn = int (*)(const AssociateInput& in, Association* out);
using SurfaceMean5Fn = void (*)(const float* depth, std::ptrdiff_t stride, const std::int32_t* centre, int n, float spread,
                                float* mean);
using DiscMomentsFn = void (*)(const std::uint8_t* centre, std::ptrdiff_t stride, std::int32_t* m10, std::int32_t* m01);

struct KernelSet {
  const char* name;  // "scalar", "neon", "avx2", ...
  NearestTwoHammingFn nearest_two_hamming;
  HammingRowsFn hamming_rows;
  PerturbationSumsFn perturbation_sums;
  ScoreRigidFn score_rigid;
  Fast9RowFn fast9_row;
  Fast9ScoreFn fast9_score;
  BlendRowsFn blend_rows;
  ResampleRowFn resample_row;
  Box5RowFn box5_row;
  DepthInRangeRowFn depth_in_range_row;
  DiscMomentsFn disc_moments;
  ColourToGrayRowFn colour_to_gray_row;
  DepthToMetresRowFn depth_to_metres_row;
  TrackSample8Fn track_sample8;
  TrackSums8x8Fn track_sums8x8;
  AssociateFn associate;
  SurfaceMean5Fn surface_mean5;
};

// Every kernel set compiled into this build, the scalar reference last.
std::span<const KernelSet> compiled_kernel_sets();

// Whether the running CPU can execute a compiled set.
bool cpu_supports(const KernelSet& set);

// What the environment asks for: the set's name, or empty for "the best supported one".
// RGBDO_KERNELS wins over RGBDO_FORCE_SCALAR.
std::string requested_kernels();

// Empty when the request can be honoured; otherwise why not, naming the variable, the set
// and the sets that can run here. main() refuses to start on it; active_kernels() then
// falls back to the best supported set, so a library user is never left without kernels.
std::string kernel_request_problem();

// The set in use: decided at the first call and fixed for the life of the process.
const KernelSet& active_kernels();

// The architecture this binary was compiled for ("x86_64", "armv7-a+neon", ...).
const char* build_architecture();

}  // namespace rgbdo::simd
