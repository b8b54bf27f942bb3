// Association, APE and RPE on synthetic trajectories with known errors.
#include <cmath>

#include <gtest/gtest.h>

#include "bench/eval/trajectory_metrics.hpp"

namespace rotolidar::bench {
namespace {

Pose3 Step(double dx_m, double yaw_rad) {
  Pose3 T = RotZ(yaw_rad);
  T.translation() = Eigen::Vector3d(dx_m, 0.0, 0.0);
  return T;
}

/// n poses, each reached from the previous by Step(dx_m, yaw_rad) in the body frame; t = 0.1 s * index.
Trajectory Chain(int n, double dx_m, double yaw_rad) {
  Trajectory traj;
  Pose3 T = Pose3::Identity();
  for (int i = 0; i < n; ++i) {
    traj.push_back({0.1 * i, T});
    T = T * Step(dx_m, yaw_rad);
  }
  return traj;
}

TEST(Association, NearestWithinMaxDiffFirstOfEqualTimes) {
  Trajectory ref, est;
  for (int i = 0; i < 10; ++i) ref.push_back({1.0 * i, Pose3::Identity()});
  ref.insert(ref.begin() + 3, {2.0, Pose3::Identity()});  // duplicate time 2.0 at index 2 and 3
  ref[3].T_ref_body.translation().x() = 99.0;              // marks the second duplicate
  est.push_back({0.004, Pose3::Identity()});                // -> ref t=0
  est.push_back({2.009, Pose3::Identity()});                // -> the first ref pose at t=2 (argmin picks first)
  est.push_back({4.5, Pose3::Identity()});                  // no match within 0.01 s
  est.push_back({8.999, Pose3::Identity()});                // -> ref t=9
  Trajectory ref_a, est_a;
  const Status s = AssociateTrajectories(ref, est, 0.01, &ref_a, &est_a);
  ASSERT_TRUE(s.ok) << s.message;
  ASSERT_EQ(ref_a.size(), 3u);
  ASSERT_EQ(est_a.size(), 3u);
  EXPECT_EQ(ref_a[0].t_s, 0.0);
  EXPECT_EQ(ref_a[1].t_s, 2.0);
  EXPECT_EQ(ref_a[1].T_ref_body.translation().x(), 0.0);
  EXPECT_EQ(ref_a[2].t_s, 9.0);
  EXPECT_EQ(est_a[2].t_s, 8.999);

  EXPECT_FALSE(AssociateTrajectories(ref, {{100.0, Pose3::Identity()}}, 0.01, &ref_a, &est_a).ok);
}

TEST(Ape, TranslationAndRotationOfKnownOffset) {
  const Trajectory ref = Chain(20, 1.0, 0.05);
  Trajectory est = ref;
  for (auto& sp : est) sp.T_ref_body = sp.T_ref_body * Step(0.0, 0.1);  // rotated by 0.1 rad in the body frame
  for (auto& sp : est) sp.T_ref_body.translation().z() += 0.25;
  std::vector<double> e;
  ASSERT_TRUE(ComputeApeErrors(ref, est, PoseRelation::kTranslation, &e).ok);
  for (double v : e) EXPECT_NEAR(v, 0.25, 1e-12);
  ASSERT_TRUE(ComputeApeErrors(ref, est, PoseRelation::kRotationAngleDeg, &e).ok);
  for (double v : e) EXPECT_NEAR(v, 0.1 * 180.0 / M_PI, 1e-9);
  EXPECT_FALSE(ComputeApeErrors(ref, Chain(3, 1.0, 0.0), PoseRelation::kTranslation, &e).ok);
}

// The estimate moves 1.1 m and turns 0.02 rad more per frame than the reference (1 m, 0 rad): each one-frame
// relative error is E = Step(0.1, 0.02), i.e. 0.1 m and 0.02 rad exactly.
TEST(Rpe, OneFrameDeltaGivesPerStepError) {
  const Trajectory ref = Chain(30, 1.0, 0.0), est = Chain(30, 1.1, 0.02);
  RpeOptions o;
  std::vector<double> e;
  std::vector<IdPair> pairs;
  ASSERT_TRUE(ComputeRpeErrors(ref, est, o, &e, &pairs).ok);
  ASSERT_EQ(e.size(), 29u);
  for (double v : e) EXPECT_NEAR(v, 0.1, 1e-12);
  o.relation = PoseRelation::kRotationAngleRad;
  ASSERT_TRUE(ComputeRpeErrors(ref, est, o, &e).ok);
  for (double v : e) EXPECT_NEAR(v, 0.02, 1e-12);
}

TEST(Rpe, FramePairsConsecutiveAndAll) {
  const Trajectory t = Chain(10, 1.0, 0.0);
  RpeOptions o;
  o.delta = 3;
  std::vector<IdPair> pairs;
  ASSERT_TRUE(ComputeIdPairs(t, o, &pairs).ok);
  EXPECT_EQ(pairs, (std::vector<IdPair>{{0, 3}, {3, 6}, {6, 9}}));
  o.all_pairs = true;
  ASSERT_TRUE(ComputeIdPairs(t, o, &pairs).ok);
  EXPECT_EQ(pairs.size(), 7u);
  EXPECT_EQ(pairs.back(), IdPair(6, 9));
  o.delta = 10;
  EXPECT_FALSE(ComputeIdPairs(t, o, &pairs).ok);  // empty list is an error, as in evo
  o.delta = 1.5;
  EXPECT_FALSE(ComputeIdPairs(t, o, &pairs).ok);
}

TEST(Rpe, MetrePairsFollowPathLength) {
  const Trajectory t = Chain(12, 1.1, 0.0);  // 1.1 m per frame
  RpeOptions o;
  o.delta = 3.0;
  o.delta_unit = DeltaUnit::kMeters;
  std::vector<IdPair> pairs;
  ASSERT_TRUE(ComputeIdPairs(t, o, &pairs).ok);
  // Path since the last id reaches 3 m at frames 3, 6, 9 (3.3 m each); pose 0 is not an id (evo).
  EXPECT_EQ(pairs, (std::vector<IdPair>{{3, 6}, {6, 9}}));
  o.all_pairs = true;
  o.delta = 3.2;  // nearest is 3 frames (3.3 m, 0.1 m off, within 10 % = 0.32 m)
  ASSERT_TRUE(ComputeIdPairs(t, o, &pairs).ok);
  ASSERT_EQ(pairs.size(), 9u);
  for (size_t k = 0; k < pairs.size(); ++k) EXPECT_EQ(pairs[k], IdPair(k, k + 3));
  o.delta = 2.75;  // 2.2 m and 3.3 m are both 0.55 m off (> 0.275 m tolerance): no pair
  EXPECT_FALSE(ComputeIdPairs(t, o, &pairs).ok);
}

TEST(Rpe, MetrePairsComeFromTheEstimateByDefault) {
  const Trajectory ref = Chain(12, 1.0, 0.0), est = Chain(12, 2.0, 0.0);
  RpeOptions o;
  o.delta = 4.0;
  o.delta_unit = DeltaUnit::kMeters;
  std::vector<double> e;
  std::vector<IdPair> pairs;
  ASSERT_TRUE(ComputeRpeErrors(ref, est, o, &e, &pairs).ok);
  EXPECT_EQ(pairs.front(), IdPair(2, 4));  // 2 m per estimate frame
  EXPECT_NEAR(e.front(), 2.0, 1e-12);      // 4 m estimated vs 2 m true
  o.pairs_from_reference = true;
  ASSERT_TRUE(ComputeRpeErrors(ref, est, o, &e, &pairs).ok);
  EXPECT_EQ(pairs.front(), IdPair(4, 8));
}

}  // namespace
}  // namespace rotolidar::bench
