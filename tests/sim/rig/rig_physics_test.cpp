// RigState: the MuJoCo physics of the rig (weld-to-mocap carrier, hinge, IMU sensors).
#include <gtest/gtest.h>

#include <complex>
#include <cstdio>

#include "sim/rig/rig_physics.hpp"

namespace rotolidar::sim {
namespace {

// A test drive: PD on the hinge towards theta_ref(t) = theta0 + omega t (a stiff stepper-like servo:
// 20 N m/rad ~ a NEMA-17's 0.4 N m holding torque x 50 pole pairs; damping near critical for ~1.1e-3 kg m^2).
class PdDrive final : public RotorDrive {
 public:
  PdDrive(double theta0_rad, double omega_radps, double kp = 20.0, double kd = 0.25)
      : theta0_(theta0_rad), omega_(omega_radps), kp_(kp), kd_(kd) {}
  double Torque(const RotorJointState& s, double /*dt_s*/) override {
    return kp_ * (theta0_ + omega_ * s.t_s - s.theta_rad) + kd_ * (omega_ - s.omega_radps);
  }
  double Reference(Seconds t) const { return theta0_ + omega_ * t; }

 private:
  double theta0_, omega_, kp_, kd_;
};

class ConstantTorque final : public RotorDrive {
 public:
  explicit ConstantTorque(double torque_nm) : torque_nm_(torque_nm) {}
  double Torque(const RotorJointState&, double) override { return torque_nm_; }

 private:
  double torque_nm_;
};

std::unique_ptr<RigModel> MakeModel(const RigModelConfig& config = RigModelConfig()) {
  std::unique_ptr<RigModel> model;
  const Status status = RigModel::Create(config, &model);
  EXPECT_TRUE(status.ok) << status.message;
  return model;
}

double RotationAngle(const Pose3& a, const Pose3& b) { return LogSO3(a.linear().transpose() * b.linear()).norm(); }

const Pose3 kTilted = MakePose({0.3, -0.2, 1.1}, Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()) *
                                                                   Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitX())));

TEST(RigPhysics, StaticRigAccelerometerReadsGravityUpGyroZero) {
  const auto model = MakeModel();
  RigState state(*model);
  state.Reset(kTilted, 0.3, 0.0);
  PdDrive hold(0.3, 0.0);
  const Eigen::Matrix3d R_world_imu = kTilted.linear() * model->geometry().T_base_imu.linear();
  const Eigen::Vector3d expected = R_world_imu.transpose() * Eigen::Vector3d(0, 0, kGravity_mps2);
  double max_accel_err = 0, max_gyro = 0, max_pos_err = 0;
  for (int k = 0; k < 1000; ++k) {
    ASSERT_TRUE(state.Step(kTilted, &hold).ok);
    const ImuTruth imu = state.imu();
    max_accel_err = std::max(max_accel_err, (imu.specific_force_imu_mps2 - expected).norm());
    max_gyro = std::max(max_gyro, imu.angular_rate_imu_radps.norm());
    max_pos_err = std::max(max_pos_err, (state.T_world_base().translation() - kTilted.translation()).norm());
  }
  std::printf("static: max |f - R g| = %.3g m/s^2, max |gyro| = %.3g rad/s, max |dp| = %.3g m\n", max_accel_err,
              max_gyro, max_pos_err);
  EXPECT_LT(max_accel_err, 1e-6);
  EXPECT_LT(max_gyro, 1e-6);
  EXPECT_LT(max_pos_err, 1e-6);
}

