#include "core/visual/reprojection_factor.hpp"

#include <cmath>

#include <Eigen/Geometry>

#include "core/imu/pose_block_view.hpp"
#include "core/imu/preintegration.hpp"
#include "core/util/log.hpp"

namespace rotolidar {

namespace {

using Eigen::Matrix2d;
using Eigen::Matrix3d;
using Eigen::Quaterniond;
using Eigen::Vector2d;
using Eigen::Vector3d;
using Jac23 = Eigen::Matrix<double, 2, 3>;

using detail::PoseView;
using detail::ReadPose;

PoseView ViewOf(const Pose3& T) {
  double pose7[kImuPoseBlockSize];
  PackImuPose(T, pose7);
  return ReadPose(pose7);
}

/// The chain anchor camera -> imu a -> world -> imu j -> camera j, every point scaled by rho (see the header).
struct Chain {
  PoseView a, j, ic;
  Vector3d u_a;  ///< [x_a, y_a, 1]
  double rho = 0.0;
  Matrix3d M;    ///< R_ci R_j^T
  Vector3d m;    ///< R_ic u_a + rho t_ic = rho p_imu_a
  Vector3d w;    ///< R_a m + rho t_a = rho p_world
  Vector3d s;    ///< R_j^T (w - rho t_j) = rho p_imu_j
  Vector3d q;    ///< R_ci (s - rho t_ic) = rho p_cj
};

Chain MakeChain(const PoseView& a, const PoseView& j, const PoseView& ic, const Vector2d& u_a, double rho) {
  Chain c{a, j, ic, Vector3d(u_a.x(), u_a.y(), 1.0), rho, Matrix3d(), Vector3d(), Vector3d(), Vector3d(),
          Vector3d()};
  c.M = ic.R.transpose() * j.R.transpose();
  c.m = ic.R * c.u_a + rho * ic.t;
  c.w = a.R * c.m + rho * a.t;
  c.s = j.R.transpose() * (c.w - rho * j.t);
  c.q = ic.R.transpose() * (c.s - rho * ic.t);
  return c;
}

/// q_z with the clamp |q_z| >= kMinProjectiveZ (sign kept, + at 0); *clamped tells whether it applied.
double ClampedZ(double z, bool* clamped) {
  *clamped = std::abs(z) < kMinProjectiveZ;
  if (!*clamped) return z;
  return z < 0.0 ? -kMinProjectiveZ : kMinProjectiveZ;
}

Vector2d Project(const Vector3d& q) {
  bool clamped = false;
  const double z = ClampedZ(q.z(), &clamped);
  return q.head<2>() / z;
}

/// d pi / d q at q (the clamped function: no z column inside the clamp band).
Jac23 ProjectJacobian(const Vector3d& q) {
  bool clamped = false;
  const double z = ClampedZ(q.z(), &clamped);
  Jac23 A;
  A << 1.0 / z, 0.0, clamped ? 0.0 : -q.x() / (z * z),  //
      0.0, 1.0 / z, clamped ? 0.0 : -q.y() / (z * z);
  return A;
}

/// The EigenQuaternionManifold's PlusJacobian at unit q (x y z w): orthonormal columns, all orthogonal to q.
Eigen::Matrix<double, 4, 3> QuaternionPlusJacobian(const Quaterniond& q) {
  Eigen::Matrix<double, 4, 3> P;
  P.topRows<3>() = q.w() * Matrix3d::Identity() - so3::Hat(q.vec());
  P.bottomRows<1>() = -q.vec().transpose();
  return P;
}

/// Writes [J_t, 2 J_theta P^T] (2 x 7, row-major): the exact derivative of r(t, q / |q|) at unit q.
void WritePoseJacobian(const Jac23& J_t, const Jac23& J_theta, const Quaterniond& q, double* out) {
  Eigen::Map<Eigen::Matrix<double, 2, kImuPoseBlockSize, Eigen::RowMajor>> J(out);
  J.leftCols<3>() = J_t;
  J.rightCols<4>() = 2.0 * J_theta * QuaternionPlusJacobian(q).transpose();
}

/// r = S (pi(q) - u_j) and the Jacobians of blocks 0..2 {pose_a, pose_j, rho} where requested. Returns S A for
/// the caller's 4th block.
Jac23 EvaluateCommon(const Chain& c, const Matrix2d& S, const Vector2d& u_j, double* residuals,
                     double** jacobians) {
  Eigen::Map<Vector2d>{residuals} = S * (Project(c.q) - u_j);
  const Jac23 SA = S * ProjectJacobian(c.q);
  if (jacobians == nullptr) return SA;
  const Jac23 SAM = SA * c.M;
  if (jacobians[0] != nullptr) {
    WritePoseJacobian(c.rho * SAM, -SAM * so3::Hat(c.a.R * c.m), c.a.q, jacobians[0]);
  }
  if (jacobians[1] != nullptr) {
    WritePoseJacobian(-c.rho * SAM, SAM * so3::Hat(c.w - c.rho * c.j.t), c.j.q, jacobians[1]);
  }
  if (jacobians[2] != nullptr) {
    const Vector3d b = c.M * (c.a.R * c.ic.t + c.a.t - c.j.t) - c.ic.R.transpose() * c.ic.t;
    Eigen::Map<Vector2d>{jacobians[2]} = SA * b;
  }
  return SA;
}

}  // namespace

// -------------------------------------------------------------------------------------------- free functions

Pose3 CameraExtrinsic(const RigCalib& calib) { return calib.T_base_imu.inverse() * calib.T_base_cam; }

Matrix2d ReprojectionSqrtInformation(double focal_px, double sigma_px) {
  ROTOLIDAR_CHECK(focal_px > 0.0 && sigma_px > 0.0, "focal_px and sigma_px must be > 0");
  return (focal_px / sigma_px) * Matrix2d::Identity();
}

Matrix2d ReprojectionSqrtInformation(const CameraIntrinsics& camera, double sigma_px) {
  ROTOLIDAR_CHECK(camera.fx_px > 0.0 && camera.fy_px > 0.0 && sigma_px > 0.0, "fx, fy and sigma_px must be > 0");
  return Vector2d(camera.fx_px / sigma_px, camera.fy_px / sigma_px).asDiagonal();
}

Vector2d PredictNormalized(const Pose3& T_world_imu_a, const Pose3& T_world_imu_j, const Pose3& T_imu_cam,
                           const Vector2d& anchor_normalized, double inverse_depth) {
  return Project(MakeChain(ViewOf(T_world_imu_a), ViewOf(T_world_imu_j), ViewOf(T_imu_cam), anchor_normalized,
                           inverse_depth).q);
}

bool LandmarkInFront(const Pose3& T_world_imu_a, const Pose3& T_world_imu_j, const Pose3& T_imu_cam,
                     const Vector2d& anchor_normalized, double inverse_depth, double min_depth_m) {
  if (!(inverse_depth > 0.0)) return false;  // also rejects NaN
  const Chain c = MakeChain(ViewOf(T_world_imu_a), ViewOf(T_world_imu_j), ViewOf(T_imu_cam), anchor_normalized,
                            inverse_depth);
  return c.q.z() / inverse_depth >= min_depth_m;  // Z_cj = q_z / rho
}

bool AnchorLandmark(const Pose3& T_world_imu_a, const Pose3& T_imu_cam, const Vector3d& p_world_m,
                    Vector2d* anchor_normalized, double* inverse_depth) {
  const Vector3d p_ca = (T_world_imu_a * T_imu_cam).inverse() * p_world_m;
  if (!(p_ca.z() > 0.0)) return false;
  *anchor_normalized = p_ca.head<2>() / p_ca.z();
  *inverse_depth = 1.0 / p_ca.z();
  return true;
}

// ------------------------------------------------------------------------------------------ ReprojectionFactor

ReprojectionFactor::ReprojectionFactor(const ReprojectionMeasurement& measurement, const Pose3& T_imu_cam)
    : measurement_(measurement) {
  PackImuPose(T_imu_cam, extrinsic_);
}

Vector2d ReprojectionFactor::Error(const double* pose_a, const double* pose_j, const double* inverse_depth) const {
  const Chain c = MakeChain(ReadPose(pose_a), ReadPose(pose_j), ReadPose(extrinsic_),
                            measurement_.anchor_normalized, inverse_depth[0]);
  return Project(c.q) - measurement_.normalized;
}

bool ReprojectionFactor::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  const Chain c = MakeChain(ReadPose(parameters[0]), ReadPose(parameters[1]), ReadPose(extrinsic_),
                            measurement_.anchor_normalized, parameters[2][0]);
  EvaluateCommon(c, measurement_.sqrt_information, measurement_.normalized, residuals, jacobians);
  return true;
}

