// From pair results to message contents: frames, lever arm, the linearisations (each checked
// by finite differences), covariance propagation against Monte Carlo, and what a failed pair
// and a recovery put on the wire.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <tuple>
#include <vector>

#include <Eigen/Eigenvalues>

#include "rgbd_odometry/link/mavlink_odometry.hpp"
#include "rgbd_odometry/core/rng.hpp"

namespace rgbdo {
namespace {

constexpr std::int64_t kFrameNs = 33'333'333;  // 30 Hz

Eigen::Isometry3d transform(const Eigen::Vector3d& t, const Eigen::Vector3d& r) {
  Vector6d xi;
  xi << t, r;
  return transform_from_xi(xi);
}

PairResult pair(std::int64_t index, const Eigen::Isometry3d& T_prev_curr, const Matrix6d& covariance) {
  PairResult p;
  p.t_prev_ns = 1'000'000'000 + index * kFrameNs;
  p.t_curr_ns = p.t_prev_ns + kFrameNs;
  p.status = Status::Ok;
  p.T_prev_curr = T_prev_curr;
  p.covariance = covariance;
  return p;
}

PairResult failed_pair(std::int64_t index) {
  PairResult p;
  p.t_prev_ns = 1'000'000'000 + index * kFrameNs;
  p.t_curr_ns = p.t_prev_ns + kFrameNs;
  p.status = Status::TooFewMatches;  // identity pose, NaN covariance: the pipeline's convention
  return p;
}

Matrix6d diagonal_covariance(double sigma_t, double sigma_r) {
  Vector6d d;
  d << Eigen::Vector3d::Constant(sigma_t * sigma_t), Eigen::Vector3d::Constant(sigma_r * sigma_r);
  return d.asDiagonal();
}

// A full, correlated covariance with the given scales (fixed seed, the project's generator).
Matrix6d correlated_covariance(double sigma_t, double sigma_r, unsigned seed) {
  Rng rng(seed);
  Matrix6d L = Matrix6d::Zero();
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j <= i; ++j) L(i, j) = (i == j ? 1.0 : 0.4) * rng.gaussian() + (i == j ? 1.5 : 0.0);
  Vector6d scale;
  scale << Eigen::Vector3d::Constant(sigma_t), Eigen::Vector3d::Constant(sigma_r);
  const Matrix6d S = scale.asDiagonal();
  return S * (L * L.transpose() / 3.0) * S;
}

CameraExtrinsic tilted_camera_with_lever_arm() {
  // Forward camera pitched down 20 deg, 12 cm ahead, 3 cm right and 5 cm below the origin.
  CameraExtrinsic X;
  X.R_body_camera = Eigen::AngleAxisd(-20 * std::numbers::pi / 180, Eigen::Vector3d::UnitY()).toRotationMatrix() *
                    CameraExtrinsic::forward_looking_rotation();
  X.p_body_camera_m = Eigen::Vector3d(0.12, 0.03, 0.05);
  return X;
}

Eigen::Isometry3d to_isometry(const CameraExtrinsic& X) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = X.R_body_camera;
  T.translation() = X.p_body_camera_m;
  return T;
}

Matrix6d full(const std::array<float, 21>& upper) {
  Matrix6d C;
  std::size_t k = 0;
  for (int i = 0; i < 6; ++i)
    for (int j = i; j < 6; ++j) C(i, j) = C(j, i) = upper[k++];
  return C;
}

