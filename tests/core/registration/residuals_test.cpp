// Residual Jacobians against numeric differentiation, the pose manifold's tangent convention, and the
// degeneracy analysis on Hessians with known structure.
#include <cmath>
#include <deque>
#include <vector>

#include <ceres/gradient_checker.h>
#include <ceres/loss_function.h>
#include <gtest/gtest.h>

#include "core/registration/degeneracy.hpp"
#include "core/registration/grouped_residual.hpp"
#include "core/registration/residuals.hpp"
#include "core/util/rng.hpp"

namespace rotolidar {
namespace {

Eigen::Vector3d RandomVector(RandomStream& rng, double sigma) {
  return Eigen::Vector3d{rng.Normal(0.0, sigma), rng.Normal(0.0, sigma), rng.Normal(0.0, sigma)};
}

Pose3 RandomPose(RandomStream& rng) {
  // Rotations up to ~pi (sigma 1 rad per axis) and translations of metres: far from identity on purpose.
  const Eigen::Vector3d t = RandomVector(rng, 5.0);  // drawn first: argument order is the compiler's choice
  return MakePose(t, Eigen::Quaterniond(ExpSO3(RandomVector(rng, 1.0))));
}

Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d S;
  S << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return S;
}

/// Central differences of a cost function's residual along the manifold's tangent at pose T (h in tangent units).
Eigen::MatrixXd NumericTangentJacobian(const ceres::CostFunction& f, const Pose3& T, double h) {
  const int m = f.num_residuals();
  Eigen::MatrixXd J(m, 6);
  for (int k = 0; k < 6; ++k) {
    Vector6d d = Vector6d::Zero();
    d(k) = h;
    const PoseParameters xp = PoseToParameters(PoseBoxPlus(T, d)), xm = PoseToParameters(PoseBoxPlus(T, -d));
    Eigen::VectorXd rp(m), rm(m);
    const double* pp[] = {xp.data()};
    const double* pm[] = {xm.data()};
    f.Evaluate(pp, rp.data(), nullptr);
    f.Evaluate(pm, rm.data(), nullptr);
    J.col(k) = (rp - rm) / (2.0 * h);
  }
  return J;
}

/// Analytic ambient Jacobian (m x 7) times the manifold's PlusJacobian (7 x 6).
Eigen::MatrixXd AnalyticTangentJacobian(const ceres::CostFunction& f, const Pose3& T) {
  const int m = f.num_residuals();
  const PoseParameters x = PoseToParameters(T);
  Eigen::Matrix<double, Eigen::Dynamic, 7, Eigen::RowMajor> J(m, 7);
  Eigen::VectorXd r(m);
  const double* p[] = {x.data()};
  double* jac[] = {J.data()};
  f.Evaluate(p, r.data(), jac);
  Eigen::Matrix<double, 7, 6, Eigen::RowMajor> plus;
  PoseManifold().PlusJacobian(x.data(), plus.data());
  return J * plus;
}

TEST(PoseManifold, BoxPlusIsLeftRotationAndBoxMinusInvertsIt) {
  RandomStream rng(7, "test.registration.manifold");
  for (int trial = 0; trial < 20; ++trial) {
    const Pose3 T = RandomPose(rng);
    Vector6d delta;
    delta << RandomVector(rng, 0.5), RandomVector(rng, 0.3);
    const Pose3 Tp = PoseBoxPlus(T, delta);
    EXPECT_LT((Tp.translation() - (T.translation() + delta.head<3>())).norm(), 1e-12);
    EXPECT_LT((Tp.linear() - ExpSO3(delta.tail<3>()) * T.linear()).norm(), 1e-12);
    EXPECT_LT((PoseBoxMinus(Tp, T) - delta).norm(), 1e-9);
  }
}

TEST(PoseManifold, CeresQuaternionTangentIsHalfTheRotationVector) {
  // Pins the Ceres 2.1 convention the registration relies on (and works around): its Plus(x, [dt; d]) equals
  // our T [+] [dt; 2 d]. If a Ceres upgrade changes this, this test says so before any Hessian goes wrong.
  RandomStream rng(7, "test.registration.ceres_manifold");
  const PoseManifold manifold;
  for (int trial = 0; trial < 20; ++trial) {
    const Pose3 T = RandomPose(rng);
    Vector6d d;
    d << RandomVector(rng, 0.5), RandomVector(rng, 0.3);
    const PoseParameters x = PoseToParameters(T);
    PoseParameters y;
    ASSERT_TRUE(manifold.Plus(x.data(), d.data(), y.data()));
    Vector6d ours = d;
    ours.tail<3>() *= 2.0;
    const Pose3 expected = PoseBoxPlus(T, ours);
    EXPECT_LT((ParametersToPose(y.data()).matrix() - expected.matrix()).norm(), 1e-12);
  }
}

TEST(Residuals, QuaternionJacobianMatchesCentralDifferences) {
  RandomStream rng(7, "test.registration.quat_jacobian");
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Quaterniond q(ExpSO3(RandomVector(rng, 1.0)));
    const Eigen::Vector3d p = RandomVector(rng, 10.0);
    const Eigen::Matrix<double, 3, 4> J = RotatedPointQuaternionJacobian(q, p);
    // Off-sphere perturbations of the coefficients: the extension R(q)p = p + 2w v x p + 2 v x (v x p) is what
    // Eigen's q * p evaluates, so the full 3x4 (not only its tangent part) must agree.
    const double h = 1e-6;
    for (int k = 0; k < 4; ++k) {
      Eigen::Quaterniond qp = q, qm = q;
      qp.coeffs()(k) += h;
      qm.coeffs()(k) -= h;
      const Eigen::Vector3d numeric = (qp * p - qm * p) / (2.0 * h);
      EXPECT_LT((J.col(k) - numeric).norm(), 1e-7 * (1.0 + p.norm())) << "coefficient " << k;
    }
  }
}

