// LoopCloser end to end on a synthetic world: a drifting odometry around a closed path; the loop closer must find
// the revisits, correct the drift, and give the same answer threaded or not.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "core/graph/loop_closer.hpp"
#include "core/graph/loop_gate.hpp"
#include "tests/core/graph/synthetic_walk.hpp"

namespace rotolidar::graph {
namespace {

using test_util::MakeWalk;
using test_util::MakeWorld;
using test_util::Observe;
using test_util::Walk;

double Rmse(const std::vector<Pose3>& a, const std::vector<Pose3>& b) {
  double sum = 0.0;
  for (size_t i = 0; i < a.size(); ++i) sum += (a[i].translation() - b[i].translation()).squaredNorm();
  return std::sqrt(sum / double(a.size()));
}

LoopClosureState RunWalk(bool threaded, const Walk& walk, const std::vector<Eigen::Vector3d>& world) {
  LoopClosureConfig config;
  config.enabled = true;
  config.threaded = threaded;
  config.map_voxel_m = 0.0;
  LoopCloser closer(config);
  for (size_t i = 0; i < walk.truth.size(); ++i) {
    KeyframeInput kf;
    kf.t_s = 0.5 * double(i);
    kf.T_world_base = walk.odometry[i];
    kf.points_base = Observe(world, walk.truth[i]);
    closer.AddKeyframe(std::move(kf));
  }
  closer.Finish();
  return closer.State();
}

std::vector<Pose3> CorrectedAtTruthSteps(const LoopClosureState& s, const Walk& walk, std::vector<Pose3>* truth) {
  std::vector<Pose3> out;
  for (const KeyframePose& k : s.keyframes) {
    out.push_back(k.T_world_corrected);
    truth->push_back(walk.truth[size_t(std::lround(k.t_s / 0.5))]);
  }
  return out;
}

TEST(LoopCloser, ClosesTheSquareAndRemovesTheDrift) {
  const std::vector<Eigen::Vector3d> world = MakeWorld(7);
  const Walk walk = MakeWalk();
  const LoopClosureState s = RunWalk(/*threaded=*/false, walk, world);
  ASSERT_GT(s.loops.size(), 0u);
  std::vector<Pose3> truth;
  const std::vector<Pose3> corrected = CorrectedAtTruthSteps(s, walk, &truth);
  std::vector<Pose3> odom;
  for (const KeyframePose& k : s.keyframes) odom.push_back(k.T_world_odom);
  const double before = Rmse(odom, truth), after = Rmse(corrected, truth);
  std::printf("keyframes %zu, loops %zu (proposed %zu, GICP %zu in %.1f s), ATE before %.3f m, after %.3f m, "
              "max solve %.3f s\n", s.keyframes.size(), s.loops.size(), s.candidates_proposed, s.candidates_checked,
              s.verify_time_s, before, after, s.max_solve_time_s);
  for (const LoopRecord& l : s.loops) {
    // Every accepted loop joins two keyframes whose true positions are within the sensor's overlap.
    const Pose3& Tq = walk.truth[size_t(std::lround(l.t_query_s / 0.5))];
    const Pose3& Tm = walk.truth[size_t(std::lround(l.t_match_s / 0.5))];
    EXPECT_LT((Tq.translation() - Tm.translation()).norm(), 10.0);
    // GICP's relative pose agrees with the truth's.
    const Pose3 err = (Tm.inverse() * Tq).inverse() * l.T_match_query;
    EXPECT_LT(err.translation().norm(), 0.01) << l.t_query_s << " -> " << l.t_match_s;  // measured <= 2 mm
    EXPECT_FALSE(l.rejected);
  }
  // The loops tie the second lap onto the first, whose own drift a pose graph can only spread (a yaw bias leaves
  // its mid-lap error: measured 0.44 -> 0.16 m overall). At the end, where the odometry is worst, the corrected pose
  // carries only the first lap's error at that place (measured 0.59 -> 0.07 m).
  EXPECT_LT(after, 0.5 * before);
  const Pose3& T_end = truth.back();
  EXPECT_LT((corrected.back().translation() - T_end.translation()).norm(),
            0.25 * (odom.back().translation() - T_end.translation()).norm());
}

TEST(LoopCloser, ThreadedGivesTheSameAnswer) {
  const std::vector<Eigen::Vector3d> world = MakeWorld(7);
  Walk walk = MakeWalk();
  walk.truth.resize(400), walk.odometry.resize(400);  // one lap and a quarter: a few loops, quicker
  const LoopClosureState a = RunWalk(false, walk, world), b = RunWalk(true, walk, world);
  ASSERT_EQ(a.keyframes.size(), b.keyframes.size());
  ASSERT_EQ(a.loops.size(), b.loops.size());
  for (size_t i = 0; i < a.keyframes.size(); ++i)
    EXPECT_TRUE(a.keyframes[i].T_world_corrected.isApprox(b.keyframes[i].T_world_corrected, 0.0)) << i;
}

// An estimator's rotations carry round-off (composed with KITTI's 6-digit calibration, R^T R - I reaches ~1e-6, the
// graph's own orthonormality tolerance); the loop closer projects them onto SO(3) and keeps every keyframe. A pose
// that is no rotation at all is counted as dropped, never handed to the graph (it once ended in a missing node).
TEST(LoopCloser, RoundedRotationsAreKeptAndBrokenOnesDropped) {
  const std::vector<Eigen::Vector3d> world = MakeWorld(7);
  Walk walk = MakeWalk();
  walk.truth.resize(400), walk.odometry.resize(400);
  const LoopClosureState exact = RunWalk(false, walk, world);
  for (Pose3& T : walk.odometry) T.linear() *= 1.0 + 3e-6;  // fails a 1e-6 check on R^T R - I
  walk.odometry[0].linear()(0, 1) += 0.1;                   // a shear: the first keyframe offered is unusable
  const LoopClosureState rounded = RunWalk(false, walk, world);
  EXPECT_EQ(exact.keyframes_dropped, 0u);
  EXPECT_EQ(rounded.keyframes_dropped, 1u);
  EXPECT_EQ(rounded.keyframes.size() + 1, exact.keyframes.size());
  EXPECT_GT(exact.loops.size(), 0u);
  EXPECT_GT(rounded.loops.size(), 0u);
  EXPECT_TRUE(rounded.last_message.empty()) << rounded.last_message;
}

TEST(LoopCloser, KeyframeSpacingAndBadConfig) {
  LoopClosureConfig config;
  config.enabled = true;
  config.threaded = false;
  std::string why;
  config.num_candidates = 0;
  EXPECT_FALSE(config.Validate(&why));
  EXPECT_NE(why.find("num_candidates"), std::string::npos) << why;
  config.num_candidates = 3;
  LoopCloser closer(config);
  for (int i = 0; i < 10; ++i) {  // 10 cm apart: one keyframe per metre is taken
    KeyframeInput kf;
    kf.t_s = i;
    kf.T_world_base.translation().x() = 0.1 * i;
    // Two points in one 0.2 m voxel, one beyond max_range_m (40 m), one non-finite: one point is stored.
    kf.points_base = {{1.0f, 1.0f, 1.0f}, {1.05f, 1.05f, 1.05f}, {50.0f, 0.0f, 0.0f},
                      {std::nanf(""), 0.0f, 0.0f}};
    closer.AddKeyframe(std::move(kf));
  }
  closer.Finish();
  const LoopClosureState s = closer.State();
  EXPECT_EQ(s.keyframes_offered, 10u);
  EXPECT_EQ(s.keyframes.size(), 1u);
  // The database copy: the taken keyframe's pose and its thinned points.
  const std::vector<KeyframeCloud> clouds = closer.KeyframeClouds();
  ASSERT_EQ(clouds.size(), 1u);
  EXPECT_EQ(clouds[0].id, 0);
  EXPECT_EQ(clouds[0].t_s, 0.0);
  EXPECT_TRUE(clouds[0].T_world_odom.isApprox(Pose3::Identity()));
  ASSERT_EQ(clouds[0].cloud_base.size(), 1u);
  EXPECT_LT((clouds[0].cloud_base[0] - Eigen::Vector3d(1.0, 1.0, 1.0)).norm(), 0.2);
}

}  // namespace
}  // namespace rotolidar::graph

