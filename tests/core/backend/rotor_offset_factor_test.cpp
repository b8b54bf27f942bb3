// The rotor-angle offset factor: analytic Jacobians against numeric ones, its model of what a scan deskewed with an
// offset encoder does to a registration (zero error at the truth), and the offset recovered from poses that the
// IMU knows.
#include <cmath>

#include <ceres/ceres.h>
#include <gtest/gtest.h>

#include "core/backend/rotor_offset_factor.hpp"
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

TEST(LidarRotorFactor, JacobiansMatchNumeric) {
  RandomStream rng(31, "rotor_offset_factor_test.jacobians");
  double worst = 0.0;
  for (int trial = 0; trial < 10; ++trial) {
    const Pose3 T_base_motor = RandomPose(rng, 0.2), T_base_imu = RandomPose(rng, 0.1);
    LidarPoseMeasurement m;
    m.T_world_imu = RandomPose(rng, 3.0);
    m.information = RandomInformation(rng, 1.0);
    const double phi_applied = rng.Normal(0.0, 0.1);
    const MotorAxisInImu motor = MotorAxisInImu::From(T_base_motor, T_base_imu);
    double pose[7], phi[1] = {rng.Normal(0.0, 0.3)};
    // A pose whose rotation error is ~0.5 rad, far from Log's cut at pi (where no derivative exists).
    const Pose3 explained = m.T_world_imu * motor.B(phi[0] - phi_applied).inverse();
    const Eigen::Vector3d dt = RandomVector(rng, 0.3), dtheta = RandomVector(rng, 0.3);
    PackImuPose(MakePose(explained.translation() + dt, Eigen::Quaterniond(ExpSO3(dtheta) * explained.linear())), pose);
    const LidarRotorFactor factor(m, motor, phi_applied);
    EXPECT_GT(factor.Error(pose, phi[0]).tail<3>().norm(), 1e-3);  // away from the identity
    worst = std::max(worst, test_util::JacobianError(factor, {pose, phi}));
  }
  // Measured over 10 random rigs and poses: ~1e-12 (smooth residuals; Ceres' Ridders differences are exact to
  // round-off). A wrong sign of the phi column gives O(1).
  EXPECT_LT(worst, 1e-8);
}

TEST(LidarRotorFactor, ARegistrationOfAnOffsetScanHasNoErrorAtTheTruth) {
  RandomStream rng(32, "rotor_offset_factor_test.model");
  for (int trial = 0; trial < 5; ++trial) {
    const Pose3 T_base_motor = RandomPose(rng, 0.2), T_base_imu = RandomPose(rng, 0.1);
    const Pose3 T_world_base = RandomPose(rng, 5.0);
    const double phi = rng.Normal(0.0, 0.1), applied = rng.Normal(0.0, 0.05);
    // The scan's points are turned by A(phi - applied); the registration aligns them with the world exactly.
    const Pose3 T_world_base_lidar = T_world_base * ScanTurn(T_base_motor, phi - applied).inverse();
    const Eigen::Vector3d p_base = RandomVector(rng, 10.0);
    EXPECT_LT((T_world_base_lidar * (ScanTurn(T_base_motor, phi - applied) * p_base) - T_world_base * p_base).norm(),
              1e-12);
    const LidarPoseMeasurement m =
        LidarMeasurementInImuFrame(T_world_base_lidar, Matrix6d::Identity(), T_base_imu);
    const LidarRotorFactor factor(m, MotorAxisInImu::From(T_base_motor, T_base_imu), applied);
    double pose[7];
    PackImuPose(T_world_base * T_base_imu, pose);
    EXPECT_LT(factor.Error(pose, phi).norm(), 1e-12);
    EXPECT_GT(factor.Error(pose, applied).tail<3>().norm(), 0.5 * std::abs(phi - applied));  // unexplained
  }
}

TEST(LidarRotorFactor, TheOffsetIsRecoveredFromPosesTheImuKnows) {
  // A horizontal motor axis (the default rig) and a base that yaws: poses known (as the IMU would give them), the
  // scans deskewed with a 0.09 rad offset encoder (36 ms at 2.6 rad/s), of which 0.02 rad were already removed.
  RandomStream rng(33, "rotor_offset_factor_test.solve");
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
    problem.AddResidualBlock(new LidarRotorFactor(m, MotorAxisInImu::From(T_base_motor, T_base_imu), applied),
                             nullptr, poses[k].data(), phi);
    problem.SetParameterBlockConstant(poses[k].data());
  }
  ceres::Solver::Summary summary;
  ceres::Solve(ceres::Solver::Options{}, &problem, &summary);
  // The rotation residuals carry phi noise-free here; the 2 mm translation noise moves it by ~1e-4 rad at most.
  EXPECT_NEAR(phi[0], phi_true, 1e-3) << summary.BriefReport();
}

}  // namespace
}  // namespace rotolidar
