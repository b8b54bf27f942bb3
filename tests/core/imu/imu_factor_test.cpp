// ImuFactor: analytic Jacobians against Ceres' numeric differentiation (with the pose manifold), whitening,
// block packing, and a two-state Ceres problem on noise-free data.
#include <cmath>
#include <cstdio>
#include <vector>

#include <ceres/ceres.h>
#include <ceres/gradient_checker.h>
#include <gtest/gtest.h>

#include "core/imu/imu_factor.hpp"
#include "tests/common/jacobian_check.hpp"
#include "core/util/rng.hpp"

namespace rotolidar {
namespace {

const Eigen::Vector3d kGravity(0.0, 0.0, -9.81);

Eigen::Vector3d RandomVector(RandomStream& rng, double sigma) {
  return {rng.Normal(0.0, sigma), rng.Normal(0.0, sigma), rng.Normal(0.0, sigma)};
}

Eigen::Matrix3d RandomRotation(RandomStream& rng) {
  Eigen::Quaterniond q{rng.Normal(), rng.Normal(), rng.Normal(), rng.Normal()};
  return q.normalized().toRotationMatrix();
}

/// A preintegration of random readings (~0.5 rad/s, ~1 m/s^2 around gravity) at random linearisation biases.
PreintegratedImu RandomPreintegration(RandomStream& rng, int steps) {
  PreintegratedImu pre{RandomVector(rng, 0.01), RandomVector(rng, 0.05), ImuNoise{}};
  for (int k = 0; k < steps; ++k) {
    const Eigen::Vector3d gyro_radps = RandomVector(rng, 0.5);  // drawn in order: argument order is unspecified
    const Eigen::Vector3d accel_mps2 = Eigen::Vector3d(0, 0, 9.81) + RandomVector(rng, 1.0);
    const Status st = pre.Integrate(gyro_radps, accel_mps2, 0.005 * (0.8 + 0.4 * rng.Uniform()));
    EXPECT_TRUE(st.ok) << st.message;
  }
  return pre;
}

/// A random state i near the preintegration's linearisation biases (the draws in this order: R, p, v, bg, ba).
NavState RandomStateI(RandomStream& rng, const PreintegratedImu& pre) {
  NavState i;
  i.R_world_imu = RandomRotation(rng);
  i.p_world_m = RandomVector(rng, 2.0);
  i.v_world_mps = RandomVector(rng, 1.0);
  i.bias_gyro_radps = pre.bias_gyro_radps() + RandomVector(rng, 0.01);
  i.bias_accel_mps2 = pre.bias_accel_mps2() + RandomVector(rng, 0.05);
  return i;
}

using test_util::MaxMixedError;

TEST(ImuFactor, AnalyticJacobiansMatchNumericWithManifold) {
  RandomStream rng(11, "imu_factor_test.jacobians");
  const std::unique_ptr<ceres::Manifold> pose_manifold = MakeImuPoseManifold();
  const std::vector<const ceres::Manifold*> manifolds = {pose_manifold.get(), nullptr, pose_manifold.get(),
                                                         nullptr};
  double worst_local = 0.0, worst_ambient = 0.0;
  for (int trial = 0; trial < 10; ++trial) {
    const PreintegratedImu pre = RandomPreintegration(rng, 20 + 10 * trial);
    const NavState i = RandomStateI(rng, pre);
    NavState j = pre.Predict(i, kGravity);  // then perturb j so that every residual is non-zero
    j.R_world_imu = ExpSO3(RandomVector(rng, 0.05)) * j.R_world_imu;
    j.p_world_m += RandomVector(rng, 0.1);
    j.v_world_mps += RandomVector(rng, 0.1);
    j.bias_gyro_radps += RandomVector(rng, 0.005);
    j.bias_accel_mps2 += RandomVector(rng, 0.02);
    double pose_i[7], sb_i[9], pose_j[7], sb_j[9];
    PackImuState(i, pose_i, sb_i);
    PackImuState(j, pose_j, sb_j);
    const double* parameters[4] = {pose_i, sb_i, pose_j, sb_j};

    const ImuFactor factor(pre, kGravity);
    ceres::GradientChecker checker(&factor, &manifolds, ceres::NumericDiffOptions{});
    ceres::GradientChecker::ProbeResults results;
    checker.Probe(parameters, 1e-5, &results);
    ASSERT_TRUE(results.return_value);
    // Compare the unwhitened Jacobians (S^-1 J): entries O(0.01..10) with exact zeros, so that a wrong entry
    // in a small block cannot hide behind the large whitening scale.
    const Eigen::Matrix<double, 15, 15> S_inv = factor.sqrt_information().inverse();
    EXPECT_GT(factor.UnwhitenedResidual(pose_i, sb_i, pose_j, sb_j).segment<9>(0).cwiseAbs().minCoeff(), 1e-5);
    for (int k = 0; k < 4; ++k) {
      worst_local = std::max(worst_local, MaxMixedError(S_inv * results.local_jacobians[k],
                                                        S_inv * results.local_numeric_jacobians[k]));
      worst_ambient = std::max(worst_ambient, MaxMixedError(S_inv * results.jacobians[k],
                                                            S_inv * results.numeric_jacobians[k]));
    }
  }
  // Measured over 10 random states: 1.4e-8 (tangent) and 3.0e-8 (ambient: the Jacobian is the exact derivative
  // of r(q/|q|)). Any wrong term would be O(1e-2..1).
  EXPECT_LT(worst_local, 1e-6);
  EXPECT_LT(worst_ambient, 1e-6);
}

// The gravity-block variant: the same residual as ImuFactor at the block's g, and every Jacobian (the gravity
// block's on the sphere manifold) against numeric differentiation.
TEST(ImuGravityFactor, MatchesImuFactorAndJacobiansMatchNumeric) {
  RandomStream rng(13, "imu_factor_test.gravity_jacobians");
  const std::unique_ptr<ceres::Manifold> pose_manifold = MakeImuPoseManifold();
  const std::unique_ptr<ceres::Manifold> gravity_manifold = MakeGravityManifold();
  const std::vector<const ceres::Manifold*> manifolds = {pose_manifold.get(), nullptr, pose_manifold.get(),
                                                         nullptr, gravity_manifold.get()};
  double worst_local = 0.0, worst_ambient = 0.0, worst_residual = 0.0;
  int probed = 0;
  // Random states until 10 have been probed (a state with a near-zero quaternion coordinate is skipped, below).
  for (int trial = 0; trial < 40 && probed < 10; ++trial) {
    const PreintegratedImu pre = RandomPreintegration(rng, 20 + 10 * (trial % 12));
    // A gravity tilted by up to ~0.1 rad from kGravity, |g| = 9.81.
    const Eigen::Vector3d g = ExpSO3(RandomVector(rng, 0.05)) * kGravity;
    const NavState i = RandomStateI(rng, pre);
    NavState j = pre.Predict(i, kGravity);  // predicted with the nominal gravity: r_v, r_p see the tilt
    j.R_world_imu = ExpSO3(RandomVector(rng, 0.05)) * j.R_world_imu;
    j.p_world_m += RandomVector(rng, 0.1);
    j.v_world_mps += RandomVector(rng, 0.1);
    j.bias_gyro_radps += RandomVector(rng, 0.005);
    j.bias_accel_mps2 += RandomVector(rng, 0.02);
    double pose_i[7], sb_i[9], pose_j[7], sb_j[9], gravity[3] = {g.x(), g.y(), g.z()};
    PackImuState(i, pose_i, sb_i);
    PackImuState(j, pose_j, sb_j);
    // Ceres' numeric step is relative to each coordinate: a quaternion coordinate near 0 gets a tiny step and
    // round-off dominates (seen: q_w = 0.012 gives 2e-5 on the plain ImuFactor's pose_j block too). Skip those.
    auto tiny = [](const double* pose) {
      return Eigen::Map<const Eigen::Vector4d>(pose + 3).cwiseAbs().minCoeff() < 0.05;
    };
    if (tiny(pose_i) || tiny(pose_j)) continue;
    ++probed;
    const double* parameters[5] = {pose_i, sb_i, pose_j, sb_j, gravity};

    const ImuGravityFactor factor(pre);
    const ImuFactor fixed(pre, g);
    const ImuFactor::Vector15d r_diff = factor.UnwhitenedResidual(pose_i, sb_i, pose_j, sb_j, gravity) -
                                        fixed.UnwhitenedResidual(pose_i, sb_i, pose_j, sb_j);
    worst_residual = std::max(worst_residual, r_diff.cwiseAbs().maxCoeff());
    ceres::GradientChecker checker(&factor, &manifolds, ceres::NumericDiffOptions{});
    ceres::GradientChecker::ProbeResults results;
    checker.Probe(parameters, 1e-5, &results);
    ASSERT_TRUE(results.return_value);
    const Eigen::Matrix<double, 15, 15> S_inv = factor.sqrt_information().inverse();
    for (int k = 0; k < 5; ++k) {
      worst_local = std::max(worst_local, MaxMixedError(S_inv * results.local_jacobians[k],
                                                        S_inv * results.local_numeric_jacobians[k]));
      worst_ambient = std::max(worst_ambient, MaxMixedError(S_inv * results.jacobians[k],
                                                            S_inv * results.numeric_jacobians[k]));
    }
    // The gravity block's tangent Jacobian is not trivially zero (2 columns, O(dt) entries).
    EXPECT_GT((S_inv * results.local_jacobians[4]).cwiseAbs().maxCoeff(), 1e-3);
  }
  std::printf("[measured] gravity factor (%d states): residual vs ImuFactor %.1e, Jacobians tangent %.1e "
              "ambient %.1e\n", probed, worst_residual, worst_local, worst_ambient);
  EXPECT_EQ(probed, 10);
  EXPECT_LT(worst_residual, 1e-12);
  EXPECT_LT(worst_local, 1e-6);
  EXPECT_LT(worst_ambient, 1e-6);
}

TEST(ImuFactor, SqrtInformationWhitensTheCovariance) {
  RandomStream rng(3, "imu_factor_test.whitening");
  const PreintegratedImu pre = RandomPreintegration(rng, 40);
  const ImuFactor factor(pre, kGravity);
  const Eigen::Matrix<double, 15, 15>& S = factor.sqrt_information();
  // S Sigma S^T = I: whitened residuals have unit covariance.
  EXPECT_LT((S * factor.covariance() * S.transpose() - Eigen::Matrix<double, 15, 15>::Identity())
                .cwiseAbs().maxCoeff(), 1e-8);
  EXPECT_LT((factor.covariance().topLeftCorner<9, 9>() - pre.covariance()).cwiseAbs().maxCoeff(), 1e-30);
  const double T = pre.dt_s(), rw = ImuNoise{}.accel_random_walk;
  EXPECT_NEAR(factor.covariance()(14, 14), rw * rw * T, 1e-18);
}

TEST(ImuFactor, PackUnpackRoundTrip) {
  RandomStream rng(5, "imu_factor_test.pack");
  NavState s;
  s.R_world_imu = RandomRotation(rng);
  s.p_world_m = RandomVector(rng, 3.0);
  s.v_world_mps = RandomVector(rng, 1.0);
  s.bias_gyro_radps = RandomVector(rng, 0.01);
  s.bias_accel_mps2 = RandomVector(rng, 0.1);
  double pose[7], sb[9];
  PackImuState(s, pose, sb);
  EXPECT_NEAR(Eigen::Map<const Eigen::Vector4d>(pose + 3).norm(), 1.0, 1e-15);
  const NavState r = UnpackImuState(pose, sb);
  EXPECT_LT((r.R_world_imu - s.R_world_imu).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_EQ(r.p_world_m, s.p_world_m);
  EXPECT_EQ(r.v_world_mps, s.v_world_mps);
  EXPECT_EQ(r.bias_gyro_radps, s.bias_gyro_radps);
  EXPECT_EQ(r.bias_accel_mps2, s.bias_accel_mps2);
  EXPECT_LT((UnpackImuPose(pose).linear() - s.R_world_imu).cwiseAbs().maxCoeff(), 1e-15);
}

/// Noise-free IMU on an analytic motion: R(t) = R0 Exp(w0 t) (body rate w0), p(t) = p0 + v0 t + A sin(f t).
struct Motion {
  Eigen::Matrix3d R0 = ExpSO3(Eigen::Vector3d(0.2, -0.1, 0.7));
  Eigen::Vector3d w0{0.3, -0.6, 0.9}, p0{1.0, -2.0, 0.5}, v0{0.8, 0.3, -0.1}, A{0.4, 0.2, 0.1}, f{1.5, 2.0, 2.5};
  Eigen::Vector3d bg{0.004, -0.003, 0.002}, ba{0.05, -0.04, 0.03};

  NavState State(double t) const {
    NavState s;
    s.R_world_imu = R0 * ExpSO3(w0 * t);
    s.p_world_m = p0 + v0 * t + A.cwiseProduct((f * t).array().sin().matrix());
    s.v_world_mps = v0 + A.cwiseProduct(f).cwiseProduct((f * t).array().cos().matrix());
    s.bias_gyro_radps = bg;
    s.bias_accel_mps2 = ba;
    return s;
  }
  ImuSample Sample(double t) const {
    const Eigen::Vector3d acc = -A.cwiseProduct(f).cwiseProduct(f).cwiseProduct((f * t).array().sin().matrix());
    ImuSample s;
    s.t_s = t;
    s.gyro_radps = w0 + bg;
    s.accel_mps2 = State(t).R_world_imu.transpose() * (acc - kGravity) + ba;
    return s;
  }
};

/// Solves for pose_j and speed-bias_j with pose_i and speed-bias_i held at the truth (one factor has 15
/// residuals: it cannot also determine state i's 9 speed/bias unknowns). Returns the errors of state j.
void SolveTwoStates(const Motion& m, const PreintegratedImu& pre, double* pos_err_m, double* rot_err_rad,
                    double* vel_err_mps) {
  const double T = pre.dt_s();
  NavState init_j = m.State(T);
  init_j.p_world_m += Eigen::Vector3d(0.3, -0.2, 0.25);
  init_j.R_world_imu = ExpSO3(Eigen::Vector3d(0.1, 0.15, -0.2)) * init_j.R_world_imu;
  init_j.v_world_mps += Eigen::Vector3d(-0.4, 0.5, 0.3);
  init_j.bias_gyro_radps.setZero();
  init_j.bias_accel_mps2.setZero();
  double pose_i[7], sb_i[9], pose_j[7], sb_j[9];
  PackImuState(m.State(0.0), pose_i, sb_i);
  PackImuState(init_j, pose_j, sb_j);
  ceres::Problem problem;
  problem.AddResidualBlock(new ImuFactor(pre, kGravity), nullptr, pose_i, sb_i, pose_j, sb_j);
  problem.SetManifold(pose_i, MakeImuPoseManifold().release());
  problem.SetManifold(pose_j, MakeImuPoseManifold().release());
  problem.SetParameterBlockConstant(pose_i);
  problem.SetParameterBlockConstant(sb_i);
  ceres::Solver::Options options;
  options.max_num_iterations = 20;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  EXPECT_EQ(summary.termination_type, ceres::CONVERGENCE) << summary.BriefReport();
  const NavState truth_j = m.State(T), j = UnpackImuState(pose_j, sb_j);
  *pos_err_m = (j.p_world_m - truth_j.p_world_m).norm();
  *rot_err_rad = LogSO3(j.R_world_imu.transpose() * truth_j.R_world_imu).norm();
  *vel_err_mps = (j.v_world_mps - truth_j.v_world_mps).norm();
  EXPECT_LT((j.bias_gyro_radps - m.bg).norm(), 1e-9);
  EXPECT_LT((j.bias_accel_mps2 - m.ba).norm(), 1e-9);
}

TEST(ImuFactor, CeresRecoversStateJFromNoiseFreeImu) {
  const Motion m;
  const double rate_hz = 200.0, T = 0.5;
  PreintegratedImu at_truth(m.bg, m.ba, ImuNoise{});
  PreintegratedImu at_zero(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), ImuNoise{});
  for (int k = 0; k < static_cast<int>(T * rate_hz); ++k) {
    ASSERT_TRUE(at_truth.Integrate(m.Sample(k / rate_hz), m.Sample((k + 1) / rate_hz)).ok);
    ASSERT_TRUE(at_zero.Integrate(m.Sample(k / rate_hz), m.Sample((k + 1) / rate_hz)).ok);
  }
  double pos, rot, vel;
  SolveTwoStates(m, at_truth, &pos, &rot, &vel);
  // Linearised at the true biases the only error is the midpoint discretisation at 200 Hz: measured
  // position 2.9e-6 m, velocity 4.6e-6 m/s, rotation 1.8e-13 rad (a constant body rate integrates exactly).
  // Bounds ~2x (rotation: round-off level).
  EXPECT_LT(pos, 6e-6);
  EXPECT_LT(rot, 1e-10);
  EXPECT_LT(vel, 1e-5);
  // Linearised at zero biases, the factor's first-order bias correction (|bg| 5e-3 rad/s, |ba| 7e-2 m/s^2)
  // adds a second-order remainder: measured position 2.1e-6 m, rotation 2.0e-7 rad, velocity 3.8e-6 m/s.
  SolveTwoStates(m, at_zero, &pos, &rot, &vel);
  EXPECT_LT(pos, 5e-6);
  EXPECT_LT(rot, 5e-7);
  EXPECT_LT(vel, 1e-5);
}

}  // namespace
}  // namespace rotolidar