Eigen::Matrix3d euler_to_rotation(double roll, double pitch, double yaw) {
  return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

double wrap_pi(double a) { return std::remainder(a, 2 * std::numbers::pi); }

// ---- frames ------------------------------------------------------------------------------

TEST(MavlinkOdometry, ForwardCameraMotionIsBodyForward) {
  // GIVEN the default forward-looking camera moving 10 cm along its optical axis (+z)
  OdometryMessageBuilder builder;
  builder.add(pair(0, transform({0, 0, 0.10}, {0, 0, 0}), diagonal_covariance(0.002, 0.001)));
  // THEN the body moved 10 cm forward (+x), at 3 m/s
  const auto o = builder.odometry();
  ASSERT_TRUE(o);
  EXPECT_NEAR(o->x, 0.10, 1e-7);
  EXPECT_NEAR(o->y, 0.0, 1e-7);
  EXPECT_NEAR(o->z, 0.0, 1e-7);
  EXPECT_NEAR(o->vx, 3.0, 1e-5);
  EXPECT_NEAR(o->vy, 0.0, 1e-6);
  EXPECT_NEAR(o->vz, 0.0, 1e-6);
  EXPECT_EQ(o->frame_id, mavlink::kMavFrameLocalFrd);
  EXPECT_EQ(o->child_frame_id, mavlink::kMavFrameBodyFrd);
  EXPECT_EQ(o->estimator_type, mavlink::kMavEstimatorTypeVision);
  const auto d = builder.vision_position_delta();
  ASSERT_TRUE(d);
  EXPECT_NEAR(d->position_delta[0], 0.10, 1e-7);
  EXPECT_NEAR(d->position_delta[1], 0.0, 1e-7);
  EXPECT_NEAR(d->position_delta[2], 0.0, 1e-7);
  // and camera right (+x) and down (+y) are body right (+y) and down (+z)
  OdometryMessageBuilder side;
  side.add(pair(0, transform({0.05, 0.02, 0}, {0, 0, 0}), diagonal_covariance(0.002, 0.001)));
  EXPECT_NEAR(side.odometry()->y, 0.05, 1e-7);
  EXPECT_NEAR(side.odometry()->z, 0.02, 1e-7);
}

TEST(MavlinkOdometry, CameraPanningRightIsPositiveYaw) {
  // A rotation about the camera's +y (down) axis turns the optical axis toward +x (right):
  // a yaw to the right, positive about the body's +z (down).
  const double angle = 0.05;
  OdometryMessageBuilder builder;
  builder.add(pair(0, transform({0, 0, 0}, {0, angle, 0}), diagonal_covariance(0.002, 0.001)));
  const auto o = builder.odometry();
  EXPECT_NEAR(o->yawspeed, angle / (kFrameNs * 1e-9), 1e-5);
  EXPECT_NEAR(o->rollspeed, 0, 1e-7);
  EXPECT_NEAR(o->pitchspeed, 0, 1e-7);
  // q = (cos(a/2), 0, 0, sin(a/2)), w first
  EXPECT_NEAR(o->q[0], std::cos(angle / 2), 1e-7);
  EXPECT_NEAR(o->q[3], std::sin(angle / 2), 1e-7);
  EXPECT_NEAR(builder.vision_position_delta()->angle_delta[2], angle, 1e-7);
}

TEST(MavlinkOdometry, LeverArmRotationInPlaceIsNoBodyTranslation) {
  // GIVEN a camera 20 cm ahead of and 5 cm above the body origin, and a vehicle yawing in place
  CameraExtrinsic X;
  X.p_body_camera_m = {0.20, 0.0, -0.05};
  const Eigen::Isometry3d dT_b = transform({0, 0, 0}, {0, 0, 0.08});
  // the camera swings along an arc: its own motion is dT_c = X^-1 dT_b X
  const Eigen::Isometry3d dT_c = to_isometry(X).inverse() * dT_b * to_isometry(X);
  ASSERT_GT(dT_c.translation().norm(), 0.01);
  MavlinkOdometryConfig config;
  config.extrinsic = X;
  OdometryMessageBuilder builder(config);
  builder.add(pair(0, dT_c, diagonal_covariance(0.002, 0.001)));
  // THEN the body did not translate, and yawed by 0.08 rad
  const auto o = builder.odometry();
  EXPECT_NEAR(std::hypot(o->x, o->y, o->z), 0, 1e-7);
  EXPECT_NEAR(std::hypot(o->vx, o->vy, o->vz), 0, 1e-5);
  EXPECT_NEAR(o->yawspeed, 0.08 / (kFrameNs * 1e-9), 1e-5);
  const auto d = builder.vision_position_delta();
  EXPECT_NEAR(std::hypot(d->position_delta[0], d->position_delta[1], d->position_delta[2]), 0, 1e-7);
  // and the lever arm shows in the translation covariance: rotation noise moves the camera
  const BodyMotion m = body_motion(pair(0, dT_c, diagonal_covariance(0.0, 0.01)), X);
  const double lever_arm_variance = m.covariance.topLeftCorner<3, 3>().trace();
  EXPECT_GT(lever_arm_variance, 0.0);
  const BodyMotion m0 = body_motion(pair(0, dT_c, diagonal_covariance(0.0, 0.01)), CameraExtrinsic{});
  const double no_lever_arm_variance = m0.covariance.topLeftCorner<3, 3>().trace();
  EXPECT_NEAR(no_lever_arm_variance, 0.0, 1e-15);
}

TEST(MavlinkOdometry, PositionDeltaIsExpressedInTheCurrentBodyFrame) {
  // GIVEN the body moving 10 cm forward while yawing 90 deg (in the previous body frame the
  // step is +x; the current body's x axis points along the previous +y)
  CameraExtrinsic X;
  const Eigen::Isometry3d dT_b = transform({0.10, 0, 0}, {0, 0, std::numbers::pi / 2});
  OdometryMessageBuilder builder;
  builder.add(pair(0, to_isometry(X).inverse() * dT_b * to_isometry(X), diagonal_covariance(0.002, 0.001)));
  // THEN the delta is rotated into the current body frame: the step lies along its -y
  const auto d = builder.vision_position_delta();
  EXPECT_NEAR(d->position_delta[0], 0.0, 1e-7);
  EXPECT_NEAR(d->position_delta[1], -0.10, 1e-7);
  EXPECT_NEAR(builder.odometry()->vy, -0.10 / (kFrameNs * 1e-9), 1e-5);
  // while the pose is in the local frame: +x
  EXPECT_NEAR(builder.odometry()->x, 0.10, 1e-7);
}

TEST(MavlinkOdometry, TimestampsInMicroseconds) {
  OdometryMessageBuilder builder;
  PairResult p = pair(0, transform({0, 0, 0.01}, {0, 0, 0}), diagonal_covariance(0.002, 0.001));
  p.t_prev_ns = 1'000'000'999;
  p.t_curr_ns = 1'033'334'001;
  builder.add(p);
  EXPECT_EQ(builder.odometry()->time_usec, 1'033'334u);
  EXPECT_EQ(builder.vision_position_delta()->time_usec, 1'033'334u);
  EXPECT_EQ(builder.vision_position_delta()->time_delta_usec, 1'033'334u - 1'000'000u);
}

// ---- linearisations by finite differences ---------------------------------------------------

TEST(MavlinkOdometryJacobians, So3RightJacobian) {
  for (const Eigen::Vector3d& r : {Eigen::Vector3d(0.3, -0.2, 0.5), Eigen::Vector3d(2e-5, -1e-5, 3e-5)}) {
    const Eigen::Matrix3d Jr = so3_right_jacobian(r);
    const double h = 1e-6;
    for (int j = 0; j < 3; ++j) {
      const Eigen::Vector3d e = Eigen::Vector3d::Unit(j) * h;
      // exp(r)^T exp(r + e) = exp(Jr e)
      const Eigen::Vector3d plus = rotation_vector(rotation_from_vector(r).transpose() * rotation_from_vector(r + e));
      const Eigen::Vector3d minus = rotation_vector(rotation_from_vector(r).transpose() * rotation_from_vector(r - e));
      EXPECT_LT(((plus - minus) / (2 * h) - Jr.col(j)).norm(), 1e-8) << "r " << r.transpose() << " col " << j;
    }
  }
}

TEST(MavlinkOdometryJacobians, CameraToBodyByFiniteDifferences) {
  const CameraExtrinsic X = tilted_camera_with_lever_arm();
  const Eigen::Isometry3d T_bc = to_isometry(X);
  Vector6d xi_c;
  xi_c << 0.03, -0.01, 0.12, 0.05, -0.12, 0.08;
  const auto xi_b_of = [&](const Vector6d& xi) {
    return xi_from_transform(T_bc * transform_from_xi(xi) * T_bc.inverse());
  };
  const Matrix6d J = camera_to_body_jacobian(X, T_bc * transform_from_xi(xi_c) * T_bc.inverse());
  const double h = 1e-6;
  for (int j = 0; j < 6; ++j) {
    const Vector6d e = Vector6d::Unit(j) * h;
    const Vector6d fd = (xi_b_of(xi_c + e) - xi_b_of(xi_c - e)) / (2 * h);
    EXPECT_LT((fd - J.col(j)).norm(), 1e-8) << "column " << j << "\nfd " << fd.transpose() << "\nJ  "
                                            << J.col(j).transpose();
  }
  // At zero rotation it is the first-order form [[R, [p]x R], [0, R]].
  const Matrix6d J0 = camera_to_body_jacobian(X, Eigen::Isometry3d::Identity());
  Eigen::Matrix3d P;
  const Eigen::Vector3d& p = X.p_body_camera_m;
  P << 0, -p.z(), p.y(), p.z(), 0, -p.x(), -p.y(), p.x(), 0;
  EXPECT_LT((J0.topRightCorner<3, 3>() - P * X.R_body_camera).norm(), 1e-15);
}

TEST(MavlinkOdometryJacobians, EulerAnglesOfALeftPerturbationByFiniteDifferences) {
  const double roll = 0.3, pitch = -0.4, yaw = 2.0;
  const Eigen::Matrix3d R = euler_to_rotation(roll, pitch, yaw);
  const Eigen::Vector3d e = euler_zyx(R);
  EXPECT_NEAR(e.x(), roll, 1e-12);
  EXPECT_NEAR(e.y(), pitch, 1e-12);
  EXPECT_NEAR(e.z(), yaw, 1e-12);
  const Eigen::Matrix3d G = euler_zyx_jacobian_left(R);
  const double h = 1e-6;
  for (int j = 0; j < 3; ++j) {
    const Eigen::Vector3d d = Eigen::Vector3d::Unit(j) * h;
    const Eigen::Vector3d plus = euler_zyx(rotation_from_vector(d) * R);
    const Eigen::Vector3d minus = euler_zyx(rotation_from_vector(-d) * R);
    Eigen::Vector3d fd;
    for (int i = 0; i < 3; ++i) fd(i) = wrap_pi(plus(i) - minus(i)) / (2 * h);
    EXPECT_LT((fd - G.col(j)).norm(), 1e-8) << "column " << j;
  }
}

TEST(MavlinkOdometryJacobians, VelocityCovarianceIsTheLinearisedVelocity) {
  BodyMotion m;
  Vector6d xi;
  xi << 0.09, -0.02, 0.01, 0.02, -0.04, 0.15;
  m.T_prev_curr = transform_from_xi(xi);
  m.covariance = correlated_covariance(0.003, 0.002, 5);
  m.dt_s = 0.04;
  const auto f = [&](const Vector6d& x) {  // (dR^T t / dt, r / dt)
    Vector6d out;
    out << rotation_from_vector(x.tail<3>()).transpose() * x.head<3>() / m.dt_s, x.tail<3>() / m.dt_s;
    return out;
  };
  Matrix6d F;
  const double h = 1e-6;
  for (int j = 0; j < 6; ++j) F.col(j) = (f(xi + Vector6d::Unit(j) * h) - f(xi - Vector6d::Unit(j) * h)) / (2 * h);
  const Matrix6d expected = F * m.covariance * F.transpose();
  EXPECT_LT((velocity_covariance(m) - expected).norm(), 1e-6 * expected.norm());
}

TEST(MavlinkOdometry, UpperTriangleIsRowMajor) {
  Matrix6d C;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) C(i, j) = 10 * std::min(i, j) + std::max(i, j);  // symmetric, distinct
  const auto u = upper_triangle(C);
  // first six: row 0 (00..05), next five: row 1 (11..15), ..., last: 55
  const std::array<float, 21> expected{0, 1, 2, 3, 4, 5, 11, 12, 13, 14, 15, 22, 23, 24, 25, 33, 34, 35, 44, 45, 55};
  EXPECT_EQ(u, expected);
}

