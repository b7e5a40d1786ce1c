// Reference RANSAC scoring kernel (score.hpp). Lanes of 8 partial sums, combined at the
// end in a fixed tree, so that the AVX2 (8 lanes) and NEON (2 x 4 lanes) twins add in the
// same order and produce the same bits.
#include "rgbd_odometry/simd/score.hpp"

namespace rgbdo::simd {

void score_rigid_scalar(const RigidScoreInput& in, int& count, float& cost) {
  constexpr int L = 8;
  float lane_cost[L] = {};
  int lane_count[L] = {};
  const float* r = in.r;
  for (int k = 0; k < in.n; ++k) {
    const int l = k % L;
    const float ex = in.px[k] - (((r[0] * in.cx[k] + r[1] * in.cy[k]) + r[2] * in.cz[k]) + in.t[0]);
    const float ey = in.py[k] - (((r[3] * in.cx[k] + r[4] * in.cy[k]) + r[5] * in.cz[k]) + in.t[1]);
    const float ez = in.pz[k] - (((r[6] * in.cx[k] + r[7] * in.cy[k]) + r[8] * in.cz[k]) + in.t[2]);
    const float e = (ex * ex + ey * ey) + ez * ez;
    const bool inside = e < in.threshold_sq;
    lane_count[l] += inside;
    lane_cost[l] = lane_cost[l] + (inside ? e : in.threshold_sq);
  }
  // Fixed reduction tree: (0+4, 1+5, 2+6, 3+7), then (0+2, 1+3), then (0+1).
  for (int l = 0; l < 4; ++l) lane_cost[l] = lane_cost[l] + lane_cost[l + 4];
  for (int l = 0; l < 2; ++l) lane_cost[l] = lane_cost[l] + lane_cost[l + 2];
  cost = lane_cost[0] + lane_cost[1];
  count = 0;
  for (int c : lane_count) count += c;
}

}  // namespace rgbdo::simd
