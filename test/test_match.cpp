#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <opencv2/core.hpp>
#include <random>

#include "rgbd_odometry/pipeline/match.hpp"

namespace rgbdo {
namespace {

cv::Mat random_descriptors(int n, int bytes, unsigned seed) {
  cv::Mat d(n, bytes, CV_8U);
  cv::RNG rng(seed);
  rng.fill(d, cv::RNG::UNIFORM, 0, 256);
  return d;
}

// Flips `bits` distinct bits of a descriptor row.
cv::Mat flipped(const cv::Mat& row, int bits, unsigned seed) {
  cv::Mat out = row.clone();
  std::vector<int> idx(static_cast<size_t>(row.cols * 8));
  std::iota(idx.begin(), idx.end(), 0);
  std::shuffle(idx.begin(), idx.end(), std::mt19937(seed));
  for (int k = 0; k < bits; ++k) out.at<uint8_t>(0, idx[static_cast<size_t>(k)] / 8) ^= static_cast<uint8_t>(1u << (idx[static_cast<size_t>(k)] % 8));
  return out;
}

TEST(HammingKernel, MatchesBruteForceDefinition) {
  for (int bytes : {1, 7, 8, 32, 61}) {
    const cv::Mat q = random_descriptors(37, bytes, 1), t = random_descriptors(23, bytes, 2);
    std::vector<simd::NearestTwo> qn(37), tn(23);
    simd::nearest_two_hamming_scalar(q.data, q.rows, q.step, t.data, t.rows, t.step, bytes, qn.data(), tn.data());
    for (int i = 0; i < q.rows; ++i) {
      std::vector<std::uint32_t> d;
      for (int j = 0; j < t.rows; ++j) d.push_back(static_cast<std::uint32_t>(cv::norm(q.row(i), t.row(j), cv::NORM_HAMMING)));
      const auto best = std::min_element(d.begin(), d.end());
      EXPECT_EQ(qn[static_cast<size_t>(i)].best_index, best - d.begin());
      EXPECT_EQ(qn[static_cast<size_t>(i)].best, *best);
      std::sort(d.begin(), d.end());
      EXPECT_EQ(qn[static_cast<size_t>(i)].second, d[1]);
    }
  }
}

TEST(HammingKernel, EmptySetsGiveNoNeighbours) {
  const cv::Mat q = random_descriptors(3, 32, 1);
  std::vector<simd::NearestTwo> qn(3);
  simd::nearest_two_hamming_scalar(q.data, 3, q.step, nullptr, 0, 32, 32, qn.data(), nullptr);
  for (const auto& n : qn) EXPECT_EQ(n.best_index, -1);
}

TEST(RatioTest, RejectsAmbiguousAndAcceptsDistinct) {
  EXPECT_TRUE(passes_ratio_test({0, 10, 20}, 0.8));
  EXPECT_FALSE(passes_ratio_test({0, 17, 20}, 0.8));   // 0.85 > 0.8
  EXPECT_FALSE(passes_ratio_test({0, 16, 20}, 0.8));   // exactly 0.8: not strictly distinct
  EXPECT_FALSE(passes_ratio_test({0, 5, 5}, 0.8));     // a tie is ambiguous
  EXPECT_FALSE(passes_ratio_test({0, 0, 0}, 0.8));     // two identical candidates
  EXPECT_TRUE(passes_ratio_test({0, 3, UINT32_MAX}, 0.8));  // a lone candidate
  EXPECT_FALSE(passes_ratio_test({-1, UINT32_MAX, UINT32_MAX}, 0.8));
}

TEST(SymmetricMatcher, FindsPlantedCorrespondences) {
  // GIVEN 50 random descriptors and, shuffled, the same ones with 5 bits flipped
  const cv::Mat prev = random_descriptors(50, 32, 5);
  std::vector<int> perm(50);
  std::iota(perm.begin(), perm.end(), 0);
  std::shuffle(perm.begin(), perm.end(), std::mt19937(3));
  cv::Mat curr(50, 32, CV_8U);
  for (int i = 0; i < 50; ++i) flipped(prev.row(i), 5, static_cast<unsigned>(i)).copyTo(curr.row(perm[static_cast<size_t>(i)]));
  SymmetricMatcher matcher(0.8);
  std::vector<Match> matches;
  matcher.match(prev, curr, matches);
  // THEN every planted pair is found, and nothing else
  ASSERT_EQ(matches.size(), 50u);
  for (const auto& m : matches) {
    EXPECT_EQ(m.curr, perm[static_cast<size_t>(m.prev)]);
    EXPECT_EQ(m.distance, 5.0f);
  }
}

TEST(SymmetricMatcher, RejectsMatchAmbiguousOnlyInTheBackwardDirection) {
  // GIVEN prev = {a, a2} and curr = {b}, with b 10 bits from a and 11 bits from a2.
  // Forward, a -> b passes (a lone candidate); backward, b -> {a: 10, a2: 11} is ambiguous
  // (10/11 > 0.8). A one-sided ratio test would keep (a, b); the symmetric one must not.
  const cv::Mat a = random_descriptors(1, 32, 1);
  const cv::Mat b = flipped(a, 10, 2);
  const cv::Mat a2 = flipped(b, 11, 3);
  cv::Mat prev;
  cv::vconcat(a, a2, prev);
  SymmetricMatcher matcher(0.8);
  std::vector<Match> matches;
  matcher.match(prev, b, matches);
  EXPECT_TRUE(matches.empty());
  // With a ratio that tolerates 10/11, the backward test passes and (a, b) is kept.
  SymmetricMatcher lenient(0.95);
  lenient.match(prev, b, matches);
  ASSERT_EQ(matches.size(), 1u);
  EXPECT_EQ(matches[0].prev, 0);
}

TEST(SymmetricMatcher, RequiresMutualNearestNeighbours) {
  // curr[0] is nearest to prev[0] but prev[0]'s nearest is curr[1].
  const cv::Mat p0 = random_descriptors(1, 32, 9);
  const cv::Mat c1 = flipped(p0, 2, 1), c0 = flipped(p0, 40, 2);
  cv::Mat curr;
  cv::vconcat(c0, c1, curr);
  SymmetricMatcher matcher(0.8);
  std::vector<Match> matches;
  matcher.match(p0, curr, matches);
  ASSERT_EQ(matches.size(), 1u);
  EXPECT_EQ(matches[0].curr, 1);
}

TEST(SymmetricMatcher, FloatDescriptorsUseL2) {
  cv::Mat prev = (cv::Mat_<float>(2, 2) << 0, 0, 10, 10);
  cv::Mat curr = (cv::Mat_<float>(2, 2) << 10, 9, 0, 1);
  SymmetricMatcher matcher(0.8);
  std::vector<Match> matches;
  matcher.match(prev, curr, matches);
  ASSERT_EQ(matches.size(), 2u);
  EXPECT_EQ(matches[0].curr, 1);
  EXPECT_EQ(matches[1].curr, 0);
  EXPECT_FLOAT_EQ(matches[0].distance, 1.0f);
}

TEST(SymmetricMatcher, EmptyInputGivesNoMatches) {
  SymmetricMatcher matcher(0.8);
  std::vector<Match> matches{{1, 2, 3}};
  matcher.match(cv::Mat(), random_descriptors(4, 32, 1), matches);
  EXPECT_TRUE(matches.empty());
}

}  // namespace
}  // namespace rgbdo