// ---- covariance propagation -------------------------------------------------------------------

TEST(MavlinkOdometryCovariance, GrowsMonotonically) {
  OdometryMessageBuilder builder;
  double last_position_trace = 0;
  Matrix6d last = Matrix6d::Zero();
  for (int k = 0; k < 50; ++k) {
    builder.add(pair(k, transform({0.002, 0.001, 0.03}, {0.002, 0.01, -0.003}), correlated_covariance(0.002, 0.001, 3)));
    const Matrix6d& P = builder.pose_covariance();
    const double position_trace = P.topLeftCorner<3, 3>().trace();
    EXPECT_GT(position_trace, last_position_trace) << "step " << k;
    // the attitude block only ever gains (Loewner order)
    const Eigen::Matrix3d gain = P.bottomRightCorner<3, 3>() - last.bottomRightCorner<3, 3>();
    const double smallest_gain = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(gain).eigenvalues().minCoeff();
    EXPECT_GT(smallest_gain, 0.0) << "step " << k;
    // and the message's variances (MAVLink parameters) grow too
    const Matrix6d wire = full(builder.odometry()->pose_covariance);
    for (int i = 0; i < 6; ++i) EXPECT_GT(wire(i, i), 0.0) << "step " << k;
    last_position_trace = position_trace;
    last = P;
  }
}

