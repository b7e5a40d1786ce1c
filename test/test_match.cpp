#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <opencv2/core.hpp>
#include <random>
#include <string>

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

// The windowed test by its definition: nearest and second-nearest over the allowed pairs
// only, the plain way (index order, strict '<').
std::vector<Match> windowed_by_definition(const cv::Mat& prev, const cv::Mat& curr, const std::vector<Eigen::Vector2d>& pred,
                                          const std::vector<Eigen::Vector2d>& pos, double r, double ratio) {
  const auto allowed = [&](int i, int j) {
    const auto& p = pred[static_cast<size_t>(i)];
    const auto& q = pos[static_cast<size_t>(j)];
    return std::abs(q.x() - p.x()) <= r && std::abs(q.y() - p.y()) <= r;  // false for NaN
  };
  const auto dist = [&](int i, int j) { return static_cast<std::uint32_t>(cv::norm(prev.row(i), curr.row(j), cv::NORM_HAMMING)); };
  std::vector<simd::NearestTwo> fwd(static_cast<size_t>(prev.rows)), bwd(static_cast<size_t>(curr.rows));
  for (int i = 0; i < prev.rows; ++i)
    for (int j = 0; j < curr.rows; ++j)
      if (allowed(i, j)) {
        simd::keep_nearest_two(fwd[static_cast<size_t>(i)], dist(i, j), j);
        simd::keep_nearest_two(bwd[static_cast<size_t>(j)], dist(i, j), i);
      }
  std::vector<Match> out;
  for (int i = 0; i < prev.rows; ++i) {
    const auto& f = fwd[static_cast<size_t>(i)];
    if (!passes_ratio_test(f, ratio)) continue;
    const auto& b = bwd[static_cast<size_t>(f.best_index)];
    if (b.best_index == i && passes_ratio_test(b, ratio)) out.push_back({i, f.best_index, static_cast<float>(f.best)});
  }
  return out;
}

void expect_same_matches(const std::vector<Match>& a, const std::vector<Match>& b, const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].prev, b[k].prev) << what << " match " << k;
    EXPECT_EQ(a[k].curr, b[k].curr) << what << " match " << k;
    EXPECT_EQ(a[k].distance, b[k].distance) << what << " match " << k;
  }
}

TEST(SymmetricMatcher, WindowedMatchingIsTheRatioTestOverTheAllowedPairs) {
  // Random positions and descriptors from a small alphabet (many equal distances: the tie
  // rule matters), every fifth prediction missing, windows of several sizes; the grid's
  // order of visiting must not show in the result.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.6, 0.6);
  for (int trial = 0; trial < 6; ++trial) {
    const int n_prev = 150 + 10 * trial, n_curr = 170 - 7 * trial;
    cv::Mat prev(n_prev, 32, CV_8U), curr(n_curr, 32, CV_8U);
    for (cv::Mat* m : {&prev, &curr})
      for (int i = 0; i < m->rows; ++i)
        for (int b = 0; b < 32; ++b) m->at<std::uint8_t>(i, b) = static_cast<std::uint8_t>((rng() % 3) * 0x55u);
    std::vector<Eigen::Vector2d> pred(static_cast<size_t>(n_prev)), pos(static_cast<size_t>(n_curr));
    for (auto& p : pos) p = {u(rng), 0.75 * u(rng)};
    for (size_t i = 0; i < pred.size(); ++i)
      pred[i] = i % 5 == 4 ? Eigen::Vector2d(NAN, NAN) : Eigen::Vector2d(u(rng), 0.75 * u(rng));
    for (double r : {0.01, 0.09, 0.3, 5.0}) {
      SymmetricMatcher matcher(0.8);
      std::vector<Match> got;
      matcher.match_within(prev, curr, pred, pos, r, got);
      expect_same_matches(got, windowed_by_definition(prev, curr, pred, pos, r, 0.8),
                          "trial " + std::to_string(trial) + " radius " + std::to_string(r));
    }
  }
}

TEST(SymmetricMatcher, AWindowOverTheWholeImageIsTheFullSearch) {
  cv::Mat curr = random_descriptors(300, 32, 8), prev = curr.clone();
  for (int i = 0; i < prev.rows; i += 2) flipped(curr.row(i), 20, static_cast<unsigned>(i)).copyTo(prev.row(i));
  std::vector<Eigen::Vector2d> pred(300), pos(300);
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-0.6, 0.6);
  for (auto* v : {&pred, &pos})
    for (auto& p : *v) p = {u(rng), u(rng)};
  SymmetricMatcher matcher(0.8);
  std::vector<Match> full, windowed;
  matcher.match(prev, curr, full);
  matcher.match_within(prev, curr, pred, pos, 2.0, windowed);
  ASSERT_GT(full.size(), 250u);
  expect_same_matches(windowed, full, "window 2.0 over positions within 0.6");
  // A keypoint whose true partner lies outside its window cannot match it.
  pred[0] = pos[0] + Eigen::Vector2d(0.05, 0);
  matcher.match_within(prev, curr, pred, pos, 0.049, windowed);
  EXPECT_TRUE(std::none_of(windowed.begin(), windowed.end(), [](const Match& m) { return m.prev == 0 && m.curr == 0; }));
  matcher.match_within(prev, curr, pred, pos, 0.051, windowed);
  EXPECT_TRUE(std::any_of(windowed.begin(), windowed.end(), [](const Match& m) { return m.prev == 0 && m.curr == 0; }));
}

TEST(SymmetricMatcher, EmptyInputGivesNoMatches) {
  SymmetricMatcher matcher(0.8);
  std::vector<Match> matches{{1, 2, 3}};
  matcher.match(cv::Mat(), random_descriptors(4, 32, 1), matches);
  EXPECT_TRUE(matches.empty());
}

}  // namespace
}  // namespace rgbdo
