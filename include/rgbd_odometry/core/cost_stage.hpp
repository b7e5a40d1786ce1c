#pragma once
// Stage markers for the ARM cost model (bench/arm_cost/): with RGBDO_COST_MARKERS=1 in the
// environment, mark_cost_stage() tells a qemu instruction-counting plugin which stage the
// calling thread is in, so that the instructions a frame costs on the target are counted per
// stage, OpenCV's included (a stage's library calls run on its thread). Without the variable
// it is one predictable branch.
//
// The marker is a getpid system call carrying two extra arguments, a magic word and the
// stage: getpid ignores them, the plugin's system-call callback reads them. No address of the
// program needs to be known to the plugin, and every thread is followed on its own.
#include <array>
#include <cstdint>

namespace rgbdo {

enum class CostStage : std::uint32_t {
  Other,       // everything outside the stages below: start-up, runtime, output
  Decode,      // reading a recorded frame (PNG decoding): not part of the target's work
  Mask,        // periphery and depth mask
  Detect,      // keypoints and descriptors (our extractor: orientation and descriptors only)
  Geometry,    // keypoints' undistortion, depth and depth gradient
  Match,       // symmetric ratio-test matching
  PointPairs,  // 3-D correspondences (both passes of the timing compensation)
  Ransac,      // hypotheses, refinement, final fit
  Covariance,  // the perturbations
  Pyramid,     // detection, our extractor: the image pyramid and its descriptor smoothing
  Corners,     // detection, our extractor: segment test, score, suppression, spread over cells
  Convert,     // colour to intensity, depth to metres: what a live frame needs too
  Refine,      // the depth maps' coarse clouds and their alignment (pipeline/depth_alignment.hpp)
  Track,       // the matched keypoints' sub-pixel tracking (pipeline/track.hpp)
  Keyframe,    // the current frame measured against its keyframe (pipeline/keyframes.hpp)
};
inline constexpr std::size_t kCostStageCount = 15;
inline constexpr std::array<const char*, kCostStageCount> kCostStageNames{
    "other", "decode", "mask", "detect", "geometry", "match", "point_pairs", "ransac", "covariance", "pyramid", "corners",
    "convert", "refine", "track", "keyframe"};
// The first extra argument of the marker call ("RGBD"): tells a marker from a real getpid.
inline constexpr std::uint32_t kCostMarkerMagic = 0x52474244u;

// From here on the calling thread works on `stage` (until its next mark).
void mark_cost_stage(CostStage stage) noexcept;

// Marks Other when it goes out of scope, so every return of a function that marks stages
// ends them.
struct CostStagesEnd {
  CostStagesEnd() = default;
  CostStagesEnd(const CostStagesEnd&) = delete;
  CostStagesEnd& operator=(const CostStagesEnd&) = delete;
  ~CostStagesEnd() { mark_cost_stage(CostStage::Other); }
};

}  // namespace rgbdo
