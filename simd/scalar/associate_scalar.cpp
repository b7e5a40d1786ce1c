// Reference kernel of the depth alignment's association (rgbd_odometry/simd/associate.hpp).
// Every expression is written in the order its twins evaluate it.
#include "rgbd_odometry/simd/associate.hpp"

namespace rgbdo::simd {

int associate_scalar(const AssociateInput& in, Association* out) {
  const float* R = in.r;
  const auto cols = static_cast<float>(in.cols), rows = static_cast<float>(in.rows);
  int count = 0;
  for (int i = 0; i < in.n; ++i) {
    const float* p = in.curr + 3 * in.step * i;
    const float px = p[0], py = p[1], pz = p[2];
    if (pz == 0) continue;
    const float qx = ((R[0] * px + R[1] * py) + R[2] * pz) + in.t[0];
    const float qy = ((R[3] * px + R[4] * py) + R[5] * pz) + in.t[1];
    const float qz = ((R[6] * px + R[7] * py) + R[8] * pz) + in.t[2];
    if (!(qz > 0)) continue;
    const float iz = 1.0f / qz;
    const float gi = (qx * iz) * in.fx + in.cx, gj = (qy * iz) * in.fy + in.cy;
    if (!(gi >= 0 && gj >= 0 && gi < cols && gj < rows)) continue;
    const int k = static_cast<int>(gj) * in.cols + static_cast<int>(gi);
    const float* n = in.prev_normal + 3 * k;
    const float nx = n[0], ny = n[1], nz = n[2];
    if (nx == 0 && ny == 0 && nz == 0) continue;
    const float* target = in.prev_point + 3 * k;
    const float dx = qx - target[0], dy = qy - target[1], dz = qz - target[2];
    if ((dx * dx + dy * dy) + dz * dz > in.max_d2) continue;
    const float sz_c = (in.coeff * pz) * pz, sz_p = (in.coeff * target[2]) * target[2];
    const float mx = (R[0] * nx + R[3] * ny) + R[6] * nz;
    const float my = (R[1] * nx + R[4] * ny) + R[7] * nz;
    const float mz = (R[2] * nx + R[5] * ny) + R[8] * nz;
    // The lever arm: the midpoint of the point and its target, in the current frame.
    const float hx = ((R[0] * dx + R[3] * dy) + R[6] * dz) * 0.5f;
    const float hy = ((R[1] * dx + R[4] * dy) + R[7] * dz) * 0.5f;
    const float hz = ((R[2] * dx + R[5] * dy) + R[8] * dz) * 0.5f;
    const float ax = px - hx, ay = py - hy, az = pz - hz;
    Association& a = out[count++];
    a.r = (nx * dx + ny * dy) + nz * dz;
    a.w = 1.0f / ((sz_c * sz_c + sz_p * sz_p) + in.floor2);
    a.j[0] = mx;
    a.j[1] = my;
    a.j[2] = mz;
    a.j[3] = ay * mz - az * my;
    a.j[4] = az * mx - ax * mz;
    a.j[5] = ax * my - ay * mx;
    a.curr_index = in.first_index + in.step * i;
    a.prev_index = k;
  }
  return count;
}

}  // namespace rgbdo::simd
