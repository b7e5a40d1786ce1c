#include <gtest/gtest.h>

#include <random>

#include "rgbd_odometry/core/geometry.hpp"
#include "rgbd_odometry/simd/kernels.hpp"
#include "rgbd_odometry/pipeline/ransac.hpp"
#include "rgbd_odometry/core/umeyama.hpp"

#include <Eigen/Cholesky>

namespace rgbdo {
namespace {

struct Scene {
  std::vector<Eigen::Vector3d> prev, curr;
  std::vector<bool> is_outlier;
};

// Points 1-3 m in front of the camera; prev = T * curr plus sensor-like noise; a fraction
// of the pairs replaced by wrong matches (random points of the same scene).
Scene make_scene(const Eigen::Isometry3d& T, int n, double outlier_fraction, double noise_m, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1), z(1, 3), unit(0, 1);
  std::normal_distribution<double> g(0, noise_m);
  Scene s;
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d c(u(rng), 0.75 * u(rng), z(rng));
    s.curr.push_back(c);
    const bool outlier = unit(rng) < outlier_fraction;
    s.is_outlier.push_back(outlier);
    s.prev.push_back(outlier ? Eigen::Vector3d(u(rng), 0.75 * u(rng), z(rng))
                             : Eigen::Vector3d(T * c + Eigen::Vector3d(g(rng), g(rng), g(rng))));
  }
  return s;
}

RansacConfig paper_config() { return RansacConfig{}; }

RansacResult run(RigidRansac& ransac, const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr,
                 Rng& rng) {
  RansacResult r;
  ransac.estimate(prev, curr, rng, r);
  return r;
}

TEST(Ransac, RecoversKnownMotionWithHalfTheMatchesWrong) {
  Vector6d xi;
  xi << 0.02, -0.01, 0.03, 0.01, -0.02, 0.015;
  const Eigen::Isometry3d truth = transform_from_xi(xi);
  const Scene s = make_scene(truth, 400, 0.5, 0.002, 7);
  RigidRansac ransac(paper_config(), SensorNoise{}, 1000);
  Rng rng(1);
  const RansacResult r = run(ransac, s.prev, s.curr, rng);
  ASSERT_EQ(r.status, Status::Ok);
  const Eigen::Isometry3d err = truth.inverse() * r.T_prev_curr;
  EXPECT_LT(err.translation().norm(), 0.002);
  EXPECT_LT(rotation_angle(err.linear()), 0.002);
  // Inliers are the true ones: no planted outlier survives the refined threshold.
  int wrong = 0;
  for (int k : r.inliers) wrong += s.is_outlier[static_cast<size_t>(k)];
  EXPECT_LE(wrong, 2);  // a random point may land within the threshold by chance
  int true_inliers = 0;
  for (bool o : s.is_outlier) true_inliers += !o;
  EXPECT_GT(static_cast<int>(r.inliers.size()), 0.9 * true_inliers);
  EXPECT_LT(r.threshold_m, paper_config().inlier_threshold_m);  // refinement tightened it
}

TEST(Ransac, RayAlignedNoiseIsBetterFitAnisotropically) {
  // GIVEN correspondences whose noise is the sensor's: large along each viewing ray (depth),
  // small across it (pixels), and no outliers
  Vector6d xi;
  xi << 0.01, 0.005, -0.02, 0.004, -0.006, 0.003;
  const Eigen::Isometry3d truth = transform_from_xi(xi);
  const SensorNoise noise{1.425e-3, 0.25, 1.2, 0.8, 525, 525};
  double err_plain = 0, err_aniso = 0;
  for (unsigned seed = 0; seed < 20; ++seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> g(0, 1);
    std::uniform_real_distribution<double> u(-1, 1), z(1, 4);
    std::vector<Eigen::Vector3d> prev, curr;
    const auto observe = [&](const Eigen::Vector3d& p) {
      const Eigen::Matrix3d L = point_covariance(p, noise).llt().matrixL();
      return Eigen::Vector3d(p + L * Eigen::Vector3d(g(rng), g(rng), g(rng)));
    };
    for (int i = 0; i < 150; ++i) {
      const Eigen::Vector3d c(u(rng) * 1.5, u(rng), z(rng));
      curr.push_back(observe(c));
      prev.push_back(observe(truth * c));
    }
    // WHEN fitted by RANSAC + refinement, and by one plain least-squares fit
    RigidRansac ransac(paper_config(), noise, 1000);
    Rng r(seed);
    const RansacResult fit = run(ransac, prev, curr, r);
    ASSERT_EQ(fit.status, Status::Ok);
    Eigen::Isometry3d plain;
    ASSERT_TRUE(fit_rigid(curr, prev, {}, plain));
    err_aniso += (xi_from_transform(truth.inverse() * fit.T_prev_curr)).squaredNorm();
    err_plain += (xi_from_transform(truth.inverse() * plain)).squaredNorm();
  }
  // THEN the noise-aware fit is clearly closer to the truth
  EXPECT_LT(err_aniso, 0.5 * err_plain);
}