Matrix6d sample_covariance(const std::vector<Vector6d>& xs) {
  Vector6d mean = Vector6d::Zero();
  for (const auto& x : xs) mean += x;
  mean /= static_cast<double>(xs.size());
  Matrix6d C = Matrix6d::Zero();
  for (const auto& x : xs) C += (x - mean) * (x - mean).transpose();
  return C / static_cast<double>(xs.size() - 1);
}

// Variances within 5 % (the sampling error of 20000 draws is ~1 %), correlations within 0.03.
void expect_covariance_matches(const Matrix6d& analytic, const Matrix6d& sampled, const char* name) {
  for (int i = 0; i < 6; ++i) EXPECT_NEAR(analytic(i, i) / sampled(i, i), 1.0, 0.05) << name << " axis " << i;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < i; ++j)
      EXPECT_NEAR(analytic(i, j) / std::sqrt(analytic(i, i) * analytic(j, j)),
                  sampled(i, j) / std::sqrt(sampled(i, i) * sampled(j, j)), 0.03)
          << name << " (" << i << ", " << j << ")";
}

// Chains the camera motions through the builder, then draws each motion from its
// distribution and chains the draws, many times; the builder's covariance must match the
// spread of the draws about the nominal pose, in both parameterisations.
void expect_propagation_matches_monte_carlo(const CameraExtrinsic& X, const std::vector<Vector6d>& means,
                                            const std::vector<Matrix6d>& covariances, unsigned seed) {
  const Eigen::Isometry3d T_bc = to_isometry(X);
  MavlinkOdometryConfig config;
  config.extrinsic = X;
  OdometryMessageBuilder builder(config);
  for (std::size_t k = 0; k < means.size(); ++k)
    builder.add(pair(static_cast<std::int64_t>(k), transform_from_xi(means[k]), covariances[k]));
  const Matrix6d P = builder.pose_covariance();
  const Matrix6d P_wire = full(builder.odometry()->pose_covariance);
  const Eigen::Isometry3d T_nominal = builder.pose();
  const Eigen::Vector3d e_nominal = euler_zyx(T_nominal.linear());

  // The project's generator, not std::normal_distribution: the draws, and so the verdict, are
  // the same on every architecture the tests run on.
  Rng rng(seed);
  std::vector<Matrix6d> L;
  for (const auto& C : covariances) L.push_back(Eigen::LLT<Matrix6d>(C).matrixL());
  const int trials = 20000;
  std::vector<Vector6d> left(trials), euler(trials);  // (dp, dth) and (dp, droll, dpitch, dyaw)
  for (std::size_t n = 0; n < left.size(); ++n) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    for (std::size_t k = 0; k < means.size(); ++k) {
      Vector6d z;
      for (int i = 0; i < 6; ++i) z(i) = rng.gaussian();
      T = T * (T_bc * transform_from_xi(means[k] + L[k] * z) * T_bc.inverse());
    }
    const Eigen::Vector3d dp = T.translation() - T_nominal.translation();
    left[n] << dp, rotation_vector(T.linear() * T_nominal.linear().transpose());
    const Eigen::Vector3d e = euler_zyx(T.linear());
    euler[n] << dp, wrap_pi(e.x() - e_nominal.x()), wrap_pi(e.y() - e_nominal.y()), wrap_pi(e.z() - e_nominal.z());
  }
  expect_covariance_matches(P, sample_covariance(left), "left (dp, dth)");
  expect_covariance_matches(P_wire, sample_covariance(euler), "MAVLink (p, rpy)");
}