TEST(Residuals, GradientCheckerAcceptsBothResidualsAtRandomPoses) {
  RandomStream rng(7, "test.registration.gradient_checker");
  PoseManifold manifold;
  const std::vector<const ceres::Manifold*> manifolds = {&manifold};
  ceres::NumericDiffOptions numeric;
  for (int trial = 0; trial < 25; ++trial) {
    const Pose3 T = RandomPose(rng);
    const PoseParameters x = PoseToParameters(T);
    const double* params[] = {x.data()};
    const PointToPlaneResidual plane{RandomVector(rng, 10.0), RandomVector(rng, 1.0).normalized(), rng.Normal()};
    const PointToLineResidual line{RandomVector(rng, 10.0), RandomVector(rng, 10.0),
                                   RandomVector(rng, 1.0).normalized()};
    ceres::GradientChecker::ProbeResults results;
    // 1e-6 relative: Ceres' central differences on O(10 m) lever arms are accurate to ~1e-8 here; a wrong
    // Jacobian term (sign, factor 2, transposed skew) shows up as O(1) relative error.
    EXPECT_TRUE(ceres::GradientChecker(&plane, &manifolds, numeric).Probe(params, 1e-6, &results))
        << results.error_log;
    EXPECT_TRUE(ceres::GradientChecker(&line, &manifolds, numeric).Probe(params, 1e-6, &results))
        << results.error_log;
  }
}

