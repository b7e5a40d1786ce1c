// Reference perturbation kernel (perturb.hpp): plain loops over the 8 lanes. The SIMD twins
// simd/x86/perturb_avx2.cpp and simd/arm/perturb_neon.cpp are tested against it.
#include "perturb_reference.hpp"

namespace rgbdo::simd {
namespace {

constexpr int L = kPerturbationLanes;

// Six normals per lane for one (block, point): (n0 n1 n2) for s, (n3 n4 n5) for d.
void draw_six(std::uint32_t state[L][4], float n[6][L]) {
  for (int pair = 0; pair < 3; ++pair) {
    std::uint32_t a[L], b[L];
    for (int l = 0; l < L; ++l) a[l] = reference::next(state[l]);
    for (int l = 0; l < L; ++l) b[l] = reference::next(state[l]);
    for (int l = 0; l < L; ++l) reference::box_muller(a[l], b[l], n[2 * pair][l], n[2 * pair + 1][l]);
  }
}

void seed_all(std::uint64_t seed, std::uint32_t state[L][4]) {
  for (int l = 0; l < L; ++l) reference::seed_lane(seed, l, state[l]);
}

}  // namespace

void perturbation_sums_scalar(const PerturbationInput& in, const PerturbationSums& out) {
  std::uint32_t state[L][4];
  seed_all(in.seed, state);
  for (int b = 0; b < in.perturbations / L; ++b) {
    float S[3][L] = {}, D[3][L] = {}, M[9][L] = {};
    for (int k = 0; k < in.points; ++k) {
      float n[6][L];
      draw_six(state, n);
      for (int l = 0; l < L; ++l) {
        const float s[3] = {(in.sx[k] + in.sigma_sx[k] * n[0][l]) + in.ray_sx[k] * n[2][l],
                            (in.sy[k] + in.sigma_sy[k] * n[1][l]) + in.ray_sy[k] * n[2][l],
                            in.sz[k] + in.ray_sz[k] * n[2][l]};
        const float d[3] = {(in.dx[k] + in.sigma_dx[k] * n[3][l]) + in.ray_dx[k] * n[5][l],
                            (in.dy[k] + in.sigma_dy[k] * n[4][l]) + in.ray_dy[k] * n[5][l],
                            in.dz[k] + in.ray_dz[k] * n[5][l]};
        const float w = in.w[k] * in.cell_weight[static_cast<long>(in.cell[k]) * in.perturbations + b * L + l];
        float ws[3];
        for (int j = 0; j < 3; ++j) {
          ws[j] = w * s[j];
          S[j][l] = S[j][l] + ws[j];
          D[j][l] = D[j][l] + w * d[j];
        }
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) M[3 * i + j][l] = M[3 * i + j][l] + d[i] * ws[j];
      }
    }
    for (int l = 0; l < L; ++l) {
      for (int j = 0; j < 3; ++j) {
        out.s[j][b * L + l] = S[j][l];
        out.d[j][b * L + l] = D[j][l];
      }
      for (int e = 0; e < 9; ++e) out.m[e][b * L + l] = M[e][l];
    }
  }
}

void perturbation_noise_scalar(std::uint64_t seed, int points, int perturbations, float* noise) {
  std::uint32_t state[L][4];
  seed_all(seed, state);
  for (int b = 0; b < perturbations / L; ++b)
    for (int k = 0; k < points; ++k) {
      float n[6][L];
      draw_six(state, n);
      for (int l = 0; l < L; ++l)
        for (int c = 0; c < 6; ++c)
          noise[((static_cast<long>(b * L + l) * points) + k) * 6 + c] = n[c][l];
    }
}

}  // namespace rgbdo::simd
