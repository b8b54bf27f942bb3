#include "core/imu/imu_factor.hpp"
#include "core/util/log.hpp"

#include <ceres/product_manifold.h>
#include <ceres/sphere_manifold.h>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

namespace rotolidar {

namespace {

using Matrix3d = Eigen::Matrix3d;
using Vector3d = Eigen::Vector3d;
using PoseJacobian = Eigen::Matrix<double, kImuResidualSize, kImuPoseBlockSize, Eigen::RowMajor>;
using SpeedBiasJacobian = Eigen::Matrix<double, kImuResidualSize, kImuSpeedBiasBlockSize, Eigen::RowMajor>;
using LocalPoseJacobian = Eigen::Matrix<double, kImuResidualSize, 6>;  // columns [dt(3) dtheta(3)]

/// The four parameter blocks, read once (quaternions normalised).
struct Blocks {
  Matrix3d Ri, Rj;
  Eigen::Quaterniond qi, qj;
  Vector3d pi, pj, vi, vj, bgi, bai, bgj, baj;
};

Blocks ReadBlocks(double const* const* parameters) {
  Blocks b;
  b.pi = Eigen::Map<const Vector3d>(parameters[0]);
  b.qi = Eigen::Map<const Eigen::Quaterniond>(parameters[0] + 3).normalized();
  b.Ri = b.qi.toRotationMatrix();
  b.vi = Eigen::Map<const Vector3d>(parameters[1]);
  b.bgi = Eigen::Map<const Vector3d>(parameters[1] + 3);
  b.bai = Eigen::Map<const Vector3d>(parameters[1] + 6);
  b.pj = Eigen::Map<const Vector3d>(parameters[2]);
  b.qj = Eigen::Map<const Eigen::Quaterniond>(parameters[2] + 3).normalized();
  b.Rj = b.qj.toRotationMatrix();
  b.vj = Eigen::Map<const Vector3d>(parameters[3]);
  b.bgj = Eigen::Map<const Vector3d>(parameters[3] + 3);
  b.baj = Eigen::Map<const Vector3d>(parameters[3] + 6);
  return b;
}

/// d(q / |q|)-consistent map from a world-frame rotation-vector Jacobian to the 4 quaternion coordinates
/// (x y z w). EigenQuaternionManifold::Plus(q, d) = [cos|d|, sin|d| d/|d|] * q rotates by theta = 2 d on the
/// left, and its PlusJacobian at d = 0 is P = [w I - [v]x ; -v^T] with orthonormal columns, all orthogonal to q.
/// So J_q = 2 J_theta P^T is the exact Jacobian of r(q/|q|) and J_q P = 2 J_theta.
Eigen::Matrix<double, kImuResidualSize, 4> QuaternionJacobian(const Eigen::Matrix<double, kImuResidualSize, 3>& J_theta,
                                                             const Eigen::Quaterniond& q) {
  Eigen::Matrix<double, 4, 3> P;
  P.topRows<3>() = q.w() * Matrix3d::Identity() - so3::Hat(q.vec());
  P.bottomRows<1>() = -q.vec().transpose();
  return 2.0 * J_theta * P.transpose();
}

/// Intermediate terms shared by the residual and its Jacobians.
struct Terms {
  ImuFactor::Vector15d r;
  Matrix3d E;         ///< (corrected dR)^T Ri^T Rj = Exp(r_R)
  Vector3d x_v, x_p;  ///< world-frame velocity / position differences of eq. 45 before rotating into frame i
  Vector3d dbg;       ///< bg_i - bg_lin
};

Terms ComputeTerms(const Blocks& b, const PreintegratedImu& pre, const Vector3d& g) {
  Terms t;
  const double T = pre.dt_s();
  t.dbg = b.bgi - pre.bias_gyro_radps();
  const ImuDelta d = pre.Corrected(t.dbg, b.bai - pre.bias_accel_mps2());
  t.E = d.dR.transpose() * b.Ri.transpose() * b.Rj;
  t.x_v = b.vj - b.vi - g * T;
  t.x_p = b.pj - b.pi - b.vi * T - 0.5 * g * T * T;
  t.r.segment<3>(0) = LogSO3(t.E);
  t.r.segment<3>(3) = b.Ri.transpose() * t.x_v - d.dv_mps;
  t.r.segment<3>(6) = b.Ri.transpose() * t.x_p - d.dp_m;
  t.r.segment<3>(9) = b.bgj - b.bgi;
  t.r.segment<3>(12) = b.baj - b.bai;
  return t;
}

Eigen::Matrix<double, 15, 15> SqrtInformation(const Eigen::Matrix<double, 15, 15>& covariance) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 15, 15>> eig(covariance);
  const Eigen::Matrix<double, 15, 1> inv_sqrt =
      eig.eigenvalues().cwiseMax(ImuFactor::kMinVariance).cwiseSqrt().cwiseInverse();
  return inv_sqrt.asDiagonal() * eig.eigenvectors().transpose();  // S^T S = V L^-1 V^T = covariance^-1
}

}  // namespace