// ---------------------------------------------------------------------------------- ReprojectionExtrinsicFactor

ReprojectionExtrinsicFactor::ReprojectionExtrinsicFactor(const ReprojectionMeasurement& measurement)
    : measurement_(measurement) {}

Vector2d ReprojectionExtrinsicFactor::Error(const double* pose_a, const double* pose_j, const double* inverse_depth,
                                            const double* extrinsic) const {
  const Chain c = MakeChain(ReadPose(pose_a), ReadPose(pose_j), ReadPose(extrinsic),
                            measurement_.anchor_normalized, inverse_depth[0]);
  return Project(c.q) - measurement_.normalized;
}

bool ReprojectionExtrinsicFactor::Evaluate(double const* const* parameters, double* residuals,
                                           double** jacobians) const {
  const Chain c = MakeChain(ReadPose(parameters[0]), ReadPose(parameters[1]), ReadPose(parameters[3]),
                            measurement_.anchor_normalized, parameters[2][0]);
  const Jac23 SA = EvaluateCommon(c, measurement_.sqrt_information, measurement_.normalized, residuals, jacobians);
  if (jacobians != nullptr && jacobians[3] != nullptr) {
    // R_ic <- Exp(phi) R_ic moves m by -[R_ic u_a]x phi and turns R_ci by Exp(-phi); t_ic enters m and q.
    const Matrix3d R_ci = c.ic.R.transpose(), RjT_Ra = c.j.R.transpose() * c.a.R;
    const Matrix3d dq_dt = c.rho * R_ci * (RjT_Ra - Matrix3d::Identity());
    const Matrix3d dq_dtheta = R_ci * (so3::Hat(c.s - c.rho * c.ic.t) - RjT_Ra * so3::Hat(c.ic.R * c.u_a));
    WritePoseJacobian(SA * dq_dt, SA * dq_dtheta, c.ic.q, jacobians[3]);
  }
  return true;
}

