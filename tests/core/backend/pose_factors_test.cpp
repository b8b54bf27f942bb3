// Pose factors: analytic Jacobians against Ceres' numeric differentiation (with the pose manifold), the base->imu
// information transform, degenerate information, and Schur-complement marginalisation against the full problem.
#include <algorithm>
#include <cstdio>
#include <cmath>
#include <vector>

#include <ceres/ceres.h>
#include <ceres/gradient_checker.h>
#include <gtest/gtest.h>

#include "core/backend/pose_factors.hpp"
#include "core/util/rng.hpp"
#include "tests/common/jacobian_check.hpp"

namespace rotolidar {
namespace {

const Eigen::Vector3d kGravity(0.0, 0.0, -9.81);

Eigen::Vector3d RandomVector(RandomStream& rng, double sigma) {
  return {rng.Normal(0.0, sigma), rng.Normal(0.0, sigma), rng.Normal(0.0, sigma)};
}

Pose3 RandomPose(RandomStream& rng, double sigma_t_m) {
  const Eigen::Vector3d t = RandomVector(rng, sigma_t_m);  // drawn first: argument order is the compiler's choice
  return MakePose(t, Eigen::Quaterniond{rng.Normal(), rng.Normal(), rng.Normal(), rng.Normal()});
}

/// T (+) xi = (t + dt, Exp(dtheta) R) in the world-left tangent [dt; dtheta].
Pose3 Perturb(const Pose3& T, const Vector6d& xi) {
  Pose3 out = T;
  out.translation() += xi.head<3>();
  out.linear() = ExpSO3(xi.tail<3>()) * T.linear();
  return out;
}

Vector6d RandomVector6(RandomStream& rng, double sigma) {
  return (Vector6d() << RandomVector(rng, sigma), RandomVector(rng, sigma)).finished();
}

/// A random symmetric positive definite information (condition ~1e2) of the given scale.
Matrix6d RandomInformation(RandomStream& rng, double scale) {
  Eigen::Matrix<double, 6, 6> M;
  for (int r = 0; r < 6; ++r)
    for (int c = 0; c < 6; ++c) M(r, c) = rng.Normal();
  return scale * (M * M.transpose() + 0.1 * Matrix6d::Identity());
}

using test_util::JacobianError;

TEST(PoseFactors, LidarAndRelativeJacobiansMatchNumeric) {
  RandomStream rng(21, "pose_factors_test.jacobians");
  double worst = 0.0;
  for (int trial = 0; trial < 10; ++trial) {
    LidarPoseMeasurement m;
    m.T_world_imu = RandomPose(rng, 3.0);
    m.information = RandomInformation(rng, 1.0);
    double pose_i[7], pose_j[7];
    PackImuPose(Perturb(m.T_world_imu, RandomVector6(rng, 0.3)), pose_i);
    PackImuPose(RandomPose(rng, 3.0), pose_j);
    const LidarPoseFactor lidar(m);
    EXPECT_GT(lidar.Error(pose_i).tail<3>().norm(), 1e-3);  // away from the identity, where Jl^-1 = I
    worst = std::max(worst, JacobianError(lidar, {pose_i}));
    // A measurement near the blocks' relative pose (rotation errors ~0.5 rad, far from Log's cut at pi).
    const Pose3 T_i_j = UnpackImuPose(pose_i).inverse() * UnpackImuPose(pose_j);
    const RelativePoseFactor relative{Perturb(T_i_j, RandomVector6(rng, 0.3)), RandomInformation(rng, 1.0)};
    EXPECT_GT(relative.Error(pose_i, pose_j).tail<3>().norm(), 1e-3);
    worst = std::max(worst, JacobianError(relative, {pose_i, pose_j}));
  }
  // Measured over 10 random poses: 6.3e-13 (the residuals are smooth, so Ceres' central differences are very
  // accurate); a wrong term is O(0.1..1) (a sign error in the relative factor gave 4.7).
  EXPECT_LT(worst, 1e-8);
}

TEST(PoseFactors, LinearizedPriorJacobiansMatchNumeric) {
  RandomStream rng(22, "pose_factors_test.prior");
  double worst = 0.0;
  for (int trial = 0; trial < 5; ++trial) {
    double pose[7], vec[4];
    const Pose3 T0 = RandomPose(rng, 2.0);
    PackImuPose(Perturb(T0, RandomVector6(rng, 0.4)), pose);
    Eigen::VectorXd x0_pose(7), x0_vec(4);
    PackImuPose(T0, x0_pose.data());
    for (int k = 0; k < 4; ++k) {
      x0_vec(k) = rng.Normal();
      vec[k] = x0_vec(k) + rng.Normal(0.0, 0.3);
    }
    Eigen::MatrixXd J(8, 10);
    for (int r = 0; r < 8; ++r)
      for (int c = 0; c < 10; ++c) J(r, c) = rng.Normal();
    Eigen::VectorXd r0(8);
    for (int r = 0; r < 8; ++r) r0(r) = rng.Normal();
    const LinearizedPriorFactor prior({{pose, BlockKind::kPose, 7}, {vec, BlockKind::kVector, 4}},
                                      {x0_pose, x0_vec}, J, r0);
    worst = std::max(worst, JacobianError(prior, {pose, vec}));
  }
  // Measured 8.6e-14 over 5 random priors.
  EXPECT_LT(worst, 1e-8);
}

TEST(PoseFactors, BaseToImuConversionPreservesTheQuadraticForm) {
  RandomStream rng(23, "pose_factors_test.extrinsic");
  double worst_rel = 0.0;
  std::vector<double> naive_rel;
  for (int trial = 0; trial < 10; ++trial) {
    const Pose3 T_world_base = RandomPose(rng, 5.0), T_base_imu = RandomPose(rng, 0.3);
    const Matrix6d info_base = RandomInformation(rng, 100.0);
    const LidarPoseMeasurement m = LidarMeasurementInImuFrame(T_world_base, info_base, T_base_imu);
    EXPECT_LT((m.T_world_imu.matrix() - (T_world_base * T_base_imu).matrix()).cwiseAbs().maxCoeff(), 1e-12);
    // A base-pose error xi_b must cost the same as the imu-pose error it causes (to second order in |xi_b|).
    const Vector6d xi_b = RandomVector6(rng, 1e-4);
    double pose[7];
    PackImuPose(Perturb(T_world_base, xi_b) * T_base_imu, pose);
    const Vector6d e_imu = LidarPoseFactor(m).Error(pose);
    const double cost_base = xi_b.dot(info_base * xi_b), cost_imu = e_imu.dot(m.information * e_imu);
    worst_rel = std::max(worst_rel, std::abs(cost_imu - cost_base) / cost_base);
    // Reusing the base information unchanged (ignoring the lever arm) is visibly wrong.
    naive_rel.push_back(std::abs(e_imu.dot(info_base * e_imu) - cost_base) / cost_base);
  }
  // Measured 7.0e-5 (second-order terms at |xi| ~ 1e-4); ignoring the lever arm errs by >= 5.1e-2
  // (measured minimum over the 10 trials).
  std::sort(naive_rel.begin(), naive_rel.end());
  const double naive_median = 0.5 * (naive_rel[4] + naive_rel[5]);
  std::printf("[measured] conversion %.1e, ignoring the lever arm: median %.1e\n", worst_rel, naive_median);
  // Measured over seeds 1-11: the conversion errs by at most 2.1e-4 (second-order terms at |xi| ~ 1e-4); ignoring
  // the lever arm errs by a median of 5.7e-2 to 2.3e-1 (one trial in ten can come close by chance: 1.6e-3).
  EXPECT_LT(worst_rel, 1e-3);
  EXPECT_GT(naive_median, 2e-2);
}

TEST(PoseFactors, DegenerateDirectionCarriesNoInformation) {
  RandomStream rng(24, "pose_factors_test.degenerate");
  const Matrix6d H = RandomInformation(rng, 50.0);
  Vector6d d = Vector6d::Zero();
  d << 1.0, 0.5, 0.0, 0.0, 0.0, 0.2;
  d.normalize();
  const Matrix6d P = Matrix6d::Identity() - d * d.transpose();  // drops d (an orthogonal projection here)
  const Matrix6d info = InformationFromRegistration(H, 0.05, P);
  EXPECT_LT((info * d).norm(), 1e-9 * info.norm());
  Vector6d u = Vector6d::Zero();
  u << 0.0, 0.0, 1.0, 0.0, 0.0, 0.0;  // orthogonal to d: keeps H's information / sigma^2
  EXPECT_NEAR(u.dot(info * u), u.dot(H * u) / 0.0025, 1e-9 * u.dot(H * u) / 0.0025);
  // The factor's residual does not see a move along d.
  LidarPoseMeasurement m;
  m.T_world_imu = RandomPose(rng, 1.0);
  m.information = info;
  double moved[7], at[7];
  PackImuPose(m.T_world_imu, at);
  PackImuPose(Perturb(m.T_world_imu, 0.7 * d), moved);
  const LidarPoseFactor factor(m);
  Vector6d r_at, r_moved;
  const double* p_at[1] = {at};
  const double* p_moved[1] = {moved};
  factor.Evaluate(p_at, r_at.data(), nullptr);
  factor.Evaluate(p_moved, r_moved.data(), nullptr);
  // With R_meas = R the rotation error Log(Exp(dtheta)) = dtheta is exact, so the error is exactly 0.7 d and its
  // whitened residual vanishes to round-off (a non-degenerate direction of the same size gives ~1e2).
  EXPECT_LT(r_moved.norm(), 1e-6);
  EXPECT_LT(r_at.norm(), 1e-12);
}

/// Two IMU states with LiDAR factors on both poses, a Gaussian prior on speed-bias 0 and one ImuFactor between.
struct TwoStateProblem {
  double pose0[7], sb0[9], pose1[7], sb1[9];
  std::unique_ptr<LidarPoseFactor> lidar0, lidar1;
  std::unique_ptr<LinearizedPriorFactor> prior_sb0;
  std::unique_ptr<ImuFactor> imu;