TEST(MavlinkOdometryCovariance, AgreesWithMonteCarloOverSeveralSteps) {
  // GIVEN a tilted camera with a lever arm and five different noisy camera motions of a
  // vehicle at walking pace
  std::vector<Vector6d> means;
  std::vector<Matrix6d> covariances;
  for (int k = 0; k < 5; ++k) {
    Vector6d xi;
    xi << 0.01 * k, -0.004, 0.05, 0.03, 0.06 - 0.02 * k, -0.02;
    means.push_back(xi);
    covariances.push_back(correlated_covariance(0.004, 0.003, 11 + static_cast<unsigned>(k)));
  }
  expect_propagation_matches_monte_carlo(tilted_camera_with_lever_arm(), means, covariances, 20240607);
}

TEST(MavlinkOdometryCovariance, AgreesWithMonteCarloUnderFastTurns) {
  // GIVEN large turns per pair (0.4-0.5 rad) and strongly anisotropic noise: which attitude
  // rotates the step noise (R_{k-1}, not R_k) and the right Jacobian in B both show here
  std::vector<Vector6d> means;
  std::vector<Matrix6d> covariances;
  Vector6d anisotropic;
  anisotropic << 0.001, 0.002, 0.008, 0.0005, 0.004, 0.001;
  for (int k = 0; k < 4; ++k) {
    Vector6d xi;
    xi << 0.05, 0.01 * k, 0.15, 0.1 * k, 0.4, -0.2;
    means.push_back(xi);
    covariances.push_back(Matrix6d(anisotropic.cwiseProduct(anisotropic).asDiagonal()));
  }
  expect_propagation_matches_monte_carlo(tilted_camera_with_lever_arm(), means, covariances, 77);
}

PairResult chain_pair(std::int64_t index, const Eigen::Isometry3d& T_prev_curr, const Matrix6d& covariance,
                      bool chain_started, const Matrix6d& chain_covariance) {
  PairResult p = pair(index, T_prev_curr, covariance);
  p.keyframe.id = 1;
  p.keyframe.chain_started = chain_started;
  p.keyframe.pose_covariance = chain_covariance;
  return p;
}

TEST(MavlinkOdometryCovariance, WithKeyframesItIsTheChainsAndHoldsOverOneView) {
  // GIVEN a hover: 60 still pairs, each uncertain, while the keyframes hold the pose to the
  // chain's first frame within a fixed covariance
  const Matrix6d pair_cov = correlated_covariance(0.003, 0.002, 5);
  const Matrix6d chain_cov = correlated_covariance(0.002, 0.001, 6);
  OdometryMessageBuilder with, without;
  const Eigen::Isometry3d still = Eigen::Isometry3d::Identity();
  for (int k = 0; k < 60; ++k) {
    with.add(chain_pair(k, still, pair_cov, k == 0, k == 0 ? Matrix6d::Zero() : chain_cov));
    without.add(pair(k, still, pair_cov));
  }
  // THEN the chain's P is the first pair's plus the chain's, and holds; integrated, it grows
  const Matrix6d first = [&] {
    OdometryMessageBuilder one;
    one.add(pair(0, still, pair_cov));
    return one.pose_covariance();
  }();
  const Matrix6d chain_in_body = [&] {
    OdometryMessageBuilder one;  // the same covariance integrated once from the origin
    one.add(pair(0, still, chain_cov));
    return one.pose_covariance();
  }();
  EXPECT_TRUE(with.pose_covariance().isApprox(first + chain_in_body, 1e-9));
  const double integrated = without.pose_covariance().topLeftCorner<3, 3>().trace();
  const double first_trace = first.topLeftCorner<3, 3>().trace();
  EXPECT_GT(integrated, 50 * first_trace);
}

