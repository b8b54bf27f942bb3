// Trajectory lookup (bench/eval/trajectory_lookup.hpp) on a motion the interpolation reproduces exactly.
#include <gtest/gtest.h>

#include "bench/eval/trajectory_lookup.hpp"

namespace rotolidar::bench {
namespace {

// Constant velocity and a constant rotation rate about a fixed axis: linear + slerp between 1 kHz samples is exact.
Pose3 LidarAt(double t) {
  return MakePose(Eigen::Vector3d(1.1 + 1.2 * t, -0.5 + 0.3 * t, 1.6 + 0.05 * t),
                  Eigen::Quaterniond(Eigen::AngleAxisd(2.6 * t, Eigen::Vector3d(1, 1, 0).normalized())));
}

/// Samples of LidarAt over [0, 1] s at 1 kHz.
Trajectory SampledLidar() {
  Trajectory trajectory;
  for (int k = 0; k <= 1000; ++k) trajectory.push_back({k * 1e-3, LidarAt(k * 1e-3)});
  return trajectory;
}

TEST(PoseAt, InterpolatesAndRefusesOutsideTheSpan) {
  const Trajectory lidar = SampledLidar();
  Pose3 T;
  ASSERT_TRUE(PoseAt(lidar, 0.4567, &T));
  EXPECT_LT((T.translation() - LidarAt(0.4567).translation()).norm(), 1e-9);
  EXPECT_LT((T.linear() - LidarAt(0.4567).linear()).norm(), 1e-9);
  EXPECT_TRUE(PoseAt(lidar, 0.0, &T));
  EXPECT_TRUE(PoseAt(lidar, 1.0, &T));
  EXPECT_FALSE(PoseAt(lidar, -1e-6, &T));
  EXPECT_FALSE(PoseAt(lidar, 1.0 + 1e-6, &T));
}

TEST(InterpolateTrajectory, KeepsTheStampsInsideTheSpanOnly) {
  const Trajectory lidar = SampledLidar();
  const Trajectory at = {{-0.1, Pose3::Identity()}, {0.0, Pose3::Identity()}, {0.4567, Pose3::Identity()},
                         {1.0, Pose3::Identity()}, {1.2, Pose3::Identity()}};
  const Trajectory out = InterpolateTrajectory(lidar, at);
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out[0].t_s, 0.0);
  EXPECT_EQ(out[1].t_s, 0.4567);
  EXPECT_EQ(out[2].t_s, 1.0);
  for (const StampedPose& p : out) {
    EXPECT_LT((p.T_ref_body.translation() - LidarAt(p.t_s).translation()).norm(), 1e-9);
    EXPECT_LT((p.T_ref_body.linear() - LidarAt(p.t_s).linear()).norm(), 1e-9);
  }
  EXPECT_TRUE(InterpolateTrajectory(Trajectory{lidar.front()}, at).empty());
}

}  // namespace
}  // namespace rotolidar::bench
