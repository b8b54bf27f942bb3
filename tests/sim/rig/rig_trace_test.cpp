// RigTrace: the sliding window of true rig states that the caster and the truth writer interpolate.
#include "sim/rig/rig_trace.hpp"

#include <cmath>

#include <gtest/gtest.h>

namespace rotolidar::sim {
namespace {

RigTraceSample MakeSample(double t) {
  RigTraceSample s;
  s.t_s = t;
  s.T_world_base = MakePose(Eigen::Vector3d(t, 2 * t, 0.5), Eigen::Quaterniond(Eigen::AngleAxisd(t, Eigen::Vector3d::UnitZ())));
  s.theta_rad = 3.0 * t;
  return s;
}

TEST(RigTrace, InterpolatesLinearMotionExactly) {
  RigTrace trace;
  for (int i = 0; i <= 10; ++i) trace.Append(MakeSample(0.002 * i));
  ASSERT_TRUE(trace.Covers(0.0, 0.02));
  EXPECT_FALSE(trace.Covers(0.0, 0.0201));
  // Translation, yaw about one fixed axis and the rotor angle are linear in t: interpolation is exact.
  const RigTraceSample s = trace.At(0.0073);
  const RigTraceSample truth = MakeSample(0.0073);
  EXPECT_NEAR((s.T_world_base.translation() - truth.T_world_base.translation()).norm(), 0.0, 1e-12);
  EXPECT_NEAR(Eigen::AngleAxisd(s.T_world_base.linear().transpose() * truth.T_world_base.linear()).angle(), 0.0, 1e-9);
  EXPECT_NEAR(s.theta_rad, 3.0 * 0.0073, 1e-12);
  EXPECT_DOUBLE_EQ(trace.At(0.02).theta_rad, 0.06);  // the last sample itself
}

TEST(RigTrace, DropBeforeKeepsTheBracketingSample) {
  RigTrace trace;
  for (int i = 0; i <= 10; ++i) trace.Append(MakeSample(0.002 * i));
  trace.DropBefore(0.0071);
  EXPECT_DOUBLE_EQ(trace.t_front_s(), 0.006);  // still brackets 0.0071 from below
  EXPECT_TRUE(trace.Covers(0.0071, 0.02));
  EXPECT_FALSE(trace.Covers(0.005, 0.02));
  EXPECT_NEAR(trace.At(0.0071).theta_rad, 3.0 * 0.0071, 1e-12);
}

}  // namespace
}  // namespace rotolidar::sim
