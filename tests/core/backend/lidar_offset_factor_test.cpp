// The LiDAR offset factor: analytic Jacobians against numeric ones (rotor offset, IMU time offset, both), its model
// of what a scan deskewed with an offset encoder does to a registration (zero error at the truth), of a state that
// the IMU's late stamps put behind the LiDAR, and the offsets recovered from poses that the IMU knows.
#include <array>
#include <cmath>
#include <vector>

#include <ceres/ceres.h>
#include <gtest/gtest.h>

#include "core/backend/lidar_offset_factor.hpp"
#include "core/util/rng.hpp"
#include "tests/common/jacobian_check.hpp"

namespace rotolidar {
namespace {

Eigen::Vector3d RandomVector(RandomStream& rng, double sigma) {
  return {rng.Normal(0.0, sigma), rng.Normal(0.0, sigma), rng.Normal(0.0, sigma)};
}

Pose3 RandomPose(RandomStream& rng, double sigma_t_m) {
  const Eigen::Vector3d t = RandomVector(rng, sigma_t_m);  // drawn first: argument order is the compiler's choice
  return MakePose(t, Eigen::Quaterniond{rng.Normal(), rng.Normal(), rng.Normal(), rng.Normal()});
}

Matrix6d RandomInformation(RandomStream& rng, double scale) {
  Eigen::Matrix<double, 6, 6> M;
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) M(r, c) = rng.Normal();
  return scale * (M * M.transpose() + 0.1 * Matrix6d::Identity());
}

/// A(phi) = T_base_motor RotZ(phi) T_base_motor^-1: what an encoder angle off by phi does to a deskewed scan.
Pose3 ScanTurn(const Pose3& T_base_motor, double phi_rad) {
  Pose3 Rz = Pose3::Identity();
  Rz.linear() = Eigen::AngleAxisd(phi_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return T_base_motor * Rz * T_base_motor.inverse();
}

/// The worst Jacobian error of LidarOffsetFactor over 10 random rigs, measurements and states.
double WorstJacobianError(LidarOffsets which, uint64_t seed) {
  RandomStream rng(seed, "lidar_offset_factor_test.jacobians");
  double worst = 0.0;
  for (int trial = 0; trial < 10; ++trial) {
    const Pose3 T_base_motor = RandomPose(rng, 0.2), T_base_imu = RandomPose(rng, 0.1);
    LidarPoseMeasurement m;
    m.T_world_imu = RandomPose(rng, 3.0);
    m.information = RandomInformation(rng, 1.0);
    m.rotor_offset_applied_rad = rng.Normal(0.0, 0.1);
    m.time_offset_applied_s = rng.Normal(0.0, 0.02);
    m.angular_velocity_imu_radps = RandomVector(rng, 1.0);
    const MotorAxisInImu motor = MotorAxisInImu::From(T_base_motor, T_base_imu);
    double pose[7], speed_bias[9], phi[1] = {rng.Normal(0.0, 0.3)}, td[1] = {rng.Normal(0.0, 0.05)};
    for (double& x : speed_bias) x = rng.Normal(0.0, 1.0);
    // A pose whose rotation error is ~0.5 rad, far from Log's cut at pi (where no derivative exists).
    const Pose3 explained = m.T_world_imu * motor.B(phi[0] - m.rotor_offset_applied_rad).inverse();
    const Eigen::Vector3d dt = RandomVector(rng, 0.3), dtheta = RandomVector(rng, 0.3);
    PackImuPose(MakePose(explained.translation() + dt, Eigen::Quaterniond(ExpSO3(dtheta) * explained.linear())), pose);
    const LidarOffsetFactor factor(m, motor, which);
    std::vector<double*> blocks = {pose};
    if (which.time) blocks.push_back(speed_bias);
    if (which.rotor) blocks.push_back(phi);
    if (which.time) blocks.push_back(td);
    EXPECT_GT(factor.Error(blocks.data()).tail<3>().norm(), 1e-3);  // away from the identity
    worst = std::max(worst, test_util::JacobianError(factor, blocks));
  }
  return worst;
}

TEST(LidarOffsetFactor, JacobiansMatchNumeric) {
  // Measured over 10 random rigs and states each: ~1e-12 (smooth residuals; Ceres' Ridders differences are exact
  // to round-off). Leaving v out of the td column gives ~2.
  EXPECT_LT(WorstJacobianError({true, false}, 31), 1e-8);
  EXPECT_LT(WorstJacobianError({false, true}, 34), 1e-8);
  EXPECT_LT(WorstJacobianError({true, true}, 35), 1e-8);
}

TEST(LidarOffsetFactor, ARegistrationOfAnOffsetScanHasNoErrorAtTheTruth) {
  RandomStream rng(32, "lidar_offset_factor_test.model");
  for (int trial = 0; trial < 5; ++trial) {
    const Pose3 T_base_motor = RandomPose(rng, 0.2), T_base_imu = RandomPose(rng, 0.1);
    const Pose3 T_world_base = RandomPose(rng, 5.0);
    const double phi = rng.Normal(0.0, 0.1), applied = rng.Normal(0.0, 0.05);
    // The scan's points are turned by A(phi - applied); the registration aligns them with the world exactly.
    const Pose3 T_world_base_lidar = T_world_base * ScanTurn(T_base_motor, phi - applied).inverse();
    const Eigen::Vector3d p_base = RandomVector(rng, 10.0);
    EXPECT_LT((T_world_base_lidar * (ScanTurn(T_base_motor, phi - applied) * p_base) - T_world_base * p_base).norm(),
              1e-12);
    LidarPoseMeasurement m =
        LidarMeasurementInImuFrame(T_world_base_lidar, Matrix6d::Identity(), T_base_imu);
    m.rotor_offset_applied_rad = applied;
    const LidarOffsetFactor factor(m, MotorAxisInImu::From(T_base_motor, T_base_imu), {true, false});
    double pose[7], phi_block[1] = {phi}, applied_block[1] = {applied};
    PackImuPose(T_world_base * T_base_imu, pose);
    const double* at_truth[] = {pose, phi_block};
    const double* at_applied[] = {pose, applied_block};
    EXPECT_LT(factor.Error(at_truth).norm(), 1e-12);
    EXPECT_GT(factor.Error(at_applied).tail<3>().norm(), 0.5 * std::abs(phi - applied));  // unexplained
  }
}

TEST(LidarOffsetFactor, TheRotorOffsetIsRecoveredFromPosesTheImuKnows) {
  // A horizontal motor axis (the default rig) and a base that yaws: poses known (as the IMU would give them), the
  // scans deskewed with a 0.09 rad offset encoder (36 ms at 2.6 rad/s), of which 0.02 rad were already removed.
  RandomStream rng(33, "lidar_offset_factor_test.solve");
  const Pose3 T_base_motor =
      MakePose({0.05, 0.0, 0.1}, Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY())));
  const Pose3 T_base_imu = MakePose({0.0, 0.02, -0.05}, Eigen::Quaterniond::Identity());
  const double phi_true = 0.09, applied = 0.02;
  ceres::Problem::Options options;
  options.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(options);
  std::vector<std::array<double, 7>> poses(8);
  double phi[1] = {0.0};
  for (size_t k = 0; k < poses.size(); ++k) {
    const Pose3 T_world_base =
        MakePose({0.5 * k, 0.1 * k, 0.0}, Eigen::Quaterniond(Eigen::AngleAxisd(0.4 * k, Eigen::Vector3d::UnitZ())));
    LidarPoseMeasurement m = LidarMeasurementInImuFrame(
        T_world_base * ScanTurn(T_base_motor, phi_true - applied).inverse(), Matrix6d::Identity() * 1e4, T_base_imu);
    m.T_world_imu.translation() += RandomVector(rng, 0.002);  // registration noise
    PackImuPose(T_world_base * T_base_imu, poses[k].data());
    m.rotor_offset_applied_rad = applied;
    problem.AddResidualBlock(new LidarOffsetFactor(m, MotorAxisInImu::From(T_base_motor, T_base_imu), {true, false}),
                             nullptr, poses[k].data(), phi);
    problem.SetParameterBlockConstant(poses[k].data());
  }
  ceres::Solver::Summary summary;
  ceres::Solve(ceres::Solver::Options{}, &problem, &summary);
  // The rotation residuals carry phi noise-free here; the 2 mm translation noise moves it by ~1e-4 rad at most.
  EXPECT_NEAR(phi[0], phi_true, 1e-3) << summary.BriefReport();
}