std::unique_ptr<ceres::Manifold> MakeImuPoseManifold() {
  return std::make_unique<ceres::ProductManifold<ceres::EuclideanManifold<3>, ceres::EigenQuaternionManifold>>();
}

void PackImuPose(const Pose3& T_world_imu, double* pose7) {
  Eigen::Map<Vector3d> t(pose7);
  Eigen::Map<Eigen::Quaterniond> q(pose7 + 3);
  t = T_world_imu.translation();
  q = Eigen::Quaterniond(T_world_imu.linear()).normalized();
}

Pose3 UnpackImuPose(const double* pose7) {
  return MakePose(Eigen::Map<const Vector3d>(pose7), Eigen::Map<const Eigen::Quaterniond>(pose7 + 3));
}

void PackImuState(const NavState& state, double* pose7, double* speed_bias9) {
  Pose3 T = Pose3::Identity();
  T.linear() = state.R_world_imu;
  T.translation() = state.p_world_m;
  PackImuPose(T, pose7);
  Eigen::Map<Eigen::Matrix<double, 9, 1>> sb(speed_bias9);
  sb << state.v_world_mps, state.bias_gyro_radps, state.bias_accel_mps2;
}

NavState UnpackImuState(const double* pose7, const double* speed_bias9) {
  NavState s;
  s.R_world_imu = Eigen::Map<const Eigen::Quaterniond>(pose7 + 3).normalized().toRotationMatrix();
  s.p_world_m = Eigen::Map<const Vector3d>(pose7);
  s.v_world_mps = Eigen::Map<const Vector3d>(speed_bias9);
  s.bias_gyro_radps = Eigen::Map<const Vector3d>(speed_bias9 + 3);
  s.bias_accel_mps2 = Eigen::Map<const Vector3d>(speed_bias9 + 6);
  return s;
}

ImuFactor::ImuFactor(const PreintegratedImu& preintegration, const Eigen::Vector3d& gravity_world_mps2)
    : preintegration_(preintegration), gravity_world_mps2_(gravity_world_mps2) {
  ROTOLIDAR_CHECK(preintegration.dt_s() > 0.0, "ImuFactor needs a preintegration with at least one step");
  const double T = preintegration.dt_s();
  const ImuNoise& n = preintegration.noise();
  covariance_.setZero();
  covariance_.topLeftCorner<9, 9>() = preintegration.covariance();
  covariance_.block<3, 3>(9, 9) = Matrix3d::Identity() * (n.gyro_random_walk * n.gyro_random_walk * T);
  covariance_.block<3, 3>(12, 12) = Matrix3d::Identity() * (n.accel_random_walk * n.accel_random_walk * T);
  sqrt_information_ = SqrtInformation(covariance_);
}

ImuFactor::Vector15d ImuFactor::UnwhitenedResidual(const double* pose_i, const double* speed_bias_i,
                                                   const double* pose_j, const double* speed_bias_j) const {
  const double* parameters[4] = {pose_i, speed_bias_i, pose_j, speed_bias_j};
  return ComputeTerms(ReadBlocks(parameters), preintegration_, gravity_world_mps2_).r;
}

