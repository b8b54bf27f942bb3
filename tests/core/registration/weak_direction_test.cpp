// Weakly observed directions (degeneracy.hpp): a corridor whose axis only its end wall observes. The LiDAR's
// estimate along such a direction is used when it agrees with the guess (the motion prior) within the gate,
// and remapped (the prior keeps it) when it strays: the innovation gate against a person walking by.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "core/registration/scan_to_map.hpp"
#include "tests/core/registration/room_points.hpp"

namespace rotolidar {
namespace {

/// A 40 m corridor shell (x in [-20, 20]) closed by one end wall at x = -20: only that wall sees x.
std::vector<Eigen::Vector3d> CorridorWithEndWall(RandomStream& rng) {
  std::vector<Eigen::Vector3d> p;
  AddShell(-20, 20, rng, &p);
  AddFace(0, -20.0, {-20, -2, 0}, {-20, 2, 3}, rng, &p);
  return p;
}

Pose3 At(const Eigen::Vector3d& t) { return MakePose(t, Eigen::Quaterniond::Identity()); }

class WeakDirection : public ::testing::Test {
 protected:
  void SetUp() override {
    RandomStream rng(5, "test.registration.weak_direction");
    LocalMapConfig map_config;
    map_config.planar_voxel_m = 0.1;
    map_ = std::make_unique<LocalMap>(map_config);
    map_->AddKeyframe(InFrameOf(CorridorWithEndWall(rng), sensor_), At(sensor_));
    scan_ = InFrameOf(CorridorWithEndWall(rng), sensor_);  // the same corridor, fresh noise
  }
  const Eigen::Vector3d sensor_{0.0, 0.3, 1.4};
  std::unique_ptr<LocalMap> map_;
  FeatureSet scan_;
};

TEST_F(WeakDirection, AxisSeenOnlyByTheEndWallIsWeakAndUsedWithinTheGate) {
  const ScanToMapConfig config;
  const Pose3 guess = At(sensor_ + Eigen::Vector3d(0.015, 0.0, 0.0));  // 1.5 cm along the axis: inside the gate
  const ScanToMapResult r = Register(scan_, *map_, guess, config);
  ASSERT_TRUE(r.converged) << r.message;
  // Measured lambda_min 0.021 (the end wall's share of the matches) against 0.27 for the next direction: weak
  // (between min_eigenvalue 0.005 and weak_eigenvalue 0.05), along x.
  EXPECT_GT(r.degeneracy.eigenvalues(0), config.degeneracy.min_eigenvalue);
  EXPECT_LT(r.degeneracy.eigenvalues(0), config.degeneracy.weak_eigenvalue);
  EXPECT_GT(std::abs(r.degeneracy.eigenvectors.col(0).normalized()(0)), 0.99);
  // Inside the gate the end wall's estimate stands: not remapped, x back at the truth (measured 2.8 mm from it,
  // from 15 mm: the end wall's voxel centroids; 2x margin).
  EXPECT_FALSE(r.remapped);
  EXPECT_FALSE(r.degeneracy.degenerate);
  EXPECT_LT(std::abs(r.T_map_scan.translation().x() - sensor_.x()), 0.006);
}

TEST_F(WeakDirection, EstimateStrayingBeyondTheGateIsRemappedToTheGuess) {
  ScanToMapConfig config;
  const Pose3 guess = At(sensor_ + Eigen::Vector3d(0.20, 0.0, 0.0));  // the solve would move 20 cm along x
  const ScanToMapResult r = Register(scan_, *map_, guess, config);
  ASSERT_TRUE(r.converged) << r.message;
  EXPECT_TRUE(r.remapped);
  ASSERT_EQ(r.degeneracy.degenerate_directions.size(), 1u);
  EXPECT_GT(std::abs(r.degeneracy.degenerate_directions[0](0)), 0.99);
  // Measured: x exactly the guess's; y, z 0.3 mm from the truth.
  EXPECT_LT(std::abs(r.T_map_scan.translation().x() - guess.translation().x()), 1e-3);
  EXPECT_LT((r.T_map_scan.translation() - sensor_).tail<2>().norm(), 0.003);
  // A wider gate lets the same estimate through.
  config.degeneracy.weak_gate_m = 0.4;
  const ScanToMapResult wide = Register(scan_, *map_, guess, config);
  EXPECT_FALSE(wide.remapped);
  EXPECT_LT(std::abs(wide.T_map_scan.translation().x() - sensor_.x()), 0.006);  // measured 2.8 mm, as above
}

// The count on constructed Hessians: H = N (G - c G w w^T G) has lambda = 1 - c along the G-unit w, 1 elsewhere.
TEST(WeakDirectionGate, CountsDegenerateAndStrayingWeakDirections) {
  std::vector<Eigen::Vector3d> levers;
  RandomStream rng(9, "test.registration.gate");
  for (int i = 0; i < 50; ++i)
    levers.push_back(Eigen::Vector3d{rng.Normal(0.0, 3.0), rng.Normal(0.0, 3.0), rng.Normal(0.0, 1.0)});
  const Matrix6d G = DisplacementMetric(levers);
  Vector6d w;
  w << 1.0, 0.0, 0.0, 0.0, 0.0, 0.0;
  w /= std::sqrt(w.dot(G * w));
  const int n = 50;
  const DegeneracyConfig config;  // min 0.005, weak 0.05, gate 0.1 m
  auto info_for = [&](double lambda) {
    const Matrix6d H = n * (G - (1.0 - lambda) * G * w * w.transpose() * G);
    return AnalyzeDegeneracy(H, G, n, config);
  };
  Vector6d small_step = 0.05 * w, large_step = 0.15 * w;  // RMS point motion 5 cm / 15 cm along w
  EXPECT_EQ(GatedDegenerateCount(info_for(0.001), small_step, config), 1);  // degenerate whatever the step
  EXPECT_EQ(GatedDegenerateCount(info_for(0.02), small_step, config), 0);   // weak, inside the gate
  EXPECT_EQ(GatedDegenerateCount(info_for(0.02), large_step, config), 1);   // weak, beyond it
  EXPECT_EQ(GatedDegenerateCount(info_for(0.5), large_step, config), 0);    // well observed: never gated
  DegeneracyInfo info = info_for(0.02);
  MarkDegenerate(1, &info);
  EXPECT_TRUE(info.degenerate);
  EXPECT_NEAR((info.projection * w).dot(G * w), 0.0, 1e-9);  // nothing left along w
}

TEST(WeakDirectionGate, ValidateNamesTheFields) {
  DegeneracyConfig c;
  std::string error;
  c.weak_eigenvalue = 0.001;  // below min_eigenvalue
  EXPECT_FALSE(c.Validate(&error));
  EXPECT_NE(error.find("degeneracy.weak_eigenvalue"), std::string::npos) << error;
  c = DegeneracyConfig();
  c.weak_gate_m = 0.0;
  EXPECT_FALSE(c.Validate(&error));
  EXPECT_NE(error.find("degeneracy.weak_gate_m"), std::string::npos) << error;
}

}  // namespace
}  // namespace rotolidar