TEST(Residuals, TangentJacobiansMatchClosedFormCentralDifferencesAndCeresChain) {
  RandomStream rng(7, "test.registration.tangent");
  Vector6d twice;  // Ceres' Plus(x, d) = ours with 2 d: d r/d(ceres) = d r/d(ours) * 2 on rotation columns
  twice << 1, 1, 1, 2, 2, 2;
  for (int trial = 0; trial < 25; ++trial) {
    const Pose3 T = RandomPose(rng);
    const Eigen::Vector3d p = RandomVector(rng, 10.0), n = RandomVector(rng, 1.0).normalized();
    const PointToPlaneResidual plane(p, n, 0.3);
    Eigen::Matrix<double, 1, 6> Jp;
    const double r = plane.EvaluateTangent(T, &Jp);
    EXPECT_NEAR(r, n.dot(T * p) + 0.3, 1e-12);
    // Closed form under the left perturbation: d r / d[dt, dtheta] = [n^T, -n^T [R p]x].
    Eigen::Matrix<double, 1, 6> expected;
    expected << n.transpose(), -n.transpose() * Skew(T.linear() * p);
    EXPECT_LT((Jp - expected).norm(), 1e-9);
    // 1e-6: central differences with h = 1e-6 on O(10 m) lever arms are accurate to ~1e-8.
    EXPECT_LT((Jp - NumericTangentJacobian(plane, T, 1e-6)).norm(), 1e-6);
    // The ambient (Ceres) Jacobian chained with Ceres' PlusJacobian is the same derivative in half-angle units.
    EXPECT_LT((AnalyticTangentJacobian(plane, T) - Jp * twice.asDiagonal()).norm(), 1e-9);

    const PointToLineResidual line(p, RandomVector(rng, 5.0), n);
    Eigen::Matrix<double, 2, 6> Jl;
    line.EvaluateTangent(T, &Jl);
    EXPECT_LT((Jl - NumericTangentJacobian(line, T, 1e-6)).norm(), 1e-6);
    EXPECT_LT((AnalyticTangentJacobian(line, T) - Jl * twice.asDiagonal()).norm(), 1e-9);
  }
}

TEST(Residuals, ValuesAreSignedPlaneDistanceAndLineDistance) {
  const Pose3 T = MakePose(Eigen::Vector3d(1.0, 2.0, 3.0), Eigen::Quaterniond(ExpSO3(Eigen::Vector3d(0, 0, 0.5))));
  const PoseParameters x = PoseToParameters(T);
  const double* params[] = {x.data()};
  const Eigen::Vector3d p_scan(0.4, -0.7, 0.2);
  const Eigen::Vector3d p_map = T * p_scan;
  // Plane z = 2 (n = +z, d = -2): the residual is p_map.z - 2.
  double r_plane = 0.0;
  PointToPlaneResidual(p_scan, Eigen::Vector3d::UnitZ(), -2.0).Evaluate(params, &r_plane, nullptr);
  EXPECT_NEAR(r_plane, p_map.z() - 2.0, 1e-12);
  // Line through a along u: |r| is the perpendicular distance.
  const Eigen::Vector3d a(0.0, 1.0, 0.0), u = Eigen::Vector3d(1.0, 1.0, 0.0).normalized();
  double r_line[2];
  PointToLineResidual(p_scan, a, u).Evaluate(params, r_line, nullptr);
  const double distance = ((p_map - a) - u.dot(p_map - a) * u).norm();
  EXPECT_NEAR(std::hypot(r_line[0], r_line[1]), distance, 1e-12);
}

TEST(Residuals, AWeightedPlaneResidualIsTheWeightTimesTheDistanceWithItsJacobian) {
  RandomStream rng(13, "test.registration.weighted_plane");
  for (int trial = 0; trial < 25; ++trial) {
    const Pose3 T = RandomPose(rng);
    const Eigen::Vector3d p = RandomVector(rng, 10.0), n = RandomVector(rng, 1.0).normalized();
    const double d = rng.Normal(0.0, 2.0), w = 0.1 + 0.9 * rng.Uniform();
    const PointToPlaneResidual plain(p, n, d), weighted(p, n, d, w);
    Eigen::Matrix<double, 1, 6> Jp, Jw;
    const double r = plain.EvaluateTangent(T, &Jp), rw = weighted.EvaluateTangent(T, &Jw);
    EXPECT_NEAR(rw, w * r, 1e-12 * (1.0 + std::abs(r)));
    EXPECT_LT((Jw - w * Jp).norm(), 1e-12 * (1.0 + Jp.norm()));
    // Against central differences, as the unweighted residual (same accuracy argument).
    EXPECT_LT((Jw - NumericTangentJacobian(weighted, T, 1e-6)).norm(), 1e-6);
  }
}

