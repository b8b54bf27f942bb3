// Alignment: Umeyama SE(3)/Sim(3) and position+yaw recover known transforms from noise-free points.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "bench/eval/alignment.hpp"

namespace rotolidar::bench {
namespace {

/// Non-planar, non-symmetric points (a helix with growing radius).
std::vector<Eigen::Vector3d> Points() {
  std::vector<Eigen::Vector3d> p;
  for (int i = 0; i < 40; ++i) p.emplace_back((1 + 0.1 * i) * std::cos(0.4 * i), 2 * std::sin(0.4 * i), 0.3 * i);
  return p;
}

std::vector<Eigen::Vector3d> Transform(const std::vector<Eigen::Vector3d>& p, const Pose3& T, double s) {
  std::vector<Eigen::Vector3d> out;
  for (const auto& x : p) out.push_back(s * (T.linear() * x) + T.translation());
  return out;
}

Pose3 KnownPose() {
  Pose3 T = Pose3::Identity();
  T.linear() = ExpSO3(Eigen::Vector3d(0.4, -1.2, 2.5));
  T.translation() = Eigen::Vector3d(10.0, -3.0, 0.7);
  return T;
}

TEST(Alignment, Se3RecoversKnownTransform) {
  const auto est = Points();
  const Pose3 T = KnownPose();
  const AlignmentResult r = AlignPositions(est, Transform(est, T, 1.0), Alignment::kSe3);
  ASSERT_TRUE(r.success) << r.message;
  EXPECT_LE((r.T_ref_est.matrix() - T.matrix()).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_EQ(r.scale, 1.0);
}

TEST(Alignment, Sim3RecoversKnownTransformAndScale) {
  const auto est = Points();
  const Pose3 T = KnownPose();
  const AlignmentResult r = AlignPositions(est, Transform(est, T, 3.7), Alignment::kSim3);
  ASSERT_TRUE(r.success) << r.message;
  EXPECT_LE((r.T_ref_est.matrix() - T.matrix()).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_NEAR(r.scale, 3.7, 1e-9);
}

TEST(Alignment, PosYawRecoversYawAndTranslation) {
  const auto est = Points();
  Pose3 T = RotZ(-2.1);
  T.translation() = Eigen::Vector3d(-4.0, 5.5, 1.25);
  const AlignmentResult r = AlignPositions(est, Transform(est, T, 1.0), Alignment::kPosYaw);
  ASSERT_TRUE(r.success) << r.message;
  EXPECT_LE((r.T_ref_est.matrix() - T.matrix()).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(Alignment, ApplyAlignmentMapsEstimateOntoReference) {
  Trajectory est;
  for (const auto& p : Points()) {
    StampedPose sp;
    sp.T_ref_body.translation() = p;
    est.push_back(sp);
  }
  AlignmentResult a;
  a.success = true;
  a.T_ref_est = KnownPose();
  a.scale = 2.0;
  const Trajectory out = ApplyAlignment(a, est);
  const auto expected = Transform(Positions(est), a.T_ref_est, 2.0);
  for (size_t i = 0; i < out.size(); ++i) {
    EXPECT_LE((out[i].T_ref_body.translation() - expected[i]).norm(), 1e-12);
    EXPECT_LE((out[i].T_ref_body.linear() - a.T_ref_est.linear()).norm(), 1e-12);  // est rotations were I
  }
}

TEST(Alignment, DegenerateInputFails) {
  std::vector<Eigen::Vector3d> line;
  for (int i = 0; i < 10; ++i) line.emplace_back(i, 2.0 * i, -1.0 * i);  // collinear: rotation about it is free
  AlignmentResult r = AlignPositions(line, line, Alignment::kSe3);
  EXPECT_FALSE(r.success);
  EXPECT_FALSE(r.message.empty());
  r = AlignPositions({Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones()}, {Eigen::Vector3d::Zero(),
                     Eigen::Vector3d::Ones()}, Alignment::kSim3);
  EXPECT_FALSE(r.success);  // too few points
  std::vector<Eigen::Vector3d> vertical = {{0, 0, 0}, {0, 0, 1}, {0, 0, 2}};
  EXPECT_FALSE(AlignPositions(vertical, vertical, Alignment::kPosYaw).success);
  EXPECT_FALSE(AlignPositions(line, vertical, Alignment::kNone).success);  // size mismatch
  EXPECT_TRUE(AlignPositions({}, {}, Alignment::kNone).success);
}

}  // namespace
}  // namespace rotolidar::bench
