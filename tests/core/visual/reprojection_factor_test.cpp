// Reprojection factors with inverse-depth landmarks: analytic Jacobians against Ceres' numeric differentiation
// (pose manifold), zero residual at the truth, whitening, small Ceres problems on noise-free data (depths, a
// pose, the extrinsic), and the documented behaviour behind the camera / at infinity.
#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include <ceres/ceres.h>
#include <ceres/gradient_checker.h>
#include <gtest/gtest.h>

#include "core/util/rng.hpp"
#include "core/visual/reprojection_factor.hpp"
#include "tests/common/jacobian_check.hpp"

namespace rotolidar {
namespace {

constexpr double kFocalPx = 462.0, kSigmaPx = 1.5;

Eigen::Vector3d RandomVector(RandomStream& rng, double sigma) {
  return {rng.Normal(0.0, sigma), rng.Normal(0.0, sigma), rng.Normal(0.0, sigma)};
}

Pose3 RandomPose(RandomStream& rng, double sigma_t_m) {
  const Eigen::Vector3d t = RandomVector(rng, sigma_t_m);  // drawn first: argument order is the compiler's choice
  return MakePose(t, Eigen::Quaterniond{rng.Normal(), rng.Normal(), rng.Normal(), rng.Normal()});
}

Eigen::Vector2d Pi(const Eigen::Vector3d& p) { return p.head<2>() / p.z(); }

/// Two camera frames 1..5 m apart (relative rotation ~0.15 rad), a random extrinsic, and a landmark 2..30 m in
/// front of the anchor camera that camera j sees at depth > 1 m within |u| < 1.5.
struct Scene {
  Pose3 T_ic, T_w_ca, T_w_cj, T_wa, T_wj;
  Eigen::Vector3d p_world;
  Eigen::Vector2d u_a, u_j;  ///< true normalised observations
  double rho = 0.0;
};

Scene RandomScene(RandomStream& rng) {
  Scene s;
  s.T_ic = RandomPose(rng, 0.1);
  s.T_w_ca = RandomPose(rng, 5.0);
  Pose3 T_ca_cj = Pose3::Identity();
  T_ca_cj.translation() = RandomVector(rng, 1.0).normalized() * (1.0 + 4.0 * rng.Uniform());
  T_ca_cj.linear() = ExpSO3(RandomVector(rng, 0.15));
  s.T_w_cj = s.T_w_ca * T_ca_cj;
  s.T_wa = s.T_w_ca * s.T_ic.inverse();
  s.T_wj = s.T_w_cj * s.T_ic.inverse();
  for (;;) {
    const Eigen::Vector3d u{rng.Uniform() * 1.2 - 0.6, rng.Uniform() * 1.2 - 0.6, 1.0};
    s.p_world = s.T_w_ca * (u * (2.0 + 28.0 * rng.Uniform()));
    const Eigen::Vector3d p_cj = s.T_w_cj.inverse() * s.p_world;
    if (p_cj.z() > 1.0 && Pi(p_cj).cwiseAbs().maxCoeff() < 1.5) {
      s.u_j = Pi(p_cj);
      EXPECT_TRUE(AnchorLandmark(s.T_wa, s.T_ic, s.p_world, &s.u_a, &s.rho));
      return s;
    }
  }
}

ReprojectionMeasurement Measure(const Scene& s, const Eigen::Vector2d& u_j) {
  ReprojectionMeasurement m;
  m.anchor_normalized = s.u_a;
  m.normalized = u_j;
  m.sqrt_information = ReprojectionSqrtInformation(kFocalPx, kSigmaPx);
  return m;
}

// Ceres' checker differentiates by Ridders' method from an initial step that is also its minimum absolute step:
// the default 1e-2 is 25 % of a 25 m landmark's rho (0.04 1/m) and its extrapolation then stops ~1 % off; 1e-4 is
// small against every block here.
double JacobianError(const ceres::CostFunction& cost, const std::vector<double*>& blocks) {
  return test_util::JacobianError(cost, blocks, 1e-4);
}

TEST(ReprojectionFactor, JacobiansMatchNumericForAllVariants) {
  RandomStream rng(31, "reprojection_factor_test.jacobians");
  double worst_fixed = 0.0, worst_extrinsic = 0.0, worst_td = 0.0;
  for (int trial = 0; trial < 200; ++trial) {
    const Scene s = RandomScene(rng);
    const Eigen::Vector2d noise{rng.Normal(0.0, 0.01), rng.Normal(0.0, 0.01)};  // a non-zero residual
    const ReprojectionMeasurement m = Measure(s, s.u_j + noise);
    double pose_a[7], pose_j[7], extrinsic[7], rho[1] = {s.rho}, td[1] = {rng.Normal(0.0, 0.01)};
    PackImuPose(s.T_wa, pose_a);
    PackImuPose(s.T_wj, pose_j);
    PackImuPose(s.T_ic, extrinsic);
    worst_fixed = std::max(worst_fixed, JacobianError(ReprojectionFactor(m, s.T_ic), {pose_a, pose_j, rho}));
    worst_extrinsic = std::max(worst_extrinsic,
                               JacobianError(ReprojectionExtrinsicFactor(m), {pose_a, pose_j, rho, extrinsic}));
    FeatureMotion motion;
    motion.anchor_velocity = {rng.Normal(0.0, 0.3), rng.Normal(0.0, 0.3)};
    motion.velocity = {rng.Normal(0.0, 0.3), rng.Normal(0.0, 0.3)};
    motion.anchor_td_s = rng.Normal(0.0, 0.005);
    motion.td_s = rng.Normal(0.0, 0.005);
    worst_td = std::max(worst_td, JacobianError(ReprojectionTimeOffsetFactor(m, motion, s.T_ic),
                                                {pose_a, pose_j, rho, td}));
  }
  std::printf("worst mixed Jacobian error: fixed %.1e, extrinsic %.1e, td %.1e\n", worst_fixed, worst_extrinsic,
              worst_td);
  // Measured over 200 random scenes: 1.1e-10 (fixed), 2.5e-10 (extrinsic), 2.0e-10 (td). Single wrong terms
  // (the t_ic term of dq/drho, the t_j lever of dq/dtheta_j, the t_ic lever of dq/dtheta_ic, the sign of
  // dr/dtd) gave 18, 115, 5.0 and 240.
  EXPECT_LT(worst_fixed, 1e-6);
  EXPECT_LT(worst_extrinsic, 1e-6);
  EXPECT_LT(worst_td, 1e-6);
}

TEST(ReprojectionFactor, ZeroResidualAtTheTruthAndVariantsAgree) {
  RandomStream rng(32, "reprojection_factor_test.truth");
  double worst_r = 0.0, worst_predict = 0.0, worst_variant = 0.0;
  for (int trial = 0; trial < 100; ++trial) {
    const Scene s = RandomScene(rng);
    const ReprojectionMeasurement m = Measure(s, s.u_j);
    double pose_a[7], pose_j[7], extrinsic[7], rho[1] = {s.rho}, r[2], r_ext[2], r_td[2];
    PackImuPose(s.T_wa, pose_a);
    PackImuPose(s.T_wj, pose_j);
    PackImuPose(s.T_ic, extrinsic);
    const double* fixed_params[3] = {pose_a, pose_j, rho};
    ASSERT_TRUE(ReprojectionFactor(m, s.T_ic).Evaluate(fixed_params, r, nullptr));
    worst_r = std::max(worst_r, Eigen::Map<Eigen::Vector2d>(r).norm());
    const double* ext_params[4] = {pose_a, pose_j, rho, extrinsic};
    ASSERT_TRUE(ReprojectionExtrinsicFactor(m).Evaluate(ext_params, r_ext, nullptr));
    // td variant: the stored observations are displaced by (td_true - td_meas) v, which td_true undoes.
    FeatureMotion motion;
    motion.anchor_velocity = {rng.Normal(0.0, 0.3), rng.Normal(0.0, 0.3)};
    motion.velocity = {rng.Normal(0.0, 0.3), rng.Normal(0.0, 0.3)};
    motion.anchor_td_s = rng.Normal(0.0, 0.01);
    motion.td_s = rng.Normal(0.0, 0.01);
    double td[1] = {0.004};
    ReprojectionMeasurement m_td = m;
    m_td.anchor_normalized += (td[0] - motion.anchor_td_s) * motion.anchor_velocity;
    m_td.normalized += (td[0] - motion.td_s) * motion.velocity;
    const double* td_params[4] = {pose_a, pose_j, rho, td};
    ASSERT_TRUE(ReprojectionTimeOffsetFactor(m_td, motion, s.T_ic).Evaluate(td_params, r_td, nullptr));
    worst_r = std::max({worst_r, Eigen::Map<Eigen::Vector2d>(r_ext).norm(), Eigen::Map<Eigen::Vector2d>(r_td).norm()});
    worst_predict = std::max(worst_predict, (PredictNormalized(s.T_wa, s.T_wj, s.T_ic, s.u_a, s.rho) - s.u_j).norm());
    // Off the truth, the extrinsic variant at the same extrinsic is the fixed one.
    pose_j[0] += 0.3;
    ASSERT_TRUE(ReprojectionFactor(m, s.T_ic).Evaluate(fixed_params, r, nullptr));
    ASSERT_TRUE(ReprojectionExtrinsicFactor(m).Evaluate(ext_params, r_ext, nullptr));
    const Eigen::Vector2d difference = Eigen::Map<Eigen::Vector2d>(r) - Eigen::Map<Eigen::Vector2d>(r_ext);
    worst_variant = std::max(worst_variant, difference.norm());
    EXPECT_GT(Eigen::Map<Eigen::Vector2d>(r).norm(), 1e-3);
  }
  std::printf("at the truth: |r| <= %.1e (whitened), |predict - u_j| <= %.1e; variants differ by %.1e\n", worst_r,
              worst_predict, worst_variant);
  EXPECT_LT(worst_r, 1e-9);
  EXPECT_LT(worst_predict, 1e-12);
  EXPECT_LT(worst_variant, 1e-12);
}

TEST(ReprojectionFactor, WhiteningScalesWithFocalOverSigma) {
  RandomStream rng(33, "reprojection_factor_test.whitening");
  const Scene s = RandomScene(rng);
  const double offset_px = 2.0;  // the observation moved by 2 px along x
  ReprojectionMeasurement m = Measure(s, s.u_j + Eigen::Vector2d(offset_px / kFocalPx, 0.0));
  double pose_a[7], pose_j[7], rho[1] = {s.rho}, r1[2], r2[2];
  PackImuPose(s.T_wa, pose_a);
  PackImuPose(s.T_wj, pose_j);
  const double* params[3] = {pose_a, pose_j, rho};
  ASSERT_TRUE(ReprojectionFactor(m, s.T_ic).Evaluate(params, r1, nullptr));
  // |r| = offset / sigma: the whitened residual counts pixel errors in sigmas.
  EXPECT_NEAR(r1[0], -offset_px / kSigmaPx, 1e-9);
  EXPECT_NEAR(r1[1], 0.0, 1e-9);
  m.sqrt_information = ReprojectionSqrtInformation(2.0 * kFocalPx, 0.5 * kSigmaPx);
  ASSERT_TRUE(ReprojectionFactor(m, s.T_ic).Evaluate(params, r2, nullptr));
  EXPECT_NEAR(r2[0], 4.0 * r1[0], 1e-9);
  const Eigen::Vector2d error = ReprojectionFactor(m, s.T_ic).Error(pose_a, pose_j, rho);
  EXPECT_NEAR(r2[0], 4.0 * kFocalPx / kSigmaPx * error.x(), 1e-9);
  CameraIntrinsics camera;
  camera.fx_px = 400.0;
  camera.fy_px = 500.0;
  const Eigen::Matrix2d S = ReprojectionSqrtInformation(camera, 2.0);
  EXPECT_EQ(S(0, 0), 200.0);
  EXPECT_EQ(S(1, 1), 250.0);
  EXPECT_EQ(S(0, 1), 0.0);
}

/// Solver options for noise-free problems: run Gauss-Newton down to round-off.
ceres::Solver::Options TightOptions() {
  ceres::Solver::Options options;
  options.max_num_iterations = 50;
  options.function_tolerance = 1e-20;
  options.gradient_tolerance = 1e-20;
  options.parameter_tolerance = 1e-16;
  return options;
}

/// Three frames 1.5 m apart, sideways to the camera's view, turning by up to 0.2 rad, and landmarks 3..25 m in
/// front of frame 0.
struct Window {
  Pose3 T_ic = MakePose(Eigen::Vector3d(0.05, -0.02, 0.08),
                        Eigen::Quaterniond(Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitX())));
  std::vector<Pose3> T_w_imu;
  std::vector<Eigen::Vector3d> points;
};

Window MakeWindow(RandomStream& rng, int num_points) {
  Window w;
  // Rotations about different axes: with a single rotation axis the extrinsic translation along it would be
  // unobservable (it cancels in T_ic^-1 T_a_j T_ic).
  const Eigen::Vector3d rotation[3] = {{0.0, 0.0, 0.0}, {0.02, 0.05, 0.1}, {0.12, -0.04, 0.15}};
  for (int k = 0; k < 3; ++k) {
    Pose3 T = Pose3::Identity();
    T.translation() = Eigen::Vector3d(1.5 * k, 0.2 * k, 0.1 * k);
    T.linear() = ExpSO3(rotation[k]);
    w.T_w_imu.push_back(T);
  }
  const Pose3 T_w_c0 = w.T_w_imu[0] * w.T_ic;
  for (int i = 0; i < num_points; ++i) {
    const Eigen::Vector3d u{rng.Uniform() - 0.5, rng.Uniform() * 0.8 - 0.4, 1.0};
    w.points.push_back(T_w_c0 * (u * (3.0 + 22.0 * rng.Uniform())));
  }
  return w;
}

ReprojectionMeasurement MeasureIn(const Window& w, int point, int frame, Eigen::Vector2d u_a) {
  ReprojectionMeasurement m;
  m.anchor_normalized = u_a;
  m.normalized = Pi((w.T_w_imu[frame] * w.T_ic).inverse() * w.points[point]);
  m.sqrt_information = ReprojectionSqrtInformation(kFocalPx, kSigmaPx);
  return m;
}

TEST(ReprojectionFactor, CeresRecoversInverseDepthsWithFixedPoses) {
  RandomStream rng(34, "reprojection_factor_test.depths");
  const Window w = MakeWindow(rng, 12);
  std::vector<std::vector<double>> poses(3, std::vector<double>(7));
  for (int k = 0; k < 3; ++k) PackImuPose(w.T_w_imu[k], poses[k].data());
  std::vector<double> rho(w.points.size()), rho_true(w.points.size());
  ceres::Problem problem;
  for (size_t i = 0; i < w.points.size(); ++i) {
    Eigen::Vector2d u_a;
    ASSERT_TRUE(AnchorLandmark(w.T_w_imu[0], w.T_ic, w.points[i], &u_a, &rho_true[i]));
    rho[i] = rho_true[i] * std::exp(rng.Normal(0.0, 0.3));  // ~30 % depth error
    for (int k = 1; k < 3; ++k) {
      problem.AddResidualBlock(new ReprojectionFactor(MeasureIn(w, i, k, u_a), w.T_ic), nullptr,
                               poses[0].data(), poses[k].data(), &rho[i]);
    }
  }
  for (auto& p : poses) problem.SetParameterBlockConstant(p.data());
  ceres::Solver::Summary summary;
  ceres::Solve(TightOptions(), &problem, &summary);
  EXPECT_TRUE(summary.IsSolutionUsable()) << summary.BriefReport();
  double worst = 0.0;
  for (size_t i = 0; i < rho.size(); ++i) worst = std::max(worst, std::abs(rho[i] / rho_true[i] - 1.0));
  std::printf("depths: worst relative error %.1e after %d iterations\n", worst,
              static_cast<int>(summary.iterations.size()));
  EXPECT_LT(worst, 1e-6);
}

TEST(ReprojectionFactor, CeresPullsAPerturbedPoseBack) {
  RandomStream rng(35, "reprojection_factor_test.pose");
  const Window w = MakeWindow(rng, 36);
  double pose0[7], pose1[7];
  PackImuPose(w.T_w_imu[0], pose0);
  Pose3 init = w.T_w_imu[1];
  init.translation() += Eigen::Vector3d(0.2, -0.15, 0.1);
  init.linear() = ExpSO3(Eigen::Vector3d(0.03, -0.05, 0.04)) * init.linear();
  PackImuPose(init, pose1);
  std::vector<double> rho(w.points.size());
  ceres::Problem problem;
  for (size_t i = 0; i < w.points.size(); ++i) {
    Eigen::Vector2d u_a;
    ASSERT_TRUE(AnchorLandmark(w.T_w_imu[0], w.T_ic, w.points[i], &u_a, &rho[i]));
    problem.AddResidualBlock(new ReprojectionFactor(MeasureIn(w, i, 1, u_a), w.T_ic), nullptr, pose0, pose1,
                             &rho[i]);
    problem.SetParameterBlockConstant(&rho[i]);  // known depths (e.g. from the LiDAR) fix the scale
  }
  problem.SetManifold(pose0, MakeImuPoseManifold().release());
  problem.SetManifold(pose1, MakeImuPoseManifold().release());
  problem.SetParameterBlockConstant(pose0);
  ceres::Solver::Summary summary;
  ceres::Solve(TightOptions(), &problem, &summary);
  EXPECT_TRUE(summary.IsSolutionUsable()) << summary.BriefReport();
  const Pose3 T = UnpackImuPose(pose1);
  const double pos_err = (T.translation() - w.T_w_imu[1].translation()).norm();
  const double rot_err = LogSO3(T.linear().transpose() * w.T_w_imu[1].linear()).norm();
  std::printf("pose: position error %.1e m, rotation error %.1e rad\n", pos_err, rot_err);
  EXPECT_LT(pos_err, 1e-6);
  EXPECT_LT(rot_err, 1e-8);
}

TEST(ReprojectionExtrinsicFactor, CeresRecoversAPerturbedExtrinsic) {
  RandomStream rng(36, "reprojection_factor_test.extrinsic");
  const Window w = MakeWindow(rng, 36);
  std::vector<std::vector<double>> poses(3, std::vector<double>(7));
  for (int k = 0; k < 3; ++k) PackImuPose(w.T_w_imu[k], poses[k].data());
  Pose3 init = w.T_ic;
  init.translation() += Eigen::Vector3d(0.02, -0.01, 0.015);
  init.linear() = ExpSO3(Eigen::Vector3d(0.01, 0.02, -0.015)) * init.linear();
  double extrinsic[7];
  PackImuPose(init, extrinsic);
  std::vector<double> rho(w.points.size());
  ceres::Problem problem;
  for (size_t i = 0; i < w.points.size(); ++i) {
    Eigen::Vector2d u_a;
    ASSERT_TRUE(AnchorLandmark(w.T_w_imu[0], w.T_ic, w.points[i], &u_a, &rho[i]));
    for (int k = 1; k < 3; ++k) {
      problem.AddResidualBlock(new ReprojectionExtrinsicFactor(MeasureIn(w, i, k, u_a)), nullptr,
                               poses[0].data(), poses[k].data(), &rho[i], extrinsic);
    }
    problem.SetParameterBlockConstant(&rho[i]);
  }
  for (auto& p : poses) problem.SetParameterBlockConstant(p.data());
  problem.SetManifold(extrinsic, MakeImuPoseManifold().release());
  ceres::Solver::Summary summary;
  ceres::Solve(TightOptions(), &problem, &summary);
  EXPECT_TRUE(summary.IsSolutionUsable()) << summary.BriefReport();
  const Pose3 T = UnpackImuPose(extrinsic);
  const double pos_err = (T.translation() - w.T_ic.translation()).norm();
  const double rot_err = LogSO3(T.linear().transpose() * w.T_ic.linear()).norm();
  std::printf("extrinsic: position error %.1e m, rotation error %.1e rad\n", pos_err, rot_err);
  EXPECT_LT(pos_err, 1e-6);
  EXPECT_LT(rot_err, 1e-8);
}

TEST(ReprojectionFactor, BehindCameraAndInfinityStayFiniteAndAreGated) {
  RandomStream rng(37, "reprojection_factor_test.degenerate");
  const Scene s = RandomScene(rng);
  const ReprojectionMeasurement m = Measure(s, s.u_j);
  const ReprojectionFactor factor(m, s.T_ic);
  double pose_a[7], pose_j[7], rho[1], r[2], J_a[14], J_j[14], J_rho[2];
  double* jacobians[3] = {J_a, J_j, J_rho};
  PackImuPose(s.T_wa, pose_a);
  PackImuPose(s.T_wj, pose_j);
  const double* params[3] = {pose_a, pose_j, rho};
  auto finite = [&]() {
    return Eigen::Map<Eigen::Vector2d>(r).allFinite() && Eigen::Map<Eigen::Matrix<double, 14, 1>>(J_a).allFinite() &&
           Eigen::Map<Eigen::Matrix<double, 14, 1>>(J_j).allFinite() && Eigen::Map<Eigen::Vector2d>(J_rho).allFinite();
  };
  EXPECT_TRUE(LandmarkInFront(s.T_wa, s.T_wj, s.T_ic, s.u_a, s.rho));
  EXPECT_TRUE(LandmarkInFront(s.T_wa, s.T_wa, s.T_ic, s.u_a, s.rho));
  // Negative inverse depth: the mirror point; Evaluate stays valid, the gate rejects it.
  rho[0] = -s.rho;
  EXPECT_TRUE(factor.Evaluate(params, r, jacobians));
  EXPECT_TRUE(finite());
  EXPECT_FALSE(LandmarkInFront(s.T_wa, s.T_wj, s.T_ic, s.u_a, -s.rho));
  // rho = 0 (a point at infinity): finite, the rotation-only projection, translations have no effect.
  rho[0] = 0.0;
  EXPECT_TRUE(factor.Evaluate(params, r, jacobians));
  EXPECT_TRUE(finite());
  const Eigen::Vector3d dir = (s.T_w_cj.linear().transpose() * s.T_w_ca.linear()) * s.u_a.homogeneous();
  EXPECT_LT((factor.Error(pose_a, pose_j, rho) - (Pi(dir) - s.u_j)).norm(), 1e-12);
  using PoseJacobian = Eigen::Matrix<double, 2, 7, Eigen::RowMajor>;
  EXPECT_EQ(Eigen::Map<PoseJacobian>(J_j).leftCols<3>().norm(), 0.0);
  EXPECT_FALSE(LandmarkInFront(s.T_wa, s.T_wj, s.T_ic, s.u_a, 0.0));
  EXPECT_LT(JacobianError(factor, {pose_a, pose_j, rho}), 1e-6);
  // A point in camera j's focal plane (Z_cj = 0): the clamp keeps everything finite.
  const Eigen::Vector3d p_plane = s.T_w_cj * Eigen::Vector3d(1.0, 0.5, 0.0);
  ReprojectionMeasurement m_plane = m;
  m_plane.anchor_normalized = (s.T_w_ca.inverse() * p_plane).hnormalized();
  rho[0] = 1.0 / (s.T_w_ca.inverse() * p_plane).z();
  EXPECT_TRUE(ReprojectionFactor(m_plane, s.T_ic).Evaluate(params, r, jacobians));
  EXPECT_TRUE(finite());
  EXPECT_FALSE(LandmarkInFront(s.T_wa, s.T_wj, s.T_ic, m_plane.anchor_normalized, rho[0]));
  // Behind camera j: camera j turned around to look away from the landmark.
  Pose3 T_w_cj_back = s.T_w_cj;
  T_w_cj_back.linear() = s.T_w_cj.linear() * Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const Pose3 T_wj_back = T_w_cj_back * s.T_ic.inverse();
  PackImuPose(T_wj_back, pose_j);
  rho[0] = s.rho;
  EXPECT_TRUE(factor.Evaluate(params, r, jacobians));
  EXPECT_TRUE(finite());
  EXPECT_FALSE(LandmarkInFront(s.T_wa, T_wj_back, s.T_ic, s.u_a, s.rho));
  // The minimum depth gate: the landmark is at Z_cj > 1 m by construction.
  const double z_j = (s.T_w_cj.inverse() * s.p_world).z();
  EXPECT_TRUE(LandmarkInFront(s.T_wa, s.T_wj, s.T_ic, s.u_a, s.rho, 0.99 * z_j));
  EXPECT_FALSE(LandmarkInFront(s.T_wa, s.T_wj, s.T_ic, s.u_a, s.rho, 1.01 * z_j));
}

}  // namespace
}  // namespace rotolidar