TEST(Residuals, ResetEqualsAFreshlyConstructedResidual) {
  RandomStream rng(11);
  PointToLineResidual line{RandomVector(rng, 3.0), RandomVector(rng, 3.0), RandomVector(rng, 1.0).normalized()};
  PointToPlaneResidual plane{RandomVector(rng, 3.0), RandomVector(rng, 1.0).normalized(), 0.3};
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Vector3d p = RandomVector(rng, 3.0), a = RandomVector(rng, 3.0);
    const Eigen::Vector3d u = RandomVector(rng, 1.0).normalized();
    const double d = rng.Normal(0.0, 2.0);
    line.Reset(p, a, u);
    plane.Reset(p, u, d);
    const PointToLineResidual fresh_line(p, a, u);
    const PointToPlaneResidual fresh_plane(p, u, d);
    const PoseParameters x = PoseToParameters(RandomPose(rng));
    const double* params[] = {x.data()};
    double r[2], r_fresh[2], J[14], J_fresh[14];
    double* jac[] = {J};
    double* jac_fresh[] = {J_fresh};
    line.Evaluate(params, r, jac);
    fresh_line.Evaluate(params, r_fresh, jac_fresh);
    for (int i = 0; i < 2; ++i) EXPECT_EQ(r[i], r_fresh[i]);
    for (int i = 0; i < 14; ++i) EXPECT_EQ(J[i], J_fresh[i]);
    plane.Evaluate(params, r, jac);
    fresh_plane.Evaluate(params, r_fresh, jac_fresh);
    EXPECT_EQ(r[0], r_fresh[0]);
    for (int i = 0; i < 7; ++i) EXPECT_EQ(J[i], J_fresh[i]);
  }
}

TEST(Degeneracy, DisplacementMetricIsTheMeanSquaredPointMotion) {
  RandomStream rng(7, "test.registration.metric");
  std::vector<Eigen::Vector3d> levers;
  for (int i = 0; i < 50; ++i) levers.push_back(RandomVector(rng, 8.0) + Eigen::Vector3d(3.0, -1.0, 0.5));
  const Matrix6d G = DisplacementMetric(levers);
  for (int trial = 0; trial < 10; ++trial) {
    Vector6d delta;
    delta << RandomVector(rng, 0.1), RandomVector(rng, 0.02);
    double mean_sq = 0.0;  // first-order motion of each point: dt + dtheta x r
    for (const auto& r : levers) mean_sq += (delta.head<3>() + delta.tail<3>().cross(r)).squaredNorm();
    mean_sq /= double(levers.size());
    EXPECT_NEAR(delta.dot(G * delta), mean_sq, 1e-12 * (1.0 + mean_sq));
  }
}

TEST(Degeneracy, FindsTheWeakDirectionAndProjectsItOut) {
  // Points spread around the origin with E[r] = 0 and E[|r|^2 I - r r^T] = L^2 I; information per correspondence
  // is strong along everything but translation x.
  const int n = 1000;
  const double L = 5.0;
  Vector6d g, info;
  g << 1, 1, 1, L * L, L * L, L * L;
  info << 1e-3, 0.5, 0.8, 0.3 * L * L, 0.4 * L * L, 0.6 * L * L;
  const Matrix6d G = g.asDiagonal();
  const Matrix6d H = (info * n).asDiagonal();
  DegeneracyConfig config;
  const DegeneracyInfo d = AnalyzeDegeneracy(H, G, n, config);
  ASSERT_TRUE(d.degenerate);
  ASSERT_EQ(d.degenerate_directions.size(), 1u);
  EXPECT_NEAR(std::abs(d.degenerate_directions[0](0)), 1.0, 1e-12);
  EXPECT_NEAR(d.eigenvalues(0), 1e-3, 1e-12);
  EXPECT_NEAR(d.eigenvalues(1), 0.3, 1e-12);  // rotations measured by the motion they cause at lever L
  Vector6d delta;
  delta << 0.5, 0.1, -0.2, 0.01, 0.02, -0.03;
  const Vector6d remapped = RemapUpdate(d, delta);
  EXPECT_NEAR(remapped(0), 0.0, 1e-12);
  EXPECT_LT((remapped.tail<5>() - delta.tail<5>()).norm(), 1e-12);
  EXPECT_LT((d.projection * d.projection - d.projection).norm(), 1e-12);  // a projector
  config.min_eigenvalue = 1e-4;  // below the weak eigenvalue: nothing degenerate, identity remapping
  const DegeneracyInfo none = AnalyzeDegeneracy(H, G, n, config);
  EXPECT_FALSE(none.degenerate);
  EXPECT_LT((RemapUpdate(none, delta) - delta).norm(), 1e-15);
}

