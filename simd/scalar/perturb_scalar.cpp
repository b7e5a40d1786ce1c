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
    float S[L][3] = {}, D[L][3] = {}, M[L][9] = {};
    for (int k = 0; k < in.points; ++k)
      for (int l = 0; l < L; ++l) {
        const float w = in.w[k] * in.cell_weight[static_cast<long>(in.cell[k]) * in.perturbations + b * L + l];
        reference::accumulate_point_of<reference::ScalarOps>(in, k, w, state[l], S[l], D[l], M[l]);
      }
    for (int l = 0; l < L; ++l) {
      for (int j = 0; j < 3; ++j) {
        out.s[j][b * L + l] = S[l][j];
        out.d[j][b * L + l] = D[l][j];
      }
      for (int e = 0; e < 9; ++e) out.m[e][b * L + l] = M[l][e];
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