TEST(MavlinkOdometryCovariance, TheChainsAgreesWithMonteCarlo) {
  // GIVEN a tilted camera with a lever arm, three integrated motions, then a chain that begins
  // with a fourth and has moved and turned since, with its own covariance of that
  const CameraExtrinsic X = tilted_camera_with_lever_arm();
  const Eigen::Isometry3d T_bc = to_isometry(X);
  MavlinkOdometryConfig config;
  config.extrinsic = X;
  OdometryMessageBuilder builder(config);
  std::vector<Vector6d> means;
  std::vector<Matrix6d> covariances;
  for (int k = 0; k < 4; ++k) {
    Vector6d xi;
    xi << 0.02, -0.01 * k, 0.06, 0.05, 0.1 - 0.05 * k, 0.03;
    means.push_back(xi);
    covariances.push_back(correlated_covariance(0.004, 0.003, 21 + static_cast<unsigned>(k)));
    builder.add(k < 3 ? pair(k, transform_from_xi(xi), covariances.back())
                      : chain_pair(k, transform_from_xi(xi), covariances.back(), true, Matrix6d::Zero()));
  }
  Vector6d since_xi;
  since_xi << 0.3, -0.05, 0.4, 0.1, 0.5, -0.2;
  const Eigen::Isometry3d since = transform_from_xi(since_xi);  // the camera's motion since the chain began
  const Matrix6d since_cov = correlated_covariance(0.01, 0.008, 31);
  // Two pairs make up that motion; the second carries the chain's covariance of the whole.
  const Eigen::Isometry3d half = transform_from_xi(0.5 * since_xi);
  builder.add(chain_pair(4, half, covariances[0], false, covariances[0]));
  builder.add(chain_pair(5, half.inverse() * since, covariances[0], false, since_cov));
  const Matrix6d P = builder.pose_covariance();
  const Eigen::Isometry3d T_nominal = builder.pose();

  // THEN P is the spread of: the four motions drawn, then the chain's motion drawn as a right
  // perturbation of the camera's pose since its origin
  Rng rng(99);
  std::vector<Matrix6d> L;
  for (const auto& C : covariances) L.push_back(Eigen::LLT<Matrix6d>(C).matrixL());
  const Matrix6d L_since = Eigen::LLT<Matrix6d>(since_cov).matrixL();
  const auto draw = [&rng] {
    Vector6d z;
    for (int i = 0; i < 6; ++i) z(i) = rng.gaussian();
    return z;
  };
  std::vector<Vector6d> left(20000);
  for (Vector6d& out : left) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    for (std::size_t k = 0; k < means.size(); ++k)
      T = T * (T_bc * transform_from_xi(means[k] + L[k] * draw()) * T_bc.inverse());
    T = T * (T_bc * since * transform_from_xi(L_since * draw()) * T_bc.inverse());
    out << T.translation() - T_nominal.translation(), rotation_vector(T.linear() * T_nominal.linear().transpose());
  }
  expect_covariance_matches(P, sample_covariance(left), "chain, left (dp, dth)");
}

// ---- failures, resets, quality ------------------------------------------------------------

TEST(MavlinkOdometry, NothingBeforeTheFirstPairAndStandby) {
  OdometryMessageBuilder builder;
  EXPECT_FALSE(builder.odometry());
  EXPECT_FALSE(builder.vision_position_delta());
  const auto h = builder.heartbeat();
  EXPECT_EQ(h.system_status, mavlink::kMavStateStandby);
  EXPECT_EQ(h.type, mavlink::kMavTypeOnboardController);
  EXPECT_EQ(h.autopilot, mavlink::kMavAutopilotInvalid);
  EXPECT_EQ(h.base_mode, 0);
  EXPECT_EQ(h.custom_mode, 0u);
  EXPECT_EQ(h.mavlink_version, 3);
}

TEST(MavlinkOdometry, FailedPairCarriesNoPoseAndRecoveryIncrementsResetOnce) {
  OdometryMessageBuilder builder;
  const Matrix6d S = diagonal_covariance(0.003, 0.002);
  builder.add(pair(0, transform({0, 0, 0.05}, {0, 0.01, 0}), S));
  builder.add(pair(1, transform({0, 0, 0.05}, {0, 0.01, 0}), S));
  EXPECT_EQ(builder.heartbeat().system_status, mavlink::kMavStateActive);
  const auto good = *builder.odometry();
  EXPECT_GE(good.quality, 1);
  EXPECT_EQ(good.reset_counter, 0);

  // WHEN two pairs fail
  for (int k = 2; k < 4; ++k) {
    builder.add(failed_pair(k));
    const auto o = *builder.odometry();
    // THEN no pose at all (PX4 at EKF2_EV_QMIN 0 would fuse a finite one, the last pose, as a
    // frozen vehicle), the velocities unknown, quality says failed
    EXPECT_TRUE(std::isnan(o.x) && std::isnan(o.y) && std::isnan(o.z));
    for (const float c : o.q) EXPECT_TRUE(std::isnan(c));
    for (const float c : o.pose_covariance) EXPECT_TRUE(std::isnan(c));
    EXPECT_TRUE(std::isnan(o.vx) && std::isnan(o.vy) && std::isnan(o.vz));
    EXPECT_TRUE(std::isnan(o.rollspeed) && std::isnan(o.pitchspeed) && std::isnan(o.yawspeed));
    for (const float c : o.velocity_covariance) EXPECT_TRUE(std::isnan(c));
    EXPECT_EQ(o.quality, -1);
    EXPECT_EQ(o.reset_counter, 0);
    EXPECT_EQ(o.time_usec, static_cast<std::uint64_t>(failed_pair(k).t_curr_ns / 1000));
    EXPECT_FALSE(builder.vision_position_delta());
    EXPECT_EQ(builder.heartbeat().system_status, mavlink::kMavStateCritical);
  }

  // WHEN tracking returns
  builder.add(pair(4, transform({0, 0, 0.05}, {0, 0.01, 0}), S));
  // THEN the reset counter says the pose jumped, once
  EXPECT_EQ(builder.odometry()->reset_counter, 1);
  EXPECT_TRUE(builder.vision_position_delta());
  EXPECT_EQ(builder.heartbeat().system_status, mavlink::kMavStateActive);
  EXPECT_FALSE(std::isnan(builder.odometry()->vx));
  // and the pose goes on from the last one sent, one step further: the failures moved nothing
  EXPECT_NEAR(builder.odometry()->x, 3 * good.x / 2, 1e-5);
  builder.add(pair(5, transform({0, 0, 0.05}, {0, 0.01, 0}), S));
  EXPECT_EQ(builder.odometry()->reset_counter, 1);
}

