#pragma once
// Ceres factor for one preintegrated IMU interval between states i and j (Forster TRO 2017, eq. 45), with the
// bias random walk in the same factor. docs/imu_preintegration.md derives the residual and its Jacobians.
//
// Parameter blocks (all in the world frame, z up; "imu" = the IMU's measurement axes):
//   pose_i, pose_j   [tx ty tz qx qy qz qw]  (7)  T_world_imu: t = the imu origin in world [m], q = the unit
//                                                 quaternion of R_world_imu in Eigen's memory order (x y z w).
//                                                 Manifold: MakeImuPoseManifold() =
//                                                 ProductManifold<EuclideanManifold<3>, EigenQuaternionManifold>.
//   speed_bias_i, _j [vx vy vz bgx bgy bgz bax bay baz]  (9)  v_world [m/s], gyro bias [rad/s] and accel
//                                                 bias [m/s^2] in the imu frame. Euclidean.
// Residual (15), whitened by the square root information of its covariance:
//   [0:3)   r_R  = Log( (dR Exp(J_R^g dbg))^T R_i^T R_j )                                       [rad]
//   [3:6)   r_v  = R_i^T (v_j - v_i - g dt) - (dv + J_v^g dbg + J_v^a dba)                       [m/s]
//   [6:9)   r_p  = R_i^T (p_j - p_i - v_i dt - g dt^2/2) - (dp + J_p^g dbg + J_p^a dba)          [m]
//   [9:12)  r_bg = bg_j - bg_i                                                                 [rad/s]
//   [12:15) r_ba = ba_j - ba_i                                                                 [m/s^2]
// with dbg = bg_i - bg_lin, dba = ba_i - ba_lin (the preintegration's linearisation biases). Covariance:
// blockdiag(the preintegration's 9x9 (eq. 63), gyro_random_walk^2 dt I3, accel_random_walk^2 dt I3).
// One 15-residual factor rather than 9 + a separate bias factor: both use the same four blocks and dt, the
// covariance is block diagonal so the cost is identical, and the window adds one factor per interval.
//
// The quaternion is normalised inside Evaluate; at a unit quaternion (what the manifold keeps) the Jacobians
// w.r.t. the 4 quaternion coordinates are the exact derivatives of r(q / |q|), and Ceres maps them to the
// 3-dof tangent with the manifold's PlusJacobian.
// The factor copies the preintegration: re-create it after PreintegratedImu::Repropagate.
// Thread safety: Evaluate is const and may run concurrently.
#include <memory>

#include <ceres/manifold.h>
#include <ceres/sized_cost_function.h>
#include <Eigen/Core>

#include "core/imu/preintegration.hpp"
#include "core/types/geometry.hpp"

namespace rotolidar {

inline constexpr int kImuPoseBlockSize = 7;        ///< [tx ty tz qx qy qz qw]
inline constexpr int kImuSpeedBiasBlockSize = 9;   ///< [v(3) bg(3) ba(3)]
inline constexpr int kImuResidualSize = 15;        ///< [r_R r_v r_p r_bg r_ba]
inline constexpr int kGravityBlockSize = 3;        ///< [gx gy gz] gravity in world [m/s^2]

/// The manifold of a pose block: ProductManifold<EuclideanManifold<3>, EigenQuaternionManifold>.
/// ceres::Problem takes ownership by default: problem.SetManifold(pose, MakeImuPoseManifold().release()).
std::unique_ptr<ceres::Manifold> MakeImuPoseManifold();

/// The manifold of an estimated gravity block: ceres::SphereManifold<3> (|g| stays at its initial value; the
/// 2-dof tangent is its direction).
std::unique_ptr<ceres::Manifold> MakeGravityManifold();

/// Pose block <-> T_world_imu / NavState (the quaternion is normalised when read).
void PackImuPose(const Pose3& T_world_imu, double* pose7);
Pose3 UnpackImuPose(const double* pose7);
void PackImuState(const NavState& state, double* pose7, double* speed_bias9);
NavState UnpackImuState(const double* pose7, const double* speed_bias9);

class ImuFactor final : public ceres::SizedCostFunction<kImuResidualSize, kImuPoseBlockSize,
                                                        kImuSpeedBiasBlockSize, kImuPoseBlockSize,
                                                        kImuSpeedBiasBlockSize> {
 public:
  using Vector15d = Eigen::Matrix<double, 15, 1>;
  using Matrix15d = Eigen::Matrix<double, 15, 15>;

  /// Copies `preintegration` (dt_s() must be > 0: a bug otherwise). gravity in world [m/s^2].
  /// Covariance eigenvalues below kMinVariance are raised to it so that noise-free (sim) data or a one-step
  /// interval (rank-deficient covariance) still give a finite square root information.
  ImuFactor(const PreintegratedImu& preintegration, const Eigen::Vector3d& gravity_world_mps2);

  /// parameters: {pose_i, speed_bias_i, pose_j, speed_bias_j}. Always returns true.
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

  /// The unwhitened residual at the given blocks (for diagnostics and tests).
  Vector15d UnwhitenedResidual(const double* pose_i, const double* speed_bias_i, const double* pose_j,
                               const double* speed_bias_j) const;

  const Matrix15d& covariance() const { return covariance_; }
  const Matrix15d& sqrt_information() const { return sqrt_information_; }  ///< S with S^T S = covariance^-1
  const PreintegratedImu& preintegration() const { return preintegration_; }

  static constexpr double kMinVariance = 1e-12;  ///< floor on covariance eigenvalues (rad^2, (m/s)^2, m^2, ...)

 private:
  PreintegratedImu preintegration_;
  Eigen::Vector3d gravity_world_mps2_;
  Matrix15d covariance_;
  Matrix15d sqrt_information_;
};

/// The ImuFactor with gravity as a fifth parameter block instead of a constant, for a window that estimates
/// gravity's direction (core/backend/sliding_window.hpp):
///   gravity  [gx gy gz]  (3)  g in world [m/s^2]. Manifold: MakeGravityManifold() (sphere, |g| fixed).
/// Same residual, covariance and state Jacobians; in ambient coordinates dr_v/dg = -R_i^T dt,
/// dr_p/dg = -R_i^T dt^2 / 2 (exact: g enters linearly), mapped by Ceres to the sphere's tangent.
class ImuGravityFactor final : public ceres::SizedCostFunction<kImuResidualSize, kImuPoseBlockSize,
                                                               kImuSpeedBiasBlockSize, kImuPoseBlockSize,
                                                               kImuSpeedBiasBlockSize, kGravityBlockSize> {
 public:
  /// Copies `preintegration` (dt_s() must be > 0).
  explicit ImuGravityFactor(const PreintegratedImu& preintegration);

  /// parameters: {pose_i, speed_bias_i, pose_j, speed_bias_j, gravity}. Always returns true.
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

  ImuFactor::Vector15d UnwhitenedResidual(const double* pose_i, const double* speed_bias_i, const double* pose_j,
                                          const double* speed_bias_j, const double* gravity3) const;

  const ImuFactor::Matrix15d& sqrt_information() const { return core_.sqrt_information(); }
  const PreintegratedImu& preintegration() const { return core_.preintegration(); }

 private:
  ImuFactor core_;  ///< covariance and preintegration; its constant gravity is unused
};

}  // namespace rotolidar
