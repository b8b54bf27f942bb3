// Which alignment places map.ply in the scene frame: the trajectory's own, except with loop closure, where the
// trajectory is the corrected one while map.ply is the odometry's dense map: then the odometry trajectory's.
#include <unistd.h>

#include <filesystem>
#include <vector>

#include <gtest/gtest.h>

#include "bench/report/run_evaluation.hpp"
#include "core/io/point_cloud_io.hpp"
#include "core/io/trajectory_io.hpp"

namespace rotolidar::bench {
namespace {

namespace fs = std::filesystem;

/// Truth: an L-shaped walk (so the SE(3) alignment is defined), turning about z.
Pose3 TruePose(double t) {
  const Eigen::Vector3d p = t <= 1.0 ? Eigen::Vector3d(2.0 * t, 0.0, 1.0) : Eigen::Vector3d(2.0, 2.0 * (t - 1.0), 1.0);
  return MakePose(p, Eigen::Quaterniond(Eigen::AngleAxisd(0.4 * t, Eigen::Vector3d::UnitZ())));
}

Pose3 RigidOffset(double yaw_rad, const Eigen::Vector3d& t_m) {
  return MakePose(t_m, Eigen::Quaterniond(Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ())));
}

struct Fixture {
  std::string recording, slam_dir;
  SlamRunResult slam;
  std::vector<Eigen::Vector3d> scene_points;  ///< where map.ply's points truly are (scene frame)
};

/// The odometry's world is the scene moved by W_odometry; the "corrected" trajectory's by W_corrected; map.ply
/// holds scene points in the odometry's world.
Fixture Make(const std::string& name, size_t loop_keyframes) {
  Fixture f;
  const std::string dir = (fs::temp_directory_path() / (name + std::to_string(::getpid()))).string();
  fs::remove_all(dir);
  f.recording = dir + "/recording", f.slam_dir = dir + "/slam";
  fs::create_directories(f.recording + "/truth");
  fs::create_directories(f.slam_dir);
  const Pose3 W_odometry = RigidOffset(0.3, Eigen::Vector3d(1.0, -2.0, 0.5));
  const Pose3 W_corrected = RigidOffset(-0.2, Eigen::Vector3d(-3.0, 1.0, 0.0));
  Trajectory truth;
  for (int k = 0; k <= 200; ++k) {
    const double t = 0.01 * k;
    truth.push_back({t, TruePose(t)});
    f.slam.odometry_trajectory.push_back({t, W_odometry.inverse() * TruePose(t)});
    f.slam.trajectory.push_back({t, W_corrected.inverse() * TruePose(t)});
  }
  EXPECT_TRUE(WriteTrajectory(f.recording + "/truth/base.tum", TrajectoryFormat::kTum, truth).ok);
  std::vector<Eigen::Vector3d> map_points;
  for (int i = 0; i < 50; ++i) {
    f.scene_points.emplace_back(0.1 * i, 3.0 - 0.05 * i, 0.02 * i);
    map_points.push_back(W_odometry.inverse() * f.scene_points.back());
  }
  EXPECT_TRUE(SavePointCloud(f.slam_dir + "/map.ply", map_points).ok);
  f.slam.loops.keyframes_offered = loop_keyframes;
  return f;
}

double WorstOffset(const RunEvaluation& eval, const std::vector<Eigen::Vector3d>& expected) {
  EXPECT_EQ(eval.map_points.size(), expected.size());
  double worst = 0.0;
  for (size_t i = 0; i < std::min(eval.map_points.size(), expected.size()); ++i)
    worst = std::max(worst, (eval.map_points[i].cast<double>() - expected[i]).norm());
  return worst;
}

RunEvaluation Evaluate(const Fixture& f) {
  RunEvaluationOptions options;
  options.map_metrics = false;
  options.completeness = false;
  RunEvaluation eval;
  const Status s = EvaluateRun(f.recording, f.slam_dir, f.slam, "", options, &eval);
  EXPECT_TRUE(s.ok) << s.message;
  return eval;
}

// With loop closure the odometry's map lands on the scene (float PLY: ~1e-6 m), although the corrected
// trajectory's alignment differs by 0.5 rad and metres.
TEST(MapAlignment, LoopClosedRunPlacesTheOdometryMapWithTheOdometryAlignment) {
  const Fixture f = Make("rotolidar_map_alignment_lc_", 12);
  const RunEvaluation eval = Evaluate(f);
  EXPECT_NEAR(eval.ape.stats.rmse, 0.0, 1e-6);  // the corrected trajectory is exact up to its alignment
  EXPECT_LT(WorstOffset(eval, f.scene_points), 1e-4);
}

// Without loop closure the trajectory is the odometry's: its own alignment places the map (here deliberately
// the other offset, so the test sees which one was used).
TEST(MapAlignment, OdometryRunPlacesTheMapWithTheTrajectoryAlignment) {
  const Fixture f = Make("rotolidar_map_alignment_odo_", 0);
  const RunEvaluation eval = Evaluate(f);
  const Pose3 W_odometry = RigidOffset(0.3, Eigen::Vector3d(1.0, -2.0, 0.5));
  const Pose3 W_corrected = RigidOffset(-0.2, Eigen::Vector3d(-3.0, 1.0, 0.0));
  std::vector<Eigen::Vector3d> expected;
  for (const Eigen::Vector3d& p : f.scene_points) expected.push_back(W_corrected * (W_odometry.inverse() * p));
  EXPECT_LT(WorstOffset(eval, expected), 1e-4);
}

}  // namespace
}  // namespace rotolidar::bench