TEST(RigPhysics, ConstantSpeedHingeFollowsAndBaseBarelyTurns) {
  const auto model = MakeModel();
  RigState state(*model);
  state.Reset(kTilted, 0.0, 0.0);
  PdDrive drive(0.0, 2.6);
  double max_hinge_err = 0, max_base_rot = 0, max_speed_err = 0;
  for (int k = 0; k < 3000; ++k) {
    ASSERT_TRUE(state.Step(kTilted, &drive).ok);
    max_base_rot = std::max(max_base_rot, RotationAngle(state.T_world_base(), kTilted));
    if (state.time_s() < 1.0) continue;  // spin-up transient
    max_hinge_err = std::max(max_hinge_err, std::abs(state.rotor_angle_rad() - drive.Reference(state.time_s())));
    max_speed_err = std::max(max_speed_err, std::abs(state.rotor_speed_radps() - 2.6));
  }
  std::printf("hinge: max |theta - ref| = %.3g rad, max |omega - 2.6| = %.3g, base rotation max %.3g rad\n",
              max_hinge_err, max_speed_err, max_base_rot);
  EXPECT_GT(state.rotor_angle_rad(), 2.6 * 2.9);  // unwrapped: more than one revolution
  EXPECT_LT(max_hinge_err, 1e-3);
  EXPECT_LT(max_base_rot, 1e-3);
}

TEST(RigPhysics, BaseTracksMovingTargetAndAccelerometerMatchesTrajectory) {
  const auto model = MakeModel();
  RigState state(*model);
  const double amp_m = 0.5, f_hz = 0.5, w = 2 * M_PI * f_hz;
  auto target = [&](Seconds t) {
    Pose3 T = kTilted;
    T.translation() += Eigen::Vector3d(amp_m * std::sin(w * t), 0.5 * amp_m * std::sin(2 * w * t), 0.0);
    T.linear() = Eigen::AngleAxisd(0.3 * std::sin(w * t), Eigen::Vector3d::UnitZ()).toRotationMatrix() *
                 kTilted.linear();
    return T;
  };
  BaseKinematics k0;
  k0.T_world_base = target(0.0);
  k0.v_world_mps = Eigen::Vector3d(amp_m * w, amp_m * w, 0.0);
  k0.omega_base_radps = k0.T_world_base.linear().transpose() * Eigen::Vector3d(0, 0, 0.3 * w);
  state.Reset(k0, 0.0, 0.0);
  PdDrive drive(0.0, 2.6);
  const Pose3 T_base_imu = model->geometry().T_base_imu;
  std::vector<Pose3> poses{state.T_world_base()};
  std::vector<ImuTruth> imu;
  double max_pos_err = 0, max_rot_err = 0;
  const int n = 4000;
  for (int k = 0; k < n; ++k) {
    ASSERT_TRUE(state.Step(target(state.time_s()), &drive).ok);
    poses.push_back(state.T_world_base());
    imu.push_back(state.imu());
    max_pos_err = std::max(max_pos_err, (state.T_world_base().translation() - target(state.time_s()).translation()).norm());
    max_rot_err = std::max(max_rot_err, RotationAngle(state.T_world_base(), target(state.time_s())));
  }
  // imu[k] describes step k's start, poses[k]; second difference of the imu site's actual positions around it.
  const double dt = state.timestep_s();
  double max_accel_err = 0;
  for (int k = 1; k + 1 < n; ++k) {
    auto p = [&](int i) { return (poses[i] * T_base_imu).translation(); };
    const Eigen::Vector3d a_world = (p(k + 1) - 2 * p(k) + p(k - 1)) / (dt * dt);
    const Eigen::Matrix3d R_world_imu = poses[k].linear() * T_base_imu.linear();
    const Eigen::Vector3d f = R_world_imu.transpose() * (a_world - GravityWorld());
    max_accel_err = std::max(max_accel_err, (imu[k].specific_force_imu_mps2 - f).norm());
  }
  std::printf("tracking: max |dp| = %.3g m, max rot = %.3g rad, accel vs 2nd difference max %.3g m/s^2\n",
              max_pos_err, max_rot_err, max_accel_err);
  EXPECT_LT(max_pos_err, 1e-3);
  EXPECT_LT(max_rot_err, 1e-3);
  EXPECT_LT(max_accel_err, 0.05);
}