// A few cm and degrees: one frame's motion.
Eigen::Isometry3d exact_depth_test_motion() {
  Vector6d xi;
  xi << 0.01, 0.005, -0.02, 0.004, -0.006, 0.003;
  return transform_from_xi(xi);
}

// A sensor whose depth is exact up to c Z^2 (ICL-NUIM's rendering), no depth-map lateral noise.
SensorNoise exact_depth_noise(double c) {
  SensorNoise n;
  n.depth_noise_coeff = c;
  n.depth_lateral_sigma_px = 0;
  return n;
}

TEST(Ransac, WithExactDepthEachPointsOwnCovarianceKeepsTheFitRight) {
  // GIVEN a sensor whose depth is exact (c at the configuration's floor, ICL-NUIM's rendering),
  // keypoints off by 0.3 px,
  // and half the points on surfaces steep in the image (1-2 cm of depth per pixel), where
  // the keypoint's error moves its depth along the ray too
  const Eigen::Isometry3d truth = exact_depth_test_motion();
  const SensorNoise exact = exact_depth_noise(1e-9);
  const double sigma_px = 0.3;
  double err_point_only = 0, err_own = 0;
  for (unsigned seed = 0; seed < 20; ++seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> g(0, 1);
    std::uniform_real_distribution<double> u(-1, 1), z(1, 4), slope(0.01, 0.02);
    std::vector<Eigen::Vector3d> prev, curr;
    PointPairCovariances own;
    const auto observe = [&](const Eigen::Vector3d& p, const Eigen::Vector2d& gradient,
                             std::vector<Eigen::Vector3d>& points, std::vector<Eigen::Matrix3d>& covariances) {
      const Eigen::Matrix3d C = physical_point_noise_px(p, sigma_px, gradient, exact).covariance();
      points.push_back(p + Eigen::Matrix3d(C.llt().matrixL()) * Eigen::Vector3d(g(rng), g(rng), g(rng)));
      covariances.push_back(C);
    };
    for (int i = 0; i < 150; ++i) {
      const Eigen::Vector3d c(u(rng) * 1.5, u(rng), z(rng));
      const Eigen::Vector2d gradient = i % 2 ? Eigen::Vector2d(slope(rng), 0) : Eigen::Vector2d::Zero();
      observe(c, gradient, curr, own.curr);
      observe(truth * c, gradient, prev, own.prev);
    }
    // WHEN fitted with each point's own covariance, and with the point-only model
    RigidRansac ransac(paper_config(), exact, 1000);
    RansacResult with_own, point_only;
    Rng r1(seed), r2(seed);
    ransac.estimate(prev, curr, r1, with_own, &own);
    ransac.estimate(prev, curr, r2, point_only);
    ASSERT_EQ(with_own.status, Status::Ok);
    ASSERT_EQ(point_only.status, Status::Ok);
    ASSERT_TRUE(with_own.T_prev_curr.matrix().allFinite());
    err_own += (xi_from_transform(truth.inverse() * with_own.T_prev_curr)).squaredNorm();
    err_point_only += (xi_from_transform(truth.inverse() * point_only.T_prev_curr)).squaredNorm();
  }
  // THEN the fit that knows which depths the slope makes uncertain is far closer to the truth
  // (measured: the point-only model, which takes every depth as exact, has 89x the summed
  // squared error, 9.4x the RMS)
  EXPECT_LT(60 * err_own, err_point_only);
}

