// Pose graph helpers: covariance -> information (inverse and floors), the information's frame change (chi2 kept),
// and the trajectory correction from keyframe poses (zero / offset corrections, following keyframes, bad input).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include <ceres/manifold.h>
#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <gtest/gtest.h>

#include "core/graph/pose_graph.hpp"
#include "core/util/log.hpp"
#include "core/util/rng.hpp"

#include "tests/core/graph/pose_graph_test_util.hpp"

namespace rotolidar::graph {
namespace {

using namespace test_util;

// ----------------------------------------------------------------------------------------- information helpers

/// A random orthonormal 6x6 basis (QR of a Gaussian matrix).
Matrix6d RandomRotation6(RandomStream& rng) {
  Matrix6d M;
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) M(r, c) = rng.Normal();
  return Eigen::HouseholderQR<Matrix6d>(M).householderQ();
}

TEST(PoseGraphHelpers, InformationFromCovarianceInvertsAndFloors) {
  RandomStream rng(3, "graph-covariance");
  const InformationFloor floor;  // 0.01 m, 0.001 rad
  Vector6d floor_sigma;
  floor_sigma << Eigen::Vector3d::Constant(floor.min_sigma_translation_m),
      Eigen::Vector3d::Constant(floor.min_sigma_rotation_rad);
  for (int trial = 0; trial < 10; ++trial) {
    const Matrix6d Q = RandomRotation6(rng);
    // Well above the floors: sigmas 0.05..0.2 m and 0.01..0.04 rad, correlated (eigenvalues of the correlation
    // 0.5..1.5), so in floor units every eigenvalue is >= 0.5 * 5^2: the helper is the plain inverse.
    Vector6d sigma;
    sigma << 0.1, 0.05, 0.2, 0.02, 0.01, 0.04;
    const Vector6d spread = (Vector6d() << 0.5, 0.7, 0.9, 1.1, 1.3, 1.5).finished();
    const Matrix6d correlation = Q * spread.asDiagonal() * Q.transpose();
    const Matrix6d covariance = sigma.asDiagonal() * correlation * sigma.asDiagonal();
    Matrix6d information;
    ASSERT_TRUE(InformationFromCovariance(covariance, floor, &information).ok);
    // Condition number ~1e3: the product is the identity to ~1e-12; 1e-9 leaves margin.
    EXPECT_LT((information * covariance - Matrix6d::Identity()).cwiseAbs().maxCoeff(), 1e-9);

    // Near-singular (a degenerate ICP: sigma 1e-7 m and 1e-9 rad along random directions) and even indefinite:
    // no direction may be more certain than its floor, i.e. D information D <= I for D = diag(floor sigmas).
    Vector6d tiny;
    tiny << 1e-14, 4e-2, -1e-6, 1e-18, 1e-4, 2e-3;  // eigenvalues, one negative (round-off gone wrong)
    const Matrix6d bad_covariance = Q * tiny.asDiagonal() * Q.transpose();
    ASSERT_TRUE(InformationFromCovariance(bad_covariance, floor, &information).ok);
    const Matrix6d scaled = floor_sigma.asDiagonal() * information * floor_sigma.asDiagonal();
    const Vector6d eigenvalues = Eigen::SelfAdjointEigenSolver<Matrix6d>(scaled).eigenvalues();
    EXPECT_LT(eigenvalues.maxCoeff(), 1.0 + 1e-9);  // the clamp is exact up to round-off
    EXPECT_GT(eigenvalues.minCoeff(), 0.0);         // still positive definite: usable as an edge information
    PoseGraph graph;
    ASSERT_TRUE(graph.AddNode(0, Pose3::Identity()).ok);
    ASSERT_TRUE(graph.AddNode(1, Pose3::Identity()).ok);
    EXPECT_TRUE(graph.AddEdge({0, 1, Pose3::Identity(), information, EdgeKind::kLoop}).ok);
  }
  Matrix6d information;
  Matrix6d nan_covariance = Matrix6d::Identity();
  nan_covariance(1, 1) = std::nan("");
  EXPECT_FALSE(InformationFromCovariance(nan_covariance, floor, &information).ok);
  InformationFloor bad_floor;
  bad_floor.min_sigma_rotation_rad = 0.0;
  const Status bad = InformationFromCovariance(Matrix6d::Identity(), bad_floor, &information);
  EXPECT_NE(bad.message.find("min_sigma_rotation_rad"), std::string::npos) << bad.message;
}

TEST(PoseGraphHelpers, InformationInToFrameKeepsTheChi2) {
  RandomStream rng(5, "graph-frames");
  double worst = 0.0, unconverted_min = 1e300;
  for (int trial = 0; trial < 20; ++trial) {
    const Pose3 T_meas = RandomPose(rng, 5.0);
    const Matrix6d Q = RandomRotation6(rng);
    const Matrix6d info_from = Q * (Vector6d() << 1, 4, 9, 100, 400, 900).finished().asDiagonal() * Q.transpose();
    // A displacement xi in the `from` convention: T_est = (t + dt, Exp(dtheta) R).
    const Vector6d xi = RandomVector6(rng, 0.3, 0.2);
    Pose3 T_est = T_meas;
    T_est.translation() += xi.head<3>();
    T_est.linear() = ExpSO3(xi.tail<3>()) * T_meas.linear();
    const Vector6d e = RelativePoseError(Pose3::Identity(), T_est, T_meas);
    const double chi2_from = xi.dot(info_from * xi);
    const Matrix6d info_to = InformationInToFrame(info_from, T_meas);
    // The map xi = blockdiag(R, R) e is exact (not a linearisation), so the chi2 agree to round-off (~1e-15
    // relative, through LogSO3's ~1e-12 on angles up to 0.6 rad): bound 1e-9.
    worst = std::max(worst, std::abs(e.dot(info_to * e) - chi2_from) / chi2_from);
    unconverted_min = std::min(unconverted_min, std::abs(e.dot(info_from * e) - chi2_from) / chi2_from);
  }
  std::printf("InformationInToFrame: worst relative chi2 error %.1e; unconverted information: >= %.2f\n", worst,
              unconverted_min);
  EXPECT_LT(worst, 1e-9);
  // Using the `from`-frame information without the conversion changes the chi2 by >= 1 % (measured), so the
  // check above can fail.
  EXPECT_GT(unconverted_min, 1e-3);
}

// ----------------------------------------------------------------------------------------- trajectory correction

/// The odometry trajectory: a climbing, turning curve.
Pose3 CurvePose(double t_s) {
  Pose3 T = RotZ(0.2 * t_s);
  T.translation() = Eigen::Vector3d(t_s, 0.1 * t_s * t_s, 0.05 * t_s);
  return T;
}

/// Keyframes at t = 0, 1, ..., 10 s and dense poses every 0.1 s from -0.5 to 10.5 s (exact at keyframe times).
std::vector<KeyframeCorrection> CurveKeyframes() {
  std::vector<KeyframeCorrection> kfs;
  for (int k = 0; k <= 10; ++k) kfs.push_back({static_cast<double>(k), CurvePose(k), CurvePose(k)});
  return kfs;
}

Trajectory DenseCurve() {
  Trajectory dense;
  for (int k = 0; k <= 110; ++k) {
    const double t_s = (k - 5) / 10.0;
    dense.push_back({t_s, CurvePose(t_s)});
  }
  return dense;
}

double MaxPoseDifference(const Pose3& a, const Pose3& b) { return (a.matrix() - b.matrix()).cwiseAbs().maxCoeff(); }

TEST(PoseGraphHelpers, CorrectTrajectoryZeroAndOffsetCorrections) {
  const Trajectory original = DenseCurve();
  for (const CorrectionMode mode : {CorrectionMode::kPrecedingKeyframe, CorrectionMode::kInterpolate}) {
    Trajectory dense = original;
    ASSERT_TRUE(CorrectTrajectory(CurveKeyframes(), mode, &dense).ok);
    for (size_t i = 0; i < dense.size(); ++i) {
      EXPECT_TRUE(dense[i].T_ref_body.matrix() == original[i].T_ref_body.matrix()) << "pose " << i;  // bit for bit
    }
    std::vector<KeyframeCorrection> kfs = CurveKeyframes();
    const Eigen::Vector3d offset(1.5, -2.0, 0.3);
    for (KeyframeCorrection& kf : kfs) kf.T_world_kf_new.translation() += offset;
    dense = original;
    ASSERT_TRUE(CorrectTrajectory(kfs, mode, &dense).ok);
    double worst = 0.0;
    for (size_t i = 0; i < dense.size(); ++i) {
      Pose3 expected = original[i].T_ref_body;
      expected.translation() += offset;
      worst = std::max(worst, MaxPoseDifference(dense[i].T_ref_body, expected));
    }
    // Composing poses of |t| <= 12 m costs ~1e-14 m of round-off: "exactly" means 1e-12.
    EXPECT_LT(worst, 1e-12) << "mode " << static_cast<int>(mode);
  }
}

TEST(PoseGraphHelpers, CorrectTrajectoryFollowsTheKeyframes) {
  const Trajectory original = DenseCurve();
  std::vector<KeyframeCorrection> kfs = CurveKeyframes();
  // Keyframe k moves by a right perturbation growing with k: 0.1 k m sideways, 0.01 k rad of yaw.
  for (int k = 0; k <= 10; ++k) {
    const Vector6d delta = (Vector6d() << 0, 0.1 * k, 0, 0, 0, 0.01 * k).finished();
    kfs[k].T_world_kf_new = RightPerturb(kfs[k].T_world_kf_old, delta);
  }
  Trajectory preceding = original, interpolated = original;
  ASSERT_TRUE(CorrectTrajectory(kfs, CorrectionMode::kPrecedingKeyframe, &preceding).ok);
  ASSERT_TRUE(CorrectTrajectory(kfs, CorrectionMode::kInterpolate, &interpolated).ok);
  double rigid = 0.0, at_keyframes = 0.0, preceding_jump = 0.0, interpolated_jump = 0.0;
  for (size_t i = 0; i < original.size(); ++i) {
    const double t_s = original[i].t_s;
    const int k = std::clamp(static_cast<int>(std::floor(t_s)), 0, 10);  // the preceding keyframe (or the first)
    // Preceding mode: each pose keeps its relative pose to its keyframe.
    rigid = std::max(rigid, MaxPoseDifference(kfs[k].T_world_kf_new.inverse() * preceding[i].T_ref_body,
                                              kfs[k].T_world_kf_old.inverse() * original[i].T_ref_body));
    if (t_s == std::floor(t_s) && t_s >= 0.0 && t_s <= 10.0) {  // both modes land on the keyframe's new pose
      at_keyframes = std::max(at_keyframes, MaxPoseDifference(interpolated[i].T_ref_body, kfs[k].T_world_kf_new));
      at_keyframes = std::max(at_keyframes, MaxPoseDifference(preceding[i].T_ref_body, kfs[k].T_world_kf_new));
    }
    if (i == 0) continue;
    // How much the correction changes the step between consecutive poses (0 for a rigid, smooth correction).
    const auto step = [&](const Trajectory& tr) {
      return tr[i].T_ref_body.translation() - tr[i - 1].T_ref_body.translation();
    };
    preceding_jump = std::max(preceding_jump, (step(preceding) - step(original)).norm());
    interpolated_jump = std::max(interpolated_jump, (step(interpolated) - step(original)).norm());
  }
  std::printf("correction: rigid %.1e, at keyframes %.1e; step change: preceding %.3f m, interpolated %.3f m\n",
              rigid, at_keyframes, preceding_jump, interpolated_jump);
  EXPECT_LT(rigid, 1e-12);         // round-off of poses <= 12 m
  EXPECT_LT(at_keyframes, 1e-12);
  // Consecutive keyframes' corrections differ by 0.1 m + 0.01 rad, and the sideways offset (up to 1 m) turns with
  // the 0.2 rad heading change per keyframe: up to ~0.3 m at t = 10 s. Preceding mode jumps by that at keyframe
  // times (measured 0.31 m); interpolation spreads it over the ten 0.1 s steps (measured 0.023 m). Bounds 2x off.
  EXPECT_GT(preceding_jump, 0.15);
  EXPECT_LT(interpolated_jump, 0.05);
}

TEST(PoseGraphHelpers, CorrectTrajectoryRejectsBadInput) {
  const Trajectory original = DenseCurve();
  Trajectory dense = original;
  EXPECT_NE(CorrectTrajectory({}, CorrectionMode::kInterpolate, &dense).message.find("no keyframes"),
            std::string::npos);
  std::vector<KeyframeCorrection> kfs = CurveKeyframes();
  std::swap(kfs[1].t_s, kfs[2].t_s);
  for (KeyframeCorrection& kf : kfs) kf.T_world_kf_new.translation().x() += 1.0;
  const Status unsorted = CorrectTrajectory(kfs, CorrectionMode::kInterpolate, &dense);
  EXPECT_FALSE(unsorted.ok);
  EXPECT_NE(unsorted.message.find("keyframe 2"), std::string::npos) << unsorted.message;
  dense[3].t_s = std::nan("");
  EXPECT_FALSE(CorrectTrajectory(CurveKeyframes(), CorrectionMode::kInterpolate, &dense).ok);
  for (size_t i = 0; i < dense.size(); ++i) {  // failures leave the trajectory untouched
    EXPECT_TRUE(dense[i].T_ref_body.matrix() == original[i].T_ref_body.matrix());
  }
}

}  // namespace
}  // namespace rotolidar::graph