TEST(MavlinkOdometry, OkPairWithUnusableNumbersIsSentAsFailed) {
  OdometryMessageBuilder builder;
  PairResult p = pair(0, transform({0, 0, 0.05}, {0, 0, 0}), diagonal_covariance(0.003, 0.002));
  p.covariance(0, 0) = std::numeric_limits<double>::quiet_NaN();
  builder.add(p);
  EXPECT_EQ(builder.odometry()->quality, -1);
  PairResult backwards = pair(1, transform({0, 0, 0.05}, {0, 0, 0}), diagonal_covariance(0.003, 0.002));
  backwards.t_curr_ns = backwards.t_prev_ns;
  builder.add(backwards);
  EXPECT_EQ(builder.odometry()->quality, -1);
  EXPECT_FALSE(builder.vision_position_delta());
}

// GIVEN deltas composed over at least 50 ms (ArduPilot's EKF3 drops closer ones), WHEN pairs
// of 33 ms come, THEN every second pair sends one delta of both motions with the summed
// interval, and a failed pair starts the composition again.
TEST(MavlinkOdometry, DeltasAreComposedOverTheMinimumInterval) {
  MavlinkOdometryConfig config;
  config.delta_min_interval_s = 0.05;
  OdometryMessageBuilder builder(config);
  const Matrix6d S = diagonal_covariance(0.003, 0.002);
  const Eigen::Isometry3d step = transform({0.01, 0, 0.05}, {0, 0.02, 0});
  builder.add(pair(0, step, S));
  EXPECT_FALSE(builder.vision_position_delta()) << "33 ms: below 50";
  builder.add(pair(1, step, S));
  const auto d = builder.vision_position_delta();
  ASSERT_TRUE(d);
  EXPECT_EQ(d->time_delta_usec, static_cast<std::uint64_t>((pair(1, step, S).t_curr_ns - pair(0, step, S).t_prev_ns) / 1000));
  // The two body motions composed: the same as the body pose after them (it started at identity).
  const Eigen::Isometry3d& T = builder.pose();
  const Eigen::Vector3d r = rotation_vector(T.linear()), t = T.linear().transpose() * T.translation();
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(d->angle_delta[static_cast<size_t>(i)], r[i], 1e-6);
    EXPECT_NEAR(d->position_delta[static_cast<size_t>(i)], t[i], 1e-6);
  }
  // A second delta needs two more pairs; a failure in between starts again.
  builder.add(pair(2, step, S));
  EXPECT_FALSE(builder.vision_position_delta());
  builder.add(failed_pair(3));
  builder.add(pair(4, step, S));
  EXPECT_FALSE(builder.vision_position_delta()) << "the pair before the failure is not part of it";
  builder.add(pair(5, step, S));
  EXPECT_TRUE(builder.vision_position_delta());
}