namespace rotolidar::graph {
namespace {

// The graph neighbour's descriptor: moved to the candidate's origin by the guess, a scan taken 4 m away compares
// as the same place; the plain descriptor does not (the polar grid shifts with the offset).
TEST(LoopGate, DescriptorAtGuessUndoesTheOffset) {
  const std::vector<Eigen::Vector3d> world = MakeWorld(7);
  Pose3 T_world_match = Pose3::Identity(), T_world_query = RotZ(0.3);
  T_world_match.translation() << 20.0, 20.0, 0.0;
  T_world_query.translation() << 24.0, 20.0, 0.0;
  auto describe = [&](const Pose3& T, std::vector<Eigen::Vector3d>* cloud) {
    std::vector<Eigen::Vector3f> points = Observe(world, T);
    for (const Eigen::Vector3f& p : points) cloud->push_back(p.cast<double>());
    return loop::ComputeLidarDescriptor(points, loop::LidarDescriptorConfig{});  // level already: R_level = I
  };
  std::vector<Eigen::Vector3d> query_cloud, match_cloud;
  const loop::LidarDescriptor query = describe(T_world_query, &query_cloud);
  const loop::LidarDescriptor match = describe(T_world_match, &match_cloud);
  const double plain = loop::DescriptorDistance(query, match).distance;
  const loop::DescriptorMatch at_guess =
      DescriptorAtGuess(query_cloud, query, match, Eigen::Matrix3d::Identity(), T_world_match.inverse() * T_world_query,
                        0.0, loop::LidarDescriptorConfig{});
  std::printf("Scan Context distance 4 m apart: plain %.3f, at the guess %.3f\n", plain, at_guess.distance);
  EXPECT_LT(at_guess.distance, plain);
  // Measured 0.069 (plain 0.260): the same surfaces from one origin; the two 25 m discs differ at their edges.
  EXPECT_LT(at_guess.distance, 0.1);

  // A drifted guess (2 m and 1 m off, as odometry after ~40 m at 5 %): the guess alone no longer undoes the offset;
  // the 1 m grid search within 3 m finds the offset again.
  Pose3 T_drift = Pose3::Identity();
  T_drift.translation() << 2.0, -1.0, 0.0;
  const Pose3 T_guess = T_drift * T_world_match.inverse() * T_world_query;
  const double drifted = DescriptorAtGuess(query_cloud, query, match, Eigen::Matrix3d::Identity(), T_guess, 0.0,
                                           loop::LidarDescriptorConfig{}).distance;
  const double searched = DescriptorAtGuess(query_cloud, query, match, Eigen::Matrix3d::Identity(), T_guess, 3.0,
                                            loop::LidarDescriptorConfig{}).distance;
  std::printf("drifted guess: %.3f, with the 3 m search %.3f\n", drifted, searched);
  EXPECT_LE(searched, at_guess.distance + 1e-6);  // the grid contains the offset that undoes the drift exactly
  EXPECT_LT(searched, drifted);
}

// A keyframe described with the window: its own points plus those of the earlier keyframes within the window, each
// moved into its base frame by the odometry; 0 keeps its own points only.
TEST(LoopGate, DescribedPointsGatherTheWindowInTheKeyframesFrame) {
  std::vector<Pose3> poses(3, Pose3::Identity());
  poses[1].translation() << 1.0, 0.0, 0.0;
  poses[2] = RotZ(M_PI / 2.0);
  poses[2].translation() << 2.0, 0.0, 0.0;
  const std::vector<double> times = {0.0, 1.0, 2.0};
  const std::vector<std::vector<Eigen::Vector3d>> points = {{{0.0, 0.0, 0.0}}, {{0.0, 0.0, 1.0}}, {{1.0, 0.0, 0.0}}};
  auto described = [&](double window_s) {
    return DescribedPoints(
        2, points[2], poses[2], window_s, times[2], [&](int k) { return times[size_t(k)]; },
        [&](int k) { return poses[size_t(k)]; },
        [&](int k) -> const std::vector<Eigen::Vector3d>& { return points[size_t(k)]; });
  };
  EXPECT_EQ(described(0.0).size(), 1u);
  const std::vector<Eigen::Vector3d> one = described(1.5);  // keyframe 1 (1 s old), not 0 (2 s old)
  ASSERT_EQ(one.size(), 2u);
  EXPECT_TRUE(one[0].isApprox(Eigen::Vector3d(1.0, 0.0, 0.0)));
  // Keyframe 1's point (1, 0, 1) in the world seen from keyframe 2 at (2, 0, 0) turned 90 deg: (0, 1, 1).
  EXPECT_LT((one[1] - Eigen::Vector3d(0.0, 1.0, 1.0)).norm(), 1e-12);
  EXPECT_EQ(described(2.0).size(), 3u);
  LoopClosureConfig bad;
  bad.descriptor_window_s = -1.0;
  std::string why;
  EXPECT_FALSE(bad.Validate(&why));
  EXPECT_NE(why.find("descriptor_window_s"), std::string::npos) << why;
}

}  // namespace
}  // namespace rotolidar::graph