TEST(Ransac, AFewDepthsFarOffWhatTheModelSaysDoNotSteerTheFinalFit) {
  // GIVEN a model that calls the depth exact (ICL-NUIM's rendering, told its true constants)
  // and one keypoint in eight whose depth is 3 mm off along its ray in one frame (a corner:
  // the depth under the keypoint is the corner's relief, not the surface's), within the
  // inlier threshold
  const Eigen::Isometry3d truth = exact_depth_test_motion();
  const SensorNoise exact = exact_depth_noise(1e-5);
  const double sigma_px = 0.3;
  double err_all = 0, err_clean = 0;
  for (unsigned seed = 0; seed < 20; ++seed) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> g(0, 1);
    std::uniform_real_distribution<double> u(-1, 1), z(1, 4);
    std::vector<Eigen::Vector3d> prev, curr, clean_prev, clean_curr;
    PointPairCovariances own, clean;
    for (int i = 0; i < 160; ++i) {
      const Eigen::Vector3d c(u(rng) * 1.5, u(rng), z(rng)), p = truth * c;
      const Eigen::Matrix3d Cc = physical_point_noise_px(c, sigma_px, Eigen::Vector2d::Zero(), exact).covariance();
      const Eigen::Matrix3d Cp = physical_point_noise_px(p, sigma_px, Eigen::Vector2d::Zero(), exact).covariance();
      const Eigen::Vector3d seen_c = c + Eigen::Matrix3d(Cc.llt().matrixL()) * Eigen::Vector3d(g(rng), g(rng), g(rng));
      Eigen::Vector3d seen_p = p + Eigen::Matrix3d(Cp.llt().matrixL()) * Eigen::Vector3d(g(rng), g(rng), g(rng));
      const bool corner = i % 8 == 0;
      if (corner) seen_p += 0.003 * (u(rng) > 0 ? 1 : -1) * p.normalized();
      prev.push_back(seen_p);
      curr.push_back(seen_c);
      own.prev.push_back(Cp);
      own.curr.push_back(Cc);
      if (corner) continue;
      clean_prev.push_back(seen_p);
      clean_curr.push_back(seen_c);
      clean.prev.push_back(Cp);
      clean.curr.push_back(Cc);
    }
    // WHEN fitted with them, and without them
    RigidRansac ransac(paper_config(), exact, 1000);
    RansacResult with_corners, without;
    Rng r1(seed), r2(seed);
    ransac.estimate(prev, curr, r1, with_corners, &own);
    ransac.estimate(clean_prev, clean_curr, r2, without, &clean);
    ASSERT_EQ(with_corners.status, Status::Ok);
    ASSERT_EQ(without.status, Status::Ok);
    err_all += (xi_from_transform(truth.inverse() * with_corners.T_prev_curr)).squaredNorm();
    err_clean += (xi_from_transform(truth.inverse() * without.T_prev_curr)).squaredNorm();
  }
  // THEN the corners cost nothing: measured 0.93x the summed squared error of the fit without
  // them (their bearings still count); weighed by the Gaussian loss alone, 2.5x
  EXPECT_LT(err_all, 1.2 * err_clean);
}

TEST(Ransac, SameSeedSameAnswer) {
  const Scene s = make_scene(Eigen::Isometry3d::Identity(), 200, 0.4, 0.003, 9);
  RigidRansac a(paper_config(), SensorNoise{}, 1000), b(paper_config(), SensorNoise{}, 1000);
  Rng ra(42), rb(42);
  const auto x = run(a, s.prev, s.curr, ra), y = run(b, s.prev, s.curr, rb);
  EXPECT_EQ(x.inliers, y.inliers);
  EXPECT_TRUE(x.T_prev_curr.isApprox(y.T_prev_curr, 0));
}

