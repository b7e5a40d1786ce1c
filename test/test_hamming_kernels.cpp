// Every compiled kernel set this CPU supports against the scalar reference, bit for bit:
// sizes at lane boundaries, empty and single sets, unaligned rows, odd strides, heavy ties,
// and real ORB descriptors from the bundled frames.
#include <gtest/gtest.h>

#include <algorithm>

#include <cstdlib>
#include <opencv2/core.hpp>
#include <random>
#include <string>
#include <vector>

#include "rgbd_odometry/simd/kernels.hpp"
#include "runnable_kernel_sets.hpp"
#include "rgbd_odometry/app/config.hpp"
#include "rgbd_odometry/pipeline/match.hpp"
#include "rgbd_odometry/pipeline/odometry.hpp"
#include "rgbd_odometry/io/tum_sequence.hpp"
#include "rgbd_odometry/pipeline/frame_extractor.hpp"
#include "rgbd_odometry/app/config_file.hpp"

namespace rgbdo {
namespace {

bool operator==(const simd::NearestTwo& a, const simd::NearestTwo& b) {
  return a.best_index == b.best_index && a.best == b.best && a.second == b.second;
}

// Rows of `bytes` bytes, `stride` apart, starting `offset` bytes into the buffer. alphabet
// > 0 draws every byte from few values, so that equal distances (ties) are frequent.
std::vector<std::uint8_t> descriptors(int n, int bytes, std::size_t stride, int offset, unsigned seed, int alphabet) {
  std::vector<std::uint8_t> buf(static_cast<std::size_t>(offset) + stride * static_cast<std::size_t>(n) + 1);
  std::mt19937 rng(seed);
  for (int i = 0; i < n; ++i)
    for (int b = 0; b < bytes; ++b) {
      const unsigned v = alphabet > 0 ? (rng() % static_cast<unsigned>(alphabet)) * 0x11u : rng();
      buf[static_cast<std::size_t>(offset) + stride * static_cast<std::size_t>(i) + static_cast<std::size_t>(b)] =
          static_cast<std::uint8_t>(v);
    }
  return buf;
}

void expect_same_as_scalar(const simd::KernelSet& set, const std::uint8_t* q, int nq, std::size_t qs,
                           const std::uint8_t* t, int nt, std::size_t ts, int bytes, const std::string& what) {
  std::vector<simd::NearestTwo> qr(static_cast<std::size_t>(nq)), tr(static_cast<std::size_t>(nt));
  std::vector<simd::NearestTwo> qk(static_cast<std::size_t>(nq), {7, 7, 7}), tk(static_cast<std::size_t>(nt), {7, 7, 7});
  simd::nearest_two_hamming_scalar(q, nq, qs, t, nt, ts, bytes, qr.data(), tr.data());
  set.nearest_two_hamming(q, nq, qs, t, nt, ts, bytes, qk.data(), tk.data());
  for (int i = 0; i < nq; ++i)
    ASSERT_TRUE(qk[static_cast<size_t>(i)] == qr[static_cast<size_t>(i)]) << set.name << " " << what << " query " << i;
  for (int j = 0; j < nt; ++j)
    ASSERT_TRUE(tk[static_cast<size_t>(j)] == tr[static_cast<size_t>(j)]) << set.name << " " << what << " train " << j;
}

TEST(HammingKernels, ThisCpuRunsAtLeastOneSimdSet) {
  // On x86-64 with AVX2 or on ARM with NEON, the scalar set alone means dispatch is broken.
  const auto sets = runnable_sets();
  ASSERT_FALSE(sets.empty());
  EXPECT_STREQ(sets.back()->name, "scalar");
#if defined(__x86_64__) || defined(__arm__) || defined(__aarch64__)
  EXPECT_GE(sets.size(), 2u) << "no SIMD kernel set compiled in or supported";
#endif
}

TEST(HammingKernels, BitExactAtLaneBoundariesAndEdgeSizes) {
  const int sizes[] = {0, 1, 2, 3, 4, 5, 7, 8, 9, 15, 16, 17, 31, 32, 33, 63, 64, 65, 100};
  for (const auto* set : twins_of_reference(&simd::KernelSet::nearest_two_hamming))
    for (int bytes : {32, 64, 8, 24, 61}) {  // 61: AKAZE's size, handled by the reference path
      for (int nq : sizes)
        for (int nt : {0, 1, 3, 4, 5, 7, 8, 9, 17, 33}) {
          const auto q = descriptors(nq, bytes, static_cast<std::size_t>(bytes), 0, 1u + static_cast<unsigned>(nq), 0);
          const auto t = descriptors(nt, bytes, static_cast<std::size_t>(bytes), 0, 100u + static_cast<unsigned>(nt), 0);
          expect_same_as_scalar(*set, q.data(), nq, static_cast<std::size_t>(bytes), t.data(), nt,
                                static_cast<std::size_t>(bytes), bytes,
                                "bytes " + std::to_string(bytes) + " " + std::to_string(nq) + "x" + std::to_string(nt));
        }
    }
}

TEST(HammingKernels, BitExactOnUnalignedRowsOddStridesAndTies) {
  for (const auto* set : twins_of_reference(&simd::KernelSet::nearest_two_hamming))
    for (int offset : {1, 3, 7})
      for (int alphabet : {0, 2, 3}) {
        const std::size_t stride = 32 + static_cast<std::size_t>(offset);  // rows not multiples of 8 apart
        const auto q = descriptors(45, 32, stride, offset, 5, alphabet);
        const auto t = descriptors(123, 32, stride + 2, offset, 6, alphabet);
        expect_same_as_scalar(*set, q.data() + offset, 45, stride, t.data() + offset, 123, stride + 2, 32,
                              "offset " + std::to_string(offset) + " alphabet " + std::to_string(alphabet));
      }
}

TEST(HammingKernels, RowsKernelBitExactForAnyRowListSizeAndLayout) {
  // Row lists of every length around the kernel's pairs, in any order, with repeats; sizes
  // the NEON path takes (32 bytes) and the ones it hands to the reference.
  std::mt19937 rng(11);
  for (const auto* set : sets_with_own(&simd::KernelSet::hamming_rows))
    for (int bytes : {32, 64, 61})
      for (int offset : {0, 3}) {
        const std::size_t stride = static_cast<std::size_t>(bytes + offset);
        const auto t = descriptors(57, bytes, stride, offset, 21, offset == 0 ? 0 : 2);
        const auto q = descriptors(1, bytes, static_cast<std::size_t>(bytes), 1, 22, offset == 0 ? 0 : 2);
        for (int n : {0, 1, 2, 3, 4, 5, 8, 9, 31, 100}) {
          std::vector<int> rows(static_cast<std::size_t>(n));
          for (int& r : rows) r = static_cast<int>(rng() % 57);
          std::vector<std::uint32_t> want(rows.size() + 1, 7), got(rows.size() + 1, 7);
          simd::hamming_rows_scalar(q.data() + 1, t.data() + offset, stride, rows.data(), n, bytes, want.data());
          set->hamming_rows(q.data() + 1, t.data() + offset, stride, rows.data(), n, bytes, got.data());
          EXPECT_EQ(got, want) << set->name << " bytes " << bytes << " rows " << n;
          EXPECT_EQ(got.back(), 7u) << "wrote past the last row";
          for (int k = 0; k < n; ++k) {
            std::uint32_t d = 0;
            for (int b = 0; b < bytes; ++b)
              d += static_cast<std::uint32_t>(__builtin_popcount(
                  q[1 + static_cast<std::size_t>(b)] ^ t[static_cast<std::size_t>(offset) + stride * static_cast<std::size_t>(rows[static_cast<std::size_t>(k)]) + static_cast<std::size_t>(b)]));
            ASSERT_EQ(want[static_cast<std::size_t>(k)], d);
          }
        }
      }
}

TEST(HammingKernels, BitExactOnRealOrbDescriptors) {
  const Config config = load_config(RGBDO_CONFIG_DIR "/tum-fr1.yaml");
  const TumSequence seq = open_tum_sequence(RGBDO_TEST_DATA_DIR);
  FrameExtractor extractor(config);
  ProcessedFrame a, b;
  extractor.extract(load_tum_frame(seq.frames[0], 5000, 640, 480), a);
  extractor.extract(load_tum_frame(seq.frames[9], 5000, 640, 480), b);
  const cv::Mat& qa = a.features.descriptors;
  const cv::Mat& tb = b.features.descriptors;
  ASSERT_GT(qa.rows, 500);
  ASSERT_EQ(qa.cols, 32);
  for (const auto* set : twins_of_reference(&simd::KernelSet::nearest_two_hamming))
    expect_same_as_scalar(*set, qa.data, qa.rows, qa.step, tb.data, tb.rows, tb.step, 32, "ORB frames 0 and 9");
}

TEST(KernelChoice, ActiveSetIsTheBestSupportedOneOrTheRequestedOne) {
  // GIVEN what the environment asks for: RGBDO_KERNELS=SET, the older RGBDO_FORCE_SCALAR=1, or nothing
  const char* named = std::getenv("RGBDO_KERNELS");
  const char* scalar = std::getenv("RGBDO_FORCE_SCALAR");
  std::string wanted;
  if (named != nullptr && *named != '\0') wanted = named;
  else if (scalar != nullptr && *scalar != '\0' && std::string(scalar) != "0") wanted = "scalar";
  EXPECT_EQ(simd::requested_kernels(), wanted);
  if (!wanted.empty()) {
    const auto compiled = simd::compiled_kernel_sets();
    const auto it = std::find_if(compiled.begin(), compiled.end(), [&](const auto& s) { return wanted == s.name; });
    ASSERT_NE(it, compiled.end()) << "RGBDO_KERNELS names a set this build does not have: " << wanted;
    if (!simd::cpu_supports(*it)) {
      EXPECT_NE(simd::kernel_request_problem().find("this CPU cannot run that set"), std::string::npos);
      GTEST_SKIP() << "this CPU cannot run kernel set " << wanted;
    }
  }
  EXPECT_EQ(simd::kernel_request_problem(), "");
  const std::string expected = wanted.empty() ? runnable_sets().front()->name : wanted;
  EXPECT_EQ(simd::active_kernels().name, expected);
  // WHEN the matcher is built THEN it binds the active set and runs that kernel.
  SymmetricMatcher matcher(0.8);
  std::vector<Match> out;
  matcher.match(cv::Mat(10, 32, CV_8U, cv::Scalar(1)), cv::Mat(12, 32, CV_8U, cv::Scalar(2)), out);
  EXPECT_EQ(matcher.kernel_name(), expected);
}

}  // namespace
}  // namespace rgbdo