TEST(Degeneracy, CoupledWeakDirectionIsFoundAndRemovedInTheMetric) {
  // Points off-centre (E[r] != 0) make G couple translation and rotation; the weak direction mixes translation x
  // with yaw. Build H = N (G - c G w w^T G) with G-unit w: then H w = N (1 - c) G w, i.e. lambda = 1 - c for w,
  // and lambda = 1 for every G-orthogonal direction.
  RandomStream rng(7, "test.registration.coupled");
  std::vector<Eigen::Vector3d> levers;
  for (int i = 0; i < 40; ++i) levers.push_back(RandomVector(rng, 4.0) + Eigen::Vector3d(6.0, 2.0, 0.0));
  const Matrix6d G = DisplacementMetric(levers);
  Vector6d w;
  w << 1.0, 0.0, 0.0, 0.0, 0.0, 0.2;
  w /= std::sqrt(w.dot(G * w));
  const int n = 40;
  const double c = 0.999;  // lambda = 0.001, below the default min_eigenvalue (0.005)
  const Matrix6d H = n * (G - c * G * w * w.transpose() * G);
  const DegeneracyInfo d = AnalyzeDegeneracy(H, G, n, DegeneracyConfig());
  ASSERT_EQ(d.degenerate_directions.size(), 1u);
  EXPECT_NEAR(d.eigenvalues(0), 1.0 - c, 1e-9);
  EXPECT_NEAR(d.eigenvalues(1), 1.0, 1e-9);
  EXPECT_NEAR(std::abs(d.degenerate_directions[0].dot(w.normalized())), 1.0, 1e-9);
  Vector6d delta;
  delta << 0.3, -0.1, 0.2, 0.01, -0.02, 0.05;
  const Vector6d remapped = RemapUpdate(d, delta);
  EXPECT_NEAR(remapped.dot(G * w), 0.0, 1e-12);  // nothing left along w (in the metric)
  const Vector6d removed = delta - remapped;     // and what was removed lies along w
  EXPECT_NEAR(std::abs(removed.normalized().dot(w.normalized())), 1.0, 1e-9);
}

TEST(Degeneracy, ValidateNamesTheField) {
  DegeneracyConfig config;
  std::string error;
  EXPECT_TRUE(config.Validate(&error));
  config.min_eigenvalue = -1.0;
  EXPECT_FALSE(config.Validate(&error));
  EXPECT_NE(error.find("degeneracy.min_eigenvalue"), std::string::npos) << error;
}