TEST(Ransac, AllPointsOnALineIsDegenerate) {
  std::vector<Eigen::Vector3d> line;
  for (int i = 0; i < 50; ++i) line.emplace_back(0.05 * i, 0.02 * i, 1.0 + 0.01 * i);
  RigidRansac ransac(paper_config(), SensorNoise{}, 1000);
  Rng rng(1);
  EXPECT_EQ(run(ransac, line, line, rng).status, Status::DegenerateSample);
}

TEST(Ransac, PureNoiseHasTooFewInliers) {
  const Scene s = make_scene(Eigen::Isometry3d::Identity(), 100, 1.0, 0.0, 11);
  RigidRansac ransac(paper_config(), SensorNoise{}, 1000);
  Rng rng(1);
  EXPECT_NE(run(ransac, s.prev, s.curr, rng).status, Status::Ok);
}

TEST(Ransac, AdaptiveStopIsDefinedForEveryInlierCount) {
  // A best hypothesis without one inlier (pure mismatches) once made the count -inf cast to int.
  EXPECT_EQ(adaptive_hypotheses(0, 100, 200), 200);
  EXPECT_EQ(adaptive_hypotheses(1, 1000, 200), 200);
  EXPECT_EQ(adaptive_hypotheses(100, 100, 200), 1);
  // Half inliers: 1 - 0.5^3 = 0.875 per draw fails; 0.875^k <= 0.001 at k = 52 (51.7).
  EXPECT_EQ(adaptive_hypotheses(50, 100, 200), 52);
  EXPECT_EQ(adaptive_hypotheses(50, 100, 40), 40);
  EXPECT_EQ(adaptive_hypotheses(0, 0, 200), 200);
}

TEST(Ransac, FewerPairsThanMinimumFails) {
  const Scene s = make_scene(Eigen::Isometry3d::Identity(), 5, 0.0, 0.0, 13);
  RigidRansac ransac(paper_config(), SensorNoise{}, 1000);
  Rng rng(1);
  EXPECT_EQ(run(ransac, s.prev, s.curr, rng).status, Status::RansacFailed);
}

}  // namespace
}  // namespace rgbdo

// ---------------------------------------------------------------------------------------
// RigidRansac against an oracle of what it promises (test/ransac_oracle.hpp): the
// refinement's fixed point and the final fit's optimality, checked with code of its own.

#include "rgbd_odometry/pipeline/odometry.hpp"
#include "rgbd_odometry/io/tum_sequence.hpp"
#include "rgbd_odometry/pipeline/frame_extractor.hpp"
#include "rgbd_odometry/app/config_file.hpp"
#include "ransac_oracle.hpp"
#include "runnable_kernel_sets.hpp"