// Amplitude [m/s^2] of the accelerometer's component at `f_hz` (single-bin DFT, vector norm over the 3 axes).
double VibrationAt(const std::vector<Eigen::Vector3d>& f, double dt, double f_hz) {
  Eigen::Vector3cd sum = Eigen::Vector3cd::Zero();
  for (size_t k = 0; k < f.size(); ++k) sum += f[k].cast<std::complex<double>>() * std::polar(1.0, -2 * M_PI * f_hz * k * dt);
  return 2.0 * sum.norm() / static_cast<double>(f.size());
}

TEST(RigPhysics, ImbalanceShakesThePlatformOncePerRevolution) {
  const double omega = 20.0, f_rot = omega / (2 * M_PI);
  double amplitude[2] = {0, 0};
  for (int big = 0; big < 2; ++big) {
    RigModelConfig config;
    config.rotor.imbalance_kgm = big ? 5e-3 : 0.0;
    const auto model = MakeModel(config);
    RigState state(*model);
    state.Reset(Pose3::Identity(), 0.0, omega);
    PdDrive drive(0.0, omega);
    std::vector<Eigen::Vector3d> f;
    const int revolutions = 10;
    const int settle = 1000, n = static_cast<int>(std::round(revolutions / f_rot / state.timestep_s()));
    for (int k = 0; k < settle + n; ++k) {
      ASSERT_TRUE(state.Step(Pose3::Identity(), &drive).ok);
      if (k >= settle) f.push_back(state.imu().specific_force_imu_mps2);
    }
    amplitude[big] = VibrationAt(f, state.timestep_s(), f_rot);
  }
  std::printf("imbalance: vibration at %.3f Hz: %.3g (none) vs %.3g m/s^2 (5e-3 kg m)\n", f_rot, amplitude[0],
              amplitude[1]);
  EXPECT_GT(amplitude[1], 100 * amplitude[0]);
}

TEST(RigPhysics, SameInputsGiveIdenticalStateBytes) {
  const auto model = MakeModel();
  RigState a(*model), b(*model);
  for (RigState* s : {&a, &b}) {
    s->Reset(kTilted, 0.1, 0.0);
    PdDrive drive(0.1, 2.6);
    for (int k = 0; k < 500; ++k) {
      Pose3 T = kTilted;
      T.translation().x() += 0.3 * std::sin(3.0 * s->time_s());
      ASSERT_TRUE(s->Step(T, &drive).ok);
    }
  }
  EXPECT_EQ(a.StateBytes(), b.StateBytes());
  PdDrive other(0.1, 2.7);
  ASSERT_TRUE(b.Step(kTilted, &other).ok);
  ASSERT_TRUE(a.Step(kTilted, nullptr).ok);
  EXPECT_NE(a.StateBytes(), b.StateBytes());
}

TEST(RigPhysics, BadTorqueAndInstabilityBecomeErrorsUntilReset) {
  const auto model = MakeModel();
  RigState state(*model);
  ConstantTorque nan_torque(std::nan(""));
  Status status = state.Step(Pose3::Identity(), &nan_torque);
  EXPECT_FALSE(status.ok);
  EXPECT_NE(status.message.find("step 0"), std::string::npos) << status.message;
  EXPECT_FALSE(state.Step(Pose3::Identity(), nullptr).ok);  // invalid until Reset
  state.Reset(Pose3::Identity(), 0.0, 0.0);
  EXPECT_TRUE(state.Step(Pose3::Identity(), nullptr).ok);
  ConstantTorque huge(1e30);
  status = state.Step(Pose3::Identity(), &huge);
  EXPECT_FALSE(status.ok);
  EXPECT_NE(status.message.find("MuJoCo warning"), std::string::npos) << status.message;
}

}  // namespace
}  // namespace rotolidar::sim