// A group's 7 rows give Ceres the gradient, Gauss-Newton matrix and cost of one block per point under the loss,
// with Ceres' per-block correction (sqrt(rho') on residual and Jacobian; Huber and Cauchy have rho'' <= 0), in
// Ceres' tangent space (the ambient Jacobians times the manifold's PlusJacobian, as Ceres uses them).
// Lines (2 rows a point) and planes (1 row), a full-rank group and groups that observe fewer directions.
template <typename Residual>
void ExpectGroupMatchesPerPointBlocks(const std::deque<Residual>& points, const PoseParameters& x) {
  const double* params[] = {x.data()};
  Eigen::Matrix<double, 7, 6, Eigen::RowMajor> P;
  ASSERT_TRUE(PoseManifold().PlusJacobian(x.data(), P.data()));
  const ceres::HuberLoss huber(0.1);
  const ceres::CauchyLoss cauchy(0.1);
  for (const ceres::LossFunction* loss : std::vector<const ceres::LossFunction*>{&huber, &cauchy, nullptr}) {
    GroupedResidual<Residual> group(loss);
    for (const auto& p : points) group.Add(&p);
    ASSERT_EQ(group.num_residuals(), 7);
    Eigen::Matrix<double, 7, 1> r;
    Eigen::Matrix<double, 7, 7, Eigen::RowMajor> J;
    double* jac[] = {J.data()};
    ASSERT_TRUE(group.Evaluate(params, r.data(), jac));
    EXPECT_TRUE(J.bottomRows<1>().isZero(0.0));  // the cost row carries no Jacobian
    Eigen::Matrix<double, 6, 1> g = Eigen::Matrix<double, 6, 1>::Zero();
    Eigen::Matrix<double, 6, 6> H = Eigen::Matrix<double, 6, 6>::Zero();
    double cost = 0.0;
    for (const auto& p : points) {  // one Ceres block per point: its ambient Jacobian through the manifold
      Eigen::Matrix<double, Residual::kRows, 1> ri;
      Eigen::Matrix<double, Residual::kRows, 7, Eigen::RowMajor> Ji;
      double* jaci[] = {Ji.data()};
      p.Evaluate(params, ri.data(), jaci);
      const Eigen::Matrix<double, Residual::kRows, 6> Ti = Ji * P;
      double rho[3] = {ri.squaredNorm(), 1.0, 0.0};
      if (loss != nullptr) loss->Evaluate(ri.squaredNorm(), rho);
      g += rho[1] * Ti.transpose() * ri;
      H += rho[1] * Ti.transpose() * Ti;
      cost += 0.5 * rho[0];
    }
    const Eigen::Matrix<double, 7, 6> JP = J * P;
    EXPECT_LT((JP.transpose() * r - g).norm(), 1e-12 * g.norm());
    EXPECT_LT((JP.transpose() * JP - H).norm(), 1e-12 * H.norm());
    EXPECT_NEAR(0.5 * r.squaredNorm(), cost, 1e-12 * cost);
    double r_only[7];
    ASSERT_TRUE(group.Evaluate(params, r_only, nullptr));  // cost-only evaluations: the same cost
    double cost_only = 0.0;
    for (double v : r_only) cost_only += 0.5 * v * v;
    EXPECT_NEAR(cost_only, cost, 1e-12 * cost);
  }
}

TEST(GroupedResidual, MatchesPerPointBlocksUnderTheLoss) {
  RandomStream rng(23);
  const Pose3 T = RandomPose(rng);
  const PoseParameters x = PoseToParameters(T);
  std::deque<PointToLineResidual> lines;
  std::deque<PointToPlaneResidual> planes, one_plane;
  for (int i = 0; i < 9; ++i) {
    const Eigen::Vector3d p = RandomVector(rng, 5.0), u = RandomVector(rng, 1.0).normalized();
    const double off = (i % 3 == 0) ? 0.6 : 0.02;  // every third point deep in the robust zone (scale 0.1)
    lines.emplace_back(p, T * p + off * u.unitOrthogonal() + RandomVector(rng, 0.01), u);
    planes.emplace_back(p, u, -u.dot(T * p) + off);
    // All on one map plane z = 1: the group observes z, roll and pitch only (G has rank 3 in the tangent).
    one_plane.emplace_back(p, Eigen::Vector3d::UnitZ(), -1.0);
  }
  ExpectGroupMatchesPerPointBlocks(lines, x);
  ExpectGroupMatchesPerPointBlocks(planes, x);
  ExpectGroupMatchesPerPointBlocks(one_plane, x);
  std::deque<PointToPlaneResidual> single;
  single.emplace_back(RandomVector(rng, 5.0), Eigen::Vector3d::UnitX(), 0.3);  // one point: rank 1
  ExpectGroupMatchesPerPointBlocks(single, x);
}

}  // namespace
}  // namespace rotolidar