  TwoStateProblem(RandomStream& rng, const ImuNoise& noise) {
    PreintegratedImu pre(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), noise);
    for (int k = 0; k < 20; ++k) {
      const Eigen::Vector3d gyro_radps = RandomVector(rng, 0.5), accel_mps2 = -kGravity + RandomVector(rng, 1.0);
      EXPECT_TRUE(pre.Integrate(gyro_radps, accel_mps2, 0.005).ok);
    }
    NavState s0;
    s0.R_world_imu = RandomPose(rng, 1.0).linear();
    s0.v_world_mps = RandomVector(rng, 1.0);
    const NavState s1 = pre.Predict(s0, kGravity);
    imu = std::make_unique<ImuFactor>(pre, kGravity);
    LidarPoseMeasurement m0, m1;  // LiDAR poses slightly off the IMU prediction: the factors pull
    m0.T_world_imu = Perturb(MakePose(s0.p_world_m, Eigen::Quaterniond(s0.R_world_imu)),
                             (Vector6d() << RandomVector(rng, 0.02), RandomVector(rng, 0.01)).finished());
    m1.T_world_imu = Perturb(MakePose(s1.p_world_m, Eigen::Quaterniond(s1.R_world_imu)),
                             (Vector6d() << RandomVector(rng, 0.02), RandomVector(rng, 0.01)).finished());
    m0.information = RandomInformation(rng, 400.0);
    m1.information = RandomInformation(rng, 400.0);
    lidar0 = std::make_unique<LidarPoseFactor>(m0);
    lidar1 = std::make_unique<LidarPoseFactor>(m1);
    PackImuState(s0, pose0, sb0);
    PackImuState(s1, pose1, sb1);
    Eigen::VectorXd sb_mean = Eigen::Map<Eigen::VectorXd>(sb0, 9);
    prior_sb0 = LinearizedPriorFactor::Gaussian({sb0, BlockKind::kVector, 9}, sb_mean,
                                                Eigen::MatrixXd::Identity(9, 9) * 100.0);
  }
  /// Adds the factors (not owned) to `problem`: state 1's LiDAR factor when with_lidar1, state 0's factors
  /// (its LiDAR factor robustified by loss0, may be null; the speed-bias prior; the IMU factor) when with_state0.
  void AddTo(ceres::Problem* problem, bool with_state0, bool with_lidar1, ceres::LossFunction* loss0) {
    problem->AddParameterBlock(pose1, 7, MakeImuPoseManifold().release());
    problem->AddParameterBlock(sb1, 9);
    if (with_lidar1) problem->AddResidualBlock(lidar1.get(), nullptr, pose1);
    if (!with_state0) return;
    problem->AddParameterBlock(pose0, 7, MakeImuPoseManifold().release());
    problem->AddResidualBlock(lidar0.get(), loss0, pose0);
    problem->AddResidualBlock(prior_sb0.get(), nullptr, sb0);
    problem->AddResidualBlock(imu.get(), nullptr, pose0, sb0, pose1, sb1);
  }
};

ceres::Problem::Options NonOwning() {
  ceres::Problem::Options o;
  o.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  return o;
}

void Solve(ceres::Problem* problem) {
  ceres::Solver::Options options;
  options.max_num_iterations = 50;
  options.function_tolerance = 1e-14;
  options.gradient_tolerance = 1e-14;
  options.parameter_tolerance = 1e-14;
  ceres::Solver::Summary summary;
  ceres::Solve(options, problem, &summary);
  EXPECT_TRUE(summary.IsSolutionUsable()) << summary.BriefReport();
}

/// Marginalises state 0 of `tp` (its LiDAR factor under `loss0`, the speed-bias prior and the IMU factor).
MarginalizationResult MarginalizeState0(TwoStateProblem& tp, const ceres::LossFunction* loss0) {
  return Marginalize(
      {{tp.lidar0.get(), loss0, {{tp.pose0, BlockKind::kPose, 7}}},
       {tp.prior_sb0.get(), nullptr, {{tp.sb0, BlockKind::kVector, 9}}},
       {tp.imu.get(), nullptr, {{tp.pose0, BlockKind::kPose, 7}, {tp.sb0, BlockKind::kVector, 9},
                                {tp.pose1, BlockKind::kPose, 7}, {tp.sb1, BlockKind::kVector, 9}}}},
      {tp.pose0, tp.sb0});
}

/// The Hessian J^T J of `problem` (Ceres' Jacobian, loss applied) in the [dt; dtheta] tangent, blocks
/// [pose0 sb0 pose1 sb1], and its Schur complement onto [pose1 sb1] by the normal equations.
Eigen::MatrixXd SchurFromCeres(ceres::Problem* problem, TwoStateProblem& tp) {
  ceres::Problem::EvaluateOptions eval;
  eval.parameter_blocks = {tp.pose0, tp.sb0, tp.pose1, tp.sb1};
  ceres::CRSMatrix crs;
  problem->Evaluate(eval, nullptr, nullptr, nullptr, &crs);
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(crs.num_rows, crs.num_cols);
  for (int r = 0; r < crs.num_rows; ++r)
    for (int i = crs.rows[r]; i < crs.rows[r + 1]; ++i) J(r, crs.cols[i]) = crs.values[i];
  for (const int c0 : {3, 18}) J.middleCols(c0, 3) *= 0.5;  // Ceres' rotation coordinate is dtheta / 2
  const Eigen::MatrixXd H = J.transpose() * J;
  return H.bottomRightCorner(15, 15) -
         H.bottomLeftCorner(15, 15) * H.topLeftCorner(15, 15).inverse() * H.topRightCorner(15, 15);
}

TEST(Marginalize, EqualsTheSchurComplementWithRobustLoss) {
  // A deliberately noisy IMU (densities x30, random walks x300) keeps the full Hessian's conditioning ~1e6, so the
  // normal-equation Schur complement used as the reference is itself accurate to ~1e-10.
  ImuNoise noisy;
  noisy.gyro_noise_density *= 30;
  noisy.accel_noise_density *= 30;
  noisy.gyro_random_walk *= 300;
  noisy.accel_random_walk *= 300;
  RandomStream rng(25, "pose_factors_test.marginalize");
  TwoStateProblem tp(rng, noisy);
  // Huber scale 0.3: state 0's whitened LiDAR residual (|r|^2 = 0.67) sits in the linear part, so the loss
  // correction matters (without it the comparison below is off by 1.6).
  ceres::HuberLoss huber(0.3);
  ceres::Problem::Options options = NonOwning();
  options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem full(options);
  tp.AddTo(&full, true, true, &huber);
  Solve(&full);
  const MarginalizationResult m = MarginalizeState0(tp, &huber);
  ASSERT_TRUE(m.success) << m.message;
  EXPECT_EQ(m.rank, 15);
  ASSERT_EQ(m.prior->blocks().size(), 2u);
  EXPECT_EQ(m.prior->blocks()[0].values, tp.pose1);
  ceres::Problem state0_terms(options);  // exactly the terms that touch state 0
  tp.AddTo(&state0_terms, true, false, &huber);
  const Eigen::MatrixXd schur = SchurFromCeres(&state0_terms, tp);
  const Eigen::MatrixXd prior_H = m.prior->J().transpose() * m.prior->J();
  // Measured relative difference 1.5e-12; a missing loss correction or a wrong tangent scale gives O(1).
  EXPECT_LT((prior_H - schur).norm() / schur.norm(), 1e-9);
}

TEST(Marginalize, ReducedProblemKeepsTheFullOptimum) {
  // Default (BMI-class) IMU noise: the IMU information spans ~1e2..1e10, the case the QR elimination is for.
  RandomStream rng(26, "pose_factors_test.marginalize_optimum");
  TwoStateProblem tp(rng, ImuNoise{});
  ceres::Problem full(NonOwning());
  tp.AddTo(&full, true, true, nullptr);
  Solve(&full);
  const MarginalizationResult m = MarginalizeState0(tp, nullptr);
  ASSERT_TRUE(m.success) << m.message;
  EXPECT_EQ(m.rank, 15);
  ceres::Problem reduced(NonOwning());  // prior + LiDAR 1
  tp.AddTo(&reduced, false, true, nullptr);
  reduced.AddResidualBlock(m.prior.get(), nullptr, m.prior->block_values());
  // At the full optimum the reduced problem's gradient vanishes too: measured 1.3e-8, against 1.3e3 after the
  // perturbation below.
  std::vector<double> gradient;
  reduced.Evaluate(ceres::Problem::EvaluateOptions{}, nullptr, nullptr, &gradient, nullptr);
  EXPECT_LT(Eigen::Map<Eigen::VectorXd>(gradient.data(), gradient.size()).norm(), 1e-5);
  double opt_pose1[7], opt_sb1[9];
  std::copy(tp.pose1, tp.pose1 + 7, opt_pose1);
  std::copy(tp.sb1, tp.sb1 + 9, opt_sb1);
  tp.pose1[0] += 0.3;  // start the reduced problem away from the optimum
  tp.sb1[2] -= 0.4;
  tp.sb1[4] += 0.01;
  Solve(&reduced);
  // Measured max deviation 4.6e-12 (pose) and 8.6e-11 (speed-bias) from perturbations of 0.3 m and 0.4 m/s.
  for (int k = 0; k < 7; ++k) EXPECT_NEAR(tp.pose1[k], opt_pose1[k], 1e-8) << k;
  for (int k = 0; k < 9; ++k) EXPECT_NEAR(tp.sb1[k], opt_sb1[k], 1e-8) << k;
}

TEST(Marginalize, ReportsBadInput) {
  double v[3] = {0, 0, 0};
  const auto prior = LinearizedPriorFactor::Gaussian({v, BlockKind::kVector, 3}, Eigen::Vector3d::Zero(),
                                                     Eigen::Matrix3d::Identity());
  const MarginalizationResult nothing_kept =
      Marginalize({{prior.get(), nullptr, {{v, BlockKind::kVector, 3}}}}, {v});
  EXPECT_FALSE(nothing_kept.success);
  EXPECT_NE(nothing_kept.message.find("no block is kept"), std::string::npos) << nothing_kept.message;
}

}  // namespace
}  // namespace rotolidar