// GIVEN the autopilot's roll and pitch at the first pair, THEN the pose starts there (the local
// frame level, yawed as the body), a forward step moves along the tilted body x in it, and the
// attitude sent has that roll and pitch; once a pose exists the frame is not levelled again.
TEST(MavlinkOdometry, TheLocalFrameIsLevelledWithTheInitialAttitude) {
  OdometryMessageBuilder builder;
  const double roll = 0.1, pitch = -0.05;
  ASSERT_TRUE(builder.level_initial_attitude(roll, pitch));
  builder.add(pair(0, transform({0, 0, 0.05}, {0, 0, 0}), diagonal_covariance(0.003, 0.002)));  // camera z: body x
  const Eigen::Matrix3d R0 = (Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                              Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX())).toRotationMatrix();
  const Eigen::Vector3d expected = R0 * Eigen::Vector3d(0.05, 0, 0);
  const auto o = *builder.odometry();
  EXPECT_NEAR(o.x, expected.x(), 1e-7);
  EXPECT_NEAR(o.z, expected.z(), 1e-7);  // nose 0.05 rad down: forward goes down (z +2.5 mm)
  const Eigen::Vector3d rpy = euler_zyx(Eigen::Quaterniond(o.q[0], o.q[1], o.q[2], o.q[3]).toRotationMatrix());
  EXPECT_NEAR(rpy.x(), roll, 1e-6);
  EXPECT_NEAR(rpy.y(), pitch, 1e-6);
  EXPECT_NEAR(rpy.z(), 0, 1e-6);
  EXPECT_FALSE(builder.level_initial_attitude(0.3, 0.3)) << "a pose exists: the frame stays";
}

TEST(MavlinkOdometry, SensorResetIncrementsAndTheCounterWraps) {
  OdometryMessageBuilder builder;
  builder.add(pair(0, transform({0, 0, 0.05}, {0, 0, 0}), diagonal_covariance(0.003, 0.002)));
  builder.note_sensor_reset();
  EXPECT_EQ(builder.reset_counter(), 1);
  EXPECT_EQ(builder.odometry()->reset_counter, 1);
  // a failure followed by a sensor reset announces one jump, not two
  builder.add(failed_pair(1));
  builder.note_sensor_reset();
  builder.add(pair(2, transform({0, 0, 0.05}, {0, 0, 0}), diagonal_covariance(0.003, 0.002)));
  EXPECT_EQ(builder.reset_counter(), 2);
  for (int i = 0; i < 254; ++i) builder.note_sensor_reset();
  EXPECT_EQ(builder.reset_counter(), 0);  // 256 wraps to 0, as uint8 on the wire
}

TEST(MavlinkOdometry, QualityFromTranslationSigma) {
  MavlinkOdometryConfig config;  // sigma_fail 2 cm
  const auto quality_for = [&](double sigma_t) {
    OdometryMessageBuilder b(config);
    b.add(pair(0, transform({0, 0, 0.05}, {0, 0, 0}), diagonal_covariance(sigma_t, 0.001)));
    return b.odometry()->quality;
  };
  EXPECT_EQ(quality_for(0.0), 100);
  EXPECT_EQ(quality_for(0.010), 50);
  EXPECT_EQ(quality_for(0.015), 25);
  EXPECT_EQ(quality_for(0.0199), 1);  // 100 (1 - 0.995) = 0.5 rounds to 1
  EXPECT_EQ(quality_for(0.0201), 1);  // -0.5 rounds to -1: clamped, never 0 ("unknown") or -1 ("failed")
  EXPECT_EQ(quality_for(0.05), 1);
}

TEST(MavlinkOdometry, ConfidenceInvertsArduPilotsVelocityNoiseMap) {
  // GIVEN dt = 50 ms and s_t = 1 cm: s_v = 0.2 m/s
  MavlinkOdometryConfig config;  // VIS_VERR_MIN 0.1, VIS_VERR_MAX 0.9
  OdometryMessageBuilder builder(config);
  PairResult p = pair(0, transform({0, 0, 0.05}, {0, 0, 0}), diagonal_covariance(0.01, 0.001));
  p.t_curr_ns = p.t_prev_ns + 50'000'000;
  builder.add(p);
  const float c = builder.vision_position_delta()->confidence;
  EXPECT_NEAR(c, 87.5, 1e-4);
  // THEN ArduPilot's EKF3 (writeBodyFrameOdom) turns it back into that noise
  const double vel_err = 0.1 + (0.9 - 0.1) * (1.0 - 0.01 * c);
  EXPECT_NEAR(vel_err, 0.2, 1e-6);
  // and the ends clamp
  OdometryMessageBuilder sharp(config), blurred(config);
  sharp.add(pair(0, transform({0, 0, 0.05}, {0, 0, 0}), diagonal_covariance(0.0, 0.001)));
  blurred.add(pair(0, transform({0, 0, 0.05}, {0, 0, 0}), diagonal_covariance(0.1, 0.001)));
  EXPECT_EQ(sharp.vision_position_delta()->confidence, 100.f);
  EXPECT_EQ(blurred.vision_position_delta()->confidence, 0.f);
}

TEST(MavlinkOdometry, FirstPairFailedThenRecoveryIsAReset) {
  OdometryMessageBuilder builder;
  builder.add(failed_pair(0));
  const auto o = builder.odometry();
  ASSERT_TRUE(o);
  EXPECT_EQ(o->quality, -1);
  EXPECT_TRUE(std::isnan(o->x));
  EXPECT_EQ(builder.heartbeat().system_status, mavlink::kMavStateCritical);
  builder.add(pair(1, transform({0, 0, 0.05}, {0, 0, 0}), diagonal_covariance(0.003, 0.002)));
  EXPECT_EQ(builder.reset_counter(), 1);
}

}  // namespace
}  // namespace rgbdo