namespace rgbdo {
namespace {

struct OracleVerdicts {
  int cases = 0, fixed_points = 0, minima = 0, refused = 0;
  double worst_threshold_difference = 0;
  void check(const std::vector<Eigen::Vector3d>& prev, const std::vector<Eigen::Vector3d>& curr, const RansacResult& r,
             const RansacConfig& config, const SensorNoise& noise) {
    if (r.status != Status::Ok) return;
    ++cases;
    const oracle::FixedPoint f =
        oracle::refinement_fixed_point(prev, curr, r.inliers, config.inlier_threshold_m, noise.depth_noise_coeff);
    fixed_points += f.inliers == r.inliers;
    worst_threshold_difference = std::max(worst_threshold_difference, std::abs(f.threshold_m - r.threshold_m));
    const Eigen::Isometry3d d = f.least_squares.inverse() * r.T_prev_curr;
    if (d.translation().norm() < 1e-9 && rotation_angle(d.linear()) < 1e-9) {
      ++refused;  // the anisotropic fit's jump was refused: the least-squares motion stands
      return;
    }
    minima += oracle::is_local_minimum(prev, curr, r.inliers, noise, r.T_prev_curr, 1e-5, 1e-12);
  }
};

TEST(RansacOracle, RealFramesEndAtTheRefinementsFixedPointAndTheFitsMinimum) {
  // GIVEN the 3-D correspondences of the bundled frame pairs (real ORB matches)
  const Config config = load_config(RGBDO_CONFIG_DIR "/tum-fr1.yaml");
  const TumSequence seq = open_tum_sequence(RGBDO_TEST_DATA_DIR);
  FrameExtractor extractor(config);
  const SensorNoise noise = sensor_noise(config);
  RigidRansac ransac(config.ransac, noise, config.features.max_features);
  SymmetricMatcher matcher(config.matching.ratio);
  ProcessedFrame prev, curr;
  extractor.extract(load_tum_frame(seq.frames[0], 5000, 640, 480), prev);
  OracleVerdicts verdicts;
  for (size_t i = 1; i < seq.frames.size(); ++i) {
    extractor.extract(load_tum_frame(seq.frames[i], 5000, 640, 480), curr);
    std::vector<Match> matches;
    matcher.match(prev.features.descriptors, curr.features.descriptors, matches);
    PointPairs pairs;
    build_point_pairs(matches, prev.geometry, prev.times, curr.geometry, curr.times, nullptr, pairs);
    // WHEN RANSAC runs from three seeds
    for (std::uint64_t seed : {1u, 2u, 3u}) {
      Rng rng(seed);
      RansacResult r;
      ransac.estimate(pairs.prev, pairs.curr, rng, r);
      verdicts.check(pairs.prev, pairs.curr, r, config.ransac, noise);
    }
    std::swap(prev, curr);
  }
  // THEN every answer is the refinement's fixed point, and the final motion minimises the
  // Mahalanobis cost (or is the least-squares one where that fit was refused)
  EXPECT_EQ(verdicts.cases, 3 * 39);
  EXPECT_EQ(verdicts.fixed_points, verdicts.cases);
  EXPECT_LT(verdicts.worst_threshold_difference, 1e-9);
  EXPECT_EQ(verdicts.minima + verdicts.refused, verdicts.cases);
  EXPECT_LE(verdicts.refused, verdicts.cases / 20) << "the anisotropic fit refused too often";
}

TEST(RansacOracle, SyntheticScenesEndAtTheRefinementsFixedPointAndTheFitsMinimum) {
  OracleVerdicts verdicts;
  for (unsigned scene_seed = 0; scene_seed < 30; ++scene_seed) {
    Vector6d xi;
    xi << 0.01 * (scene_seed % 5), -0.02, 0.01, 0.01, -0.005 * (scene_seed % 3), 0.01;
    const Scene s = make_scene(transform_from_xi(xi), 300, 0.1 + 0.015 * scene_seed, 0.003, scene_seed);
    RigidRansac ransac(paper_config(), SensorNoise{}, 300);
    Rng rng(scene_seed);
    RansacResult r;
    ransac.estimate(s.prev, s.curr, rng, r);
    verdicts.check(s.prev, s.curr, r, paper_config(), SensorNoise{});
  }
  EXPECT_EQ(verdicts.cases, 30);
  EXPECT_EQ(verdicts.fixed_points, verdicts.cases);
  EXPECT_LT(verdicts.worst_threshold_difference, 1e-9);
  EXPECT_EQ(verdicts.minima + verdicts.refused, verdicts.cases);
}

TEST(RansacOracle, TheOracleCatchesAWrongAnswer) {
  // The oracle must be able to fail: an inlier dropped, or the motion moved by 1 mm, is seen.
  const Scene s = make_scene(transform_from_xi(Vector6d::Constant(0.01)), 300, 0.2, 0.003, 7);
  RigidRansac ransac(paper_config(), SensorNoise{}, 300);
  Rng rng(7);
  RansacResult r;
  ransac.estimate(s.prev, s.curr, rng, r);
  ASSERT_EQ(r.status, Status::Ok);
  RansacResult dropped = r;
  dropped.inliers.pop_back();
  EXPECT_NE(oracle::refinement_fixed_point(s.prev, s.curr, dropped.inliers, 0.05, SensorNoise{}.depth_noise_coeff).inliers,
            dropped.inliers);
  Eigen::Isometry3d moved = r.T_prev_curr;
  moved.translation().x() += 0.001;
  EXPECT_TRUE(oracle::is_local_minimum(s.prev, s.curr, r.inliers, SensorNoise{}, r.T_prev_curr, 1e-5, 1e-12));
  EXPECT_FALSE(oracle::is_local_minimum(s.prev, s.curr, r.inliers, SensorNoise{}, moved, 1e-5, 1e-12));
}

TEST(Triplet, ClosedFormFitEqualsTheSvdFit) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(-1, 1);
  std::normal_distribution<double> g(0, 0.003);
  for (int trial = 0; trial < 200; ++trial) {
    Vector6d xi;
    xi << u(rng) * 0.1, u(rng) * 0.1, u(rng) * 0.1, u(rng) * 0.3, u(rng) * 0.3, u(rng) * 0.3;
    const Eigen::Isometry3d T = transform_from_xi(xi);
    Eigen::Vector3d s[3], d[3];
    for (int i = 0; i < 3; ++i) {
      s[i] = Eigen::Vector3d(u(rng), u(rng), 2 + u(rng));
      d[i] = T * s[i] + Eigen::Vector3d(g(rng), g(rng), g(rng));  // noisy: not exactly rigid
    }
    Eigen::Isometry3d a, b;
    ASSERT_TRUE(fit_triplet(s, d, a));
    ASSERT_TRUE(fit_rigid(std::span<const Eigen::Vector3d>(s, 3), std::span<const Eigen::Vector3d>(d, 3), {}, b));
    EXPECT_LT((a.matrix() - b.matrix()).cwiseAbs().maxCoeff(), 1e-9) << "trial " << trial;
  }
  Eigen::Vector3d line[3] = {{0, 0, 1}, {1, 0, 1}, {2, 0, 1}};
  Eigen::Isometry3d T;
  EXPECT_FALSE(fit_triplet(line, line, T));
}

}  // namespace
}  // namespace rgbdo