namespace {

// Jacobians of the unwhitened residual w.r.t. world-frame (left) rotation perturbations R <- Exp(theta) R,
// translations, velocities and biases (docs/imu_preintegration.md, "Jacobians"), then whitened by S and
// mapped to the blocks' ambient coordinates. g: gravity in world [m/s^2]; parameters / jacobians: the 4 state
// blocks (a fifth, gravity, block is the caller's).
void EvaluateImu(const PreintegratedImu& pre, const ImuFactor::Matrix15d& S, const Vector3d& g,
                 double const* const* parameters, double* residuals, double** jacobians) {
  const Blocks b = ReadBlocks(parameters);
  const Terms t = ComputeTerms(b, pre, g);
  Eigen::Map<ImuFactor::Vector15d>{residuals} = S * t.r;
  if (jacobians == nullptr) return;

  const double T = pre.dt_s();
  const Matrix3d Jr_inv = so3::RightJacobianInverse(t.r.head<3>());
  const Matrix3d RiT = b.Ri.transpose();
  const Matrix3d I3 = Matrix3d::Identity();

  if (jacobians[0] != nullptr) {  // pose_i
    LocalPoseJacobian J = LocalPoseJacobian::Zero();
    J.block<3, 3>(0, 3) = -Jr_inv * b.Rj.transpose();
    J.block<3, 3>(3, 3) = RiT * so3::Hat(t.x_v);
    J.block<3, 3>(6, 0) = -RiT;
    J.block<3, 3>(6, 3) = RiT * so3::Hat(t.x_p);
    Eigen::Map<PoseJacobian> out(jacobians[0]);
    out.leftCols<3>() = S * J.leftCols<3>();
    out.rightCols<4>() = QuaternionJacobian(S * J.rightCols<3>(), b.qi);
  }
  if (jacobians[1] != nullptr) {  // speed_bias_i
    SpeedBiasJacobian J = SpeedBiasJacobian::Zero();
    const Matrix3d Jr_corr = so3::RightJacobian(pre.dR_dbg() * t.dbg);
    J.block<3, 3>(0, 3) = -Jr_inv * t.E.transpose() * Jr_corr * pre.dR_dbg();
    J.block<3, 3>(3, 0) = -RiT;
    J.block<3, 3>(3, 3) = -pre.dv_dbg();
    J.block<3, 3>(3, 6) = -pre.dv_dba();
    J.block<3, 3>(6, 0) = -RiT * T;
    J.block<3, 3>(6, 3) = -pre.dp_dbg();
    J.block<3, 3>(6, 6) = -pre.dp_dba();
    J.block<3, 3>(9, 3) = -I3;
    J.block<3, 3>(12, 6) = -I3;
    Eigen::Map<SpeedBiasJacobian>{jacobians[1]} = S * J;
  }
  if (jacobians[2] != nullptr) {  // pose_j
    LocalPoseJacobian J = LocalPoseJacobian::Zero();
    J.block<3, 3>(0, 3) = Jr_inv * b.Rj.transpose();
    J.block<3, 3>(6, 0) = RiT;
    Eigen::Map<PoseJacobian> out(jacobians[2]);
    out.leftCols<3>() = S * J.leftCols<3>();
    out.rightCols<4>() = QuaternionJacobian(S * J.rightCols<3>(), b.qj);
  }
  if (jacobians[3] != nullptr) {  // speed_bias_j
    SpeedBiasJacobian J = SpeedBiasJacobian::Zero();
    J.block<3, 3>(3, 0) = RiT;
    J.block<3, 3>(9, 3) = I3;
    J.block<3, 3>(12, 6) = I3;
    Eigen::Map<SpeedBiasJacobian>{jacobians[3]} = S * J;
  }
}

}  // namespace

bool ImuFactor::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  EvaluateImu(preintegration_, sqrt_information_, gravity_world_mps2_, parameters, residuals, jacobians);
  return true;
}

std::unique_ptr<ceres::Manifold> MakeGravityManifold() { return std::make_unique<ceres::SphereManifold<3>>(); }

ImuGravityFactor::ImuGravityFactor(const PreintegratedImu& preintegration)
    : core_(preintegration, Vector3d::Zero()) {}

ImuFactor::Vector15d ImuGravityFactor::UnwhitenedResidual(const double* pose_i, const double* speed_bias_i,
                                                          const double* pose_j, const double* speed_bias_j,
                                                          const double* gravity3) const {
  const double* parameters[4] = {pose_i, speed_bias_i, pose_j, speed_bias_j};
  return ComputeTerms(ReadBlocks(parameters), core_.preintegration(), Eigen::Map<const Vector3d>(gravity3)).r;
}

// g enters r_v = R_i^T (... - g dt) and r_p = R_i^T (... - g dt^2 / 2) linearly, so the gravity Jacobian is exact
// in the ambient coordinates; Ceres maps it to the sphere's 2-dof tangent. The pose_i Jacobian already uses the
// block's g through x_v and x_p.
bool ImuGravityFactor::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  const Vector3d g = Eigen::Map<const Vector3d>(parameters[4]);
  EvaluateImu(core_.preintegration(), core_.sqrt_information(), g, parameters, residuals, jacobians);
  if (jacobians == nullptr || jacobians[4] == nullptr) return true;
  const double T = core_.preintegration().dt_s();
  const Matrix3d RiT = Eigen::Map<const Eigen::Quaterniond>(parameters[0] + 3).normalized().toRotationMatrix()
                           .transpose();
  Eigen::Matrix<double, kImuResidualSize, kGravityBlockSize> J;
  J.setZero();
  J.block<3, 3>(3, 0) = -RiT * T;
  J.block<3, 3>(6, 0) = -RiT * (0.5 * T * T);
  Eigen::Map<Eigen::Matrix<double, kImuResidualSize, kGravityBlockSize, Eigen::RowMajor>>{jacobians[4]} =
      core_.sqrt_information() * J;
  return true;
}

}  // namespace rotolidar