/// A rig turning at a constant body rate w and moving at a constant world velocity: T_world_imu(t), exact.
Pose3 ConstantTwist(const Pose3& T0, const Eigen::Vector3d& w_imu, const Eigen::Vector3d& v_world, double t) {
  return MakePose(T0.translation() + v_world * t, Eigen::Quaterniond(T0.linear() * ExpSO3(w_imu * t)));
}

TEST(LidarOffsetFactor, AStateBehindTheLidarByTauIsExplainedByTheTimeOffset) {
  RandomStream rng(36, "lidar_offset_factor_test.time_model");
  for (int trial = 0; trial < 5; ++trial) {
    const Pose3 T0 = RandomPose(rng, 5.0);
    const Eigen::Vector3d w = RandomVector(rng, 1.0), v = RandomVector(rng, 1.5);
    const double td = rng.Normal(0.0, 0.03), applied = rng.Normal(0.0, 0.01), t = 1.0 + rng.Uniform();
    // IMU stamps are rig time + td, shifted back by `applied`: the state at rig time t is the pose at t - tau.
    const double tau = td - applied;
    LidarPoseMeasurement m;
    m.T_world_imu = ConstantTwist(T0, w, v, t);
    m.time_offset_applied_s = applied;
    m.angular_velocity_imu_radps = w;
    const LidarOffsetFactor factor(m, MotorAxisInImu{}, {false, true});
    double pose[7], speed_bias[9] = {v.x(), v.y(), v.z(), 0, 0, 0, 0, 0, 0}, at_td[1] = {td}, at_applied[1] = {applied};
    PackImuPose(ConstantTwist(T0, w, v, t - tau), pose);
    const double* truth[] = {pose, speed_bias, at_td};
    const double* ignored[] = {pose, speed_bias, at_applied};
    EXPECT_LT(factor.Error(truth).norm(), 1e-12);
    EXPECT_GT(factor.Error(ignored).head<3>().norm(), 0.5 * v.norm() * std::abs(tau));  // unexplained
  }
}