// --------------------------------------------------------------------------------- ReprojectionTimeOffsetFactor

ReprojectionTimeOffsetFactor::ReprojectionTimeOffsetFactor(const ReprojectionMeasurement& measurement,
                                                           const FeatureMotion& motion, const Pose3& T_imu_cam)
    : measurement_(measurement), motion_(motion) {
  PackImuPose(T_imu_cam, extrinsic_);
}

Vector2d ReprojectionTimeOffsetFactor::Error(const double* pose_a, const double* pose_j,
                                             const double* inverse_depth, const double* td) const {
  const Vector2d u_a = measurement_.anchor_normalized - (td[0] - motion_.anchor_td_s) * motion_.anchor_velocity;
  const Vector2d u_j = measurement_.normalized - (td[0] - motion_.td_s) * motion_.velocity;
  return Project(MakeChain(ReadPose(pose_a), ReadPose(pose_j), ReadPose(extrinsic_), u_a, inverse_depth[0]).q) -
         u_j;
}

bool ReprojectionTimeOffsetFactor::Evaluate(double const* const* parameters, double* residuals,
                                            double** jacobians) const {
  const double td = parameters[3][0];
  const Vector2d u_a = measurement_.anchor_normalized - (td - motion_.anchor_td_s) * motion_.anchor_velocity;
  const Vector2d u_j = measurement_.normalized - (td - motion_.td_s) * motion_.velocity;
  const Chain c = MakeChain(ReadPose(parameters[0]), ReadPose(parameters[1]), ReadPose(extrinsic_), u_a,
                            parameters[2][0]);
  const Matrix2d& S = measurement_.sqrt_information;
  const Jac23 SA = EvaluateCommon(c, S, u_j, residuals, jacobians);
  if (jacobians != nullptr && jacobians[3] != nullptr) {
    // dq/du_a = C = M R_a R_ic, du_a/dtd = -[v_a; 0]; du_j/dtd = -v_j enters r with a minus sign.
    const Vector3d v_a(motion_.anchor_velocity.x(), motion_.anchor_velocity.y(), 0.0);
    Eigen::Map<Vector2d>{jacobians[3]} = -SA * (c.M * c.a.R * c.ic.R * v_a) + S * motion_.velocity;
  }
  return true;
}

}  // namespace rotolidar
