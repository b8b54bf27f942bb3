// GICP scan-to-map registration recovers a known rigid transform on a synthetic room.
#include <gtest/gtest.h>

#include "core/registration/gicp_matcher.hpp"
#include "core/util/rng.hpp"

namespace rotolidar {
namespace {

/// Points sampled on the walls, floor and ceiling of a 10 x 8 x 3 m room plus a box: structure in all 6 DOF.
std::vector<Eigen::Vector3d> RoomCloud(RandomStream* rng, int n) {
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < n; ++i) {
    const double u = rng->Uniform(), v = rng->Uniform();
    switch (i % 7) {
      case 0: pts.emplace_back(-5, -4 + 8 * u, 3 * v); break;
      case 1: pts.emplace_back(5, -4 + 8 * u, 3 * v); break;
      case 2: pts.emplace_back(-5 + 10 * u, -4, 3 * v); break;
      case 3: pts.emplace_back(-5 + 10 * u, 4, 3 * v); break;
      case 4: pts.emplace_back(-5 + 10 * u, -4 + 8 * v, 0); break;
      case 5: pts.emplace_back(-5 + 10 * u, -4 + 8 * v, 3); break;
      default: pts.emplace_back(1 + u, 1, 1.5 * v); break;  // a box face
    }
  }
  return pts;
}

TEST(GicpMatcher, RecoversAKnownTransform) {
  RandomStream rng(3, "gicp_matcher_test");
  const std::vector<Eigen::Vector3d> target = RoomCloud(&rng, 20000);
  const Pose3 T_target_source =
      MakePose({0.3, -0.2, 0.1}, Eigen::Quaterniond(Eigen::AngleAxisd(0.1, Eigen::Vector3d(0.2, 0.3, 1).normalized())));
  std::vector<Eigen::Vector3d> source;
  for (const auto& p : RoomCloud(&rng, 8000)) source.push_back(T_target_source.inverse() * p);
  GicpMatcher matcher(GicpConfig{});
  matcher.SetTarget(target);
  const RegistrationResult r = matcher.Align(source, Pose3::Identity());
  ASSERT_TRUE(r.converged);
  EXPECT_GT(r.iterations, 0);
  EXPECT_GT(r.num_inliers, source.size() * 9 / 10);
  // Exact, noise-free samples of the same surfaces: GICP's float arithmetic leaves ~mm error.
  EXPECT_LT((r.T_target_source.translation() - T_target_source.translation()).norm(), 0.01);
  EXPECT_LT(Eigen::AngleAxisd(r.T_target_source.linear().transpose() * T_target_source.linear()).angle(), 1e-3);
}

TEST(GicpMatcher, WithoutTargetReportsNotConverged) {
  GicpMatcher matcher(GicpConfig{});
  const RegistrationResult r = matcher.Align({Eigen::Vector3d::Zero()}, Pose3::Identity());
  EXPECT_FALSE(r.converged);
}

}  // namespace
}  // namespace rotolidar
