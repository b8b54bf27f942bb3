// The KITTI devkit's segment errors against closed forms: a 1 % scale drift and a 1 deg / 100 m heading drift on a
// straight 1 km drive, sampled like KITTI (1 m steps at 10 Hz).
#include <cmath>

#include <gtest/gtest.h>

#include "bench/eval/kitti_odometry_error.hpp"

namespace rotolidar::bench {
namespace {

constexpr size_t kPoses = 1001;  // 0 .. 1000 m, one pose per metre

/// Pose k at x = k m, t = 0.1 k s, with heading k * yaw_per_pose_rad and position scaled by `scale`.
Trajectory StraightDrive(double scale, double yaw_per_pose_rad) {
  Trajectory t(kPoses);
  for (size_t k = 0; k < kPoses; ++k) {
    t[k].t_s = 0.1 * double(k);
    t[k].T_ref_body = Pose3::Identity();
    t[k].T_ref_body.translation() = Eigen::Vector3d(scale * double(k), 0.0, 0.0);
    t[k].T_ref_body.linear() = Eigen::AngleAxisd(yaw_per_pose_rad * double(k), Eigen::Vector3d::UnitZ()).matrix();
  }
  return t;
}

/// The devkit's segment: from pose `first`, the first pose whose path exceeds L (strictly) is first + L + 1 here.
size_t SegmentsOfLength(double length_m) {
  size_t n = 0;
  for (size_t first = 0; first < kPoses; first += 10)
    if (first + size_t(length_m) + 1 < kPoses) ++n;
  return n;
}

TEST(KittiOdometryError, ScaleDriftGivesItsPercentage) {
  const Trajectory ref = StraightDrive(1.0, 0.0), est = StraightDrive(1.01, 0.0);
  KittiOdometryErrors e;
  ASSERT_TRUE(ComputeKittiOdometryErrors(ref, est, KittiOdometryOptions(), &e));
  // Each segment spans L + 1 m of reference path; the estimate's is 1 % longer: t_err / L = 0.01 (L + 1) / L.
  double sum = 0.0;
  size_t count = 0;
  for (double length : KittiOdometryOptions().lengths_m) {
    const size_t n = SegmentsOfLength(length);
    sum += double(n) * 0.01 * (length + 1.0) / length;
    count += n;
  }
  ASSERT_EQ(e.segments.size(), count);
  EXPECT_NEAR(e.t_rel_percent, 100.0 * sum / double(count), 1e-9);
  EXPECT_NEAR(e.r_rel_deg_per_100m, 0.0, 1e-9);
  ASSERT_EQ(e.by_length.size(), 8u);
  EXPECT_EQ(e.by_length.back().segments, SegmentsOfLength(800.0));
  EXPECT_NEAR(e.by_length.front().t_rel_percent, 1.01, 1e-9);  // 100 m segments: 101 m of path
  EXPECT_NEAR(e.segments.front().speed_mps, 100.0 / 10.1, 1e-9);
}

TEST(KittiOdometryError, HeadingDriftGivesDegreesPer100m) {
  const double drift_rad_per_m = (1.0 * M_PI / 180.0) / 100.0;  // 1 deg / 100 m
  const Trajectory ref = StraightDrive(1.0, 0.0), est = StraightDrive(1.0, drift_rad_per_m);
  KittiOdometryErrors e;
  ASSERT_TRUE(ComputeKittiOdometryErrors(ref, est, KittiOdometryOptions(), &e));
  for (const KittiLengthError& l : e.by_length)  // the extra heading over L + 1 m, per L
    EXPECT_NEAR(l.r_rel_deg_per_100m, (l.length_m + 1.0) / l.length_m, 1e-6) << l.length_m;
  EXPECT_GT(e.t_rel_percent, 0.0);  // the turned estimate also leaves the line
}

TEST(KittiOdometryError, IdenticalTrajectoriesHaveNoError) {
  const Trajectory t = StraightDrive(1.0, 0.001);
  KittiOdometryErrors e;
  ASSERT_TRUE(ComputeKittiOdometryErrors(t, t, KittiOdometryOptions(), &e));
  EXPECT_NEAR(e.t_rel_percent, 0.0, 1e-12);
  EXPECT_NEAR(e.r_rel_deg_per_100m, 0.0, 1e-5);  // acos near 1 is ill-conditioned: ~1e-8 rad of rounding
}

TEST(KittiOdometryError, RejectsUnequalShortOrBadInput) {
  const Trajectory t = StraightDrive(1.0, 0.0);
  KittiOdometryErrors e;
  Status s = ComputeKittiOdometryErrors(t, Trajectory(t.begin(), t.end() - 1), KittiOdometryOptions(), &e);
  EXPECT_FALSE(s);
  EXPECT_NE(s.message.find("equal size"), std::string::npos) << s.message;
  s = ComputeKittiOdometryErrors(Trajectory(t.begin(), t.begin() + 50), Trajectory(t.begin(), t.begin() + 50),
                                 KittiOdometryOptions(), &e);
  EXPECT_FALSE(s);
  EXPECT_NE(s.message.find("shortest segment"), std::string::npos) << s.message;
  KittiOdometryOptions bad;
  bad.step_frames = 0;
  s = ComputeKittiOdometryErrors(t, t, bad, &e);
  EXPECT_FALSE(s);
  EXPECT_NE(s.message.find("step_frames"), std::string::npos) << s.message;
}

}  // namespace
}  // namespace rotolidar::bench