TEST(LidarOffsetFactor, BothOffsetsAreRecoveredFromStatesTheImuKnows) {
  // A horizontal motor axis (the default rig) on a base that turns at a varying rate and walks: states known (as
  // the IMU would give them, 25 ms behind the LiDAR), scans deskewed with a 0.09 rad offset encoder.
  RandomStream rng(37, "lidar_offset_factor_test.solve_both");
  const Pose3 T_base_motor =
      MakePose({0.05, 0.0, 0.1}, Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY())));
  const Pose3 T_base_imu = MakePose({0.0, 0.02, -0.05}, Eigen::Quaterniond::Identity());
  const MotorAxisInImu motor = MotorAxisInImu::From(T_base_motor, T_base_imu);
  const double phi_true = 0.09, td_true = 0.025;
  ceres::Problem::Options options;
  options.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(options);
  std::vector<std::array<double, 7>> poses(12);
  std::vector<std::array<double, 9>> speed_biases(poses.size());
  double phi[1] = {0.0}, td[1] = {0.0};
  for (size_t k = 0; k < poses.size(); ++k) {
    // Each stretch turns at its own rate: the rotation seen through tau differs from the rotor's turn B.
    const Eigen::Vector3d w(0.3 * std::sin(1.0 * k), 0.2 * std::cos(0.7 * k), 0.8 * std::sin(0.5 * k + 1.0));
    const Eigen::Vector3d v(1.2 * std::cos(0.3 * k), 0.8 * std::sin(0.4 * k), 0.1);
    const Pose3 T0 = MakePose({0.5 * k, 0.1 * k, 0.0}, Eigen::Quaterniond(ExpSO3(Eigen::Vector3d(0.1, -0.2, 0.4 * k))));
    LidarPoseMeasurement m;
    m.T_world_imu = T0 * motor.B(phi_true);  // the LiDAR's view at rig time 0: the scan turned by phi
    m.T_world_imu.translation() += RandomVector(rng, 0.001);  // registration noise
    m.information = Matrix6d::Identity() * 1e4;
    m.angular_velocity_imu_radps = w;
    PackImuPose(ConstantTwist(T0, w, v, -td_true), poses[k].data());
    speed_biases[k] = {v.x(), v.y(), v.z(), 0, 0, 0, 0, 0, 0};
    problem.AddResidualBlock(new LidarOffsetFactor(m, motor, {true, true}), nullptr, poses[k].data(),
                             speed_biases[k].data(), phi, td);
    problem.SetParameterBlockConstant(poses[k].data());
    problem.SetParameterBlockConstant(speed_biases[k].data());
  }
  ceres::Solver::Summary summary;
  ceres::Solve(ceres::Solver::Options{}, &problem, &summary);
  // Noise-free rotations determine both (the turn about the motor axis and the per-stretch rate differ); the 1 mm
  // translation noise moves td by ~1 mm / 1.2 m/s / sqrt(12) ~ 0.3 ms at most.
  EXPECT_NEAR(phi[0], phi_true, 1e-3) << summary.BriefReport();
  EXPECT_NEAR(td[0], td_true, 1e-3) << summary.BriefReport();
}

}  // namespace
}  // namespace rotolidar