namespace rgbdo {
namespace {

TEST(ScoreKernels, EverySetIsBitExactWithTheReference) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(-2, 2);
  for (int n : {0, 1, 3, 7, 8, 9, 15, 16, 17, 100, 501}) {
    std::vector<float> v[6];
    for (auto& a : v)
      for (int k = 0; k < n; ++k) a.push_back(u(rng));
    simd::RigidScoreInput in;
    in.n = n;
    in.px = v[0].data(), in.py = v[1].data(), in.pz = v[2].data();
    in.cx = v[3].data(), in.cy = v[4].data(), in.cz = v[5].data();
    const Eigen::Matrix3d R = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
    for (int e = 0; e < 9; ++e) in.r[e] = static_cast<float>(R(e / 3, e % 3));
    in.t[0] = 0.1f, in.t[1] = -0.2f, in.t[2] = 0.05f;
    in.threshold_sq = 2.0f;  // about half the random pairs fall inside
    int ref_count = -1;
    float ref_cost = -1;
    simd::score_rigid_scalar(in, ref_count, ref_cost);
    // The reference against the definition, in double.
    int def_count = 0;
    for (int k = 0; k < n; ++k) {
      const Eigen::Vector3d p(v[0][static_cast<size_t>(k)], v[1][static_cast<size_t>(k)], v[2][static_cast<size_t>(k)]);
      const Eigen::Vector3d c(v[3][static_cast<size_t>(k)], v[4][static_cast<size_t>(k)], v[5][static_cast<size_t>(k)]);
      const Eigen::Vector3f rc = R.cast<float>() * c.cast<float>();
      def_count += (p - (rc.cast<double>() + Eigen::Vector3d(0.1, -0.2, 0.05))).squaredNorm() < 2.0;
    }
    EXPECT_NEAR(ref_count, def_count, 1) << "n " << n;  // float vs double at the boundary
    for (const auto* set : twins_of_reference(&simd::KernelSet::score_rigid)) {
      int count = -1;
      float cost = -1;
      set->score_rigid(in, count, cost);
      EXPECT_EQ(count, ref_count) << set->name << " n " << n;
      EXPECT_EQ(cost, ref_cost) << set->name << " n " << n;
    }
  }
}

}  // namespace
}  // namespace rgbdo
