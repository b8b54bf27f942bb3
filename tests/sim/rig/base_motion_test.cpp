#include "sim/rig/base_motion.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace rotolidar::sim {
namespace {

// Times spread over two laps, off any symmetric grid.
std::vector<double> TestTimes() {
  std::vector<double> ts;
  for (double t = 0.013; t < 40.0; t += 0.377) ts.push_back(t);
  return ts;
}

TEST(ScriptedBaseMotionConfig, DefaultsValidateAndFitTheRoom) {
  ScriptedBaseMotionConfig c;
  std::string error;
  EXPECT_TRUE(c.Validate(&error)) << error;
  // Walking speed: the closed-form bounds of the default loop lie inside 0.4..1.2 m/s.
  EXPECT_GT(c.MinSpeedBound(), 0.4);
  EXPECT_LT(c.MaxSpeedBound(), 1.2);
}

TEST(ScriptedBaseMotionConfig, RejectsBadFieldsWithTheirNames) {
  std::string error;
  ScriptedBaseMotionConfig c;
  c.radius_x_m = -1.0;
  EXPECT_FALSE(c.Validate(&error));
  EXPECT_NE(error.find("radius_x_m"), std::string::npos) << error;

  c = {};
  c.center_x_m = 2.0;  // 2 + 3 + 0.25 + 0.5 > 5
  EXPECT_FALSE(c.Validate(&error));
  EXPECT_NE(error.find("room"), std::string::npos) << error;

  c = {};
  c.loop_period_s = 200.0;  // too slow
  EXPECT_FALSE(c.Validate(&error));
  EXPECT_NE(error.find("min_speed_mps"), std::string::npos) << error;

  c = {};
  c.shape_harmonic_m = 0.8;  // 3d > min radius: the path would stop and cusp
  EXPECT_FALSE(c.Validate(&error));

  c = {};
  c.height_m = std::nan("");
  EXPECT_FALSE(c.Validate(&error));
  EXPECT_NE(error.find("finite"), std::string::npos) << error;
}

TEST(ScriptedBaseMotion, StaysInRoomAtWalkingSpeedAndIsPeriodic) {
  const ScriptedBaseMotionConfig c;
  const ScriptedBaseMotion motion(c);
  for (double t = 0.0; t < c.loop_period_s; t += 0.01) {
    const BaseKinematics k = motion.At(t);
    const Eigen::Vector3d p = k.T_world_base.translation();
    EXPECT_GT(p.x(), c.room_min_x_m + c.margin_m);
    EXPECT_LT(p.x(), c.room_max_x_m - c.margin_m);
    EXPECT_GT(p.y(), c.room_min_y_m + c.margin_m);
    EXPECT_LT(p.y(), c.room_max_y_m - c.margin_m);
    EXPECT_NEAR(p.z(), c.height_m, c.bounce_amplitude_m + 1e-12);
    const double speed = k.v_world_mps.head<2>().norm();
    EXPECT_GE(speed, c.MinSpeedBound() - 1e-12);
    EXPECT_LE(speed, c.MaxSpeedBound() + 1e-12);
    // Yaw follows the heading: the base x axis is along the horizontal velocity (up to the small pitch/roll).
    const Eigen::Vector3d x_axis = k.T_world_base.linear().col(0);
    EXPECT_GT(x_axis.head<2>().normalized().dot(k.v_world_mps.head<2>() / speed), 1.0 - 1e-12);
  }
  // Bounce (2 Hz), roll (1 Hz) and pitch (2 Hz) have whole periods in one 20 s lap.
  const Pose3 a = motion.At(3.21).T_world_base, b = motion.At(3.21 + c.loop_period_s).T_world_base;
  EXPECT_LT((a.translation() - b.translation()).norm(), 1e-12);
  EXPECT_LT(LogSO3(a.linear().transpose() * b.linear()).norm(), 1e-12);
}

// Central differences with step h have truncation error h^2/6 * |third derivative|. The largest derivatives
// come from the 2 Hz, 2 cm bounce ((4 pi)^3 * 0.02 = 40 m/s^3, (4 pi)^4 * 0.02 = 500 m/s^4) and the 2 Hz
// pitch nod. With h = 1e-4 s: position -> v error <= 1e-8 * 40 / 6 ~ 7e-8, v -> a <= 1e-8 * 500 / 6 ~ 1e-6;
// round-off ~ 1e-16 * 3 m / 1e-4 s = 3e-12. Measured maxima are printed; bounds are ~10x the estimates.
TEST(ScriptedBaseMotion, AnalyticDerivativesMatchNumericDifferentiation) {
  const ScriptedBaseMotion motion{ScriptedBaseMotionConfig{}};
  const double h = 1e-4;
  double max_v = 0, max_a = 0, max_w = 0, max_alpha = 0;
  for (double t : TestTimes()) {
    const BaseKinematics k = motion.At(t), km = motion.At(t - h), kp = motion.At(t + h);
    const Eigen::Vector3d v_num = (kp.T_world_base.translation() - km.T_world_base.translation()) / (2 * h);
    const Eigen::Vector3d a_num = (kp.v_world_mps - km.v_world_mps) / (2 * h);
    // omega in the base frame: R(t+h) = R(t-h) Exp(omega * 2h) + O(h^3).
    const Eigen::Vector3d w_num =
        LogSO3(km.T_world_base.linear().transpose() * kp.T_world_base.linear()) / (2 * h);
    const Eigen::Vector3d alpha_num = (kp.omega_base_radps - km.omega_base_radps) / (2 * h);
    max_v = std::max(max_v, (v_num - k.v_world_mps).norm());
    max_a = std::max(max_a, (a_num - k.a_world_mps2).norm());
    max_w = std::max(max_w, (w_num - k.omega_base_radps).norm());
    max_alpha = std::max(max_alpha, (alpha_num - k.alpha_base_radps2).norm());
  }
  std::printf("max |v - v_num| %.3g, |a - a_num| %.3g, |w - w_num| %.3g, |alpha - alpha_num| %.3g\n", max_v,
              max_a, max_w, max_alpha);
  EXPECT_LT(max_v, 1e-6);
  EXPECT_LT(max_a, 1e-5);
  EXPECT_LT(max_w, 1e-6);
  EXPECT_LT(max_alpha, 1e-5);
}

TEST(ScriptedBaseMotion, SampleTrajectoryIncludesBothEnds) {
  const ScriptedBaseMotion motion{ScriptedBaseMotionConfig{}};
  const Trajectory traj = SampleTrajectory(motion, 1.0, 2.0, 0.1);
  ASSERT_EQ(traj.size(), 11u);
  EXPECT_DOUBLE_EQ(traj.front().t_s, 1.0);
  EXPECT_NEAR(traj.back().t_s, 2.0, 1e-12);
  EXPECT_TRUE(traj[3].T_ref_body.isApprox(motion.At(traj[3].t_s).T_world_base));
  EXPECT_DOUBLE_EQ(motion.Duration(), ScriptedBaseMotionConfig{}.duration_s);
}

}  // namespace
}  // namespace rotolidar::sim
