#pragma once
// Pose factors of the sliding-window back end (seed paper Sec. 3.3, "LiDAR odometry factor"), the linearised prior
// that carries marginalised information, and the Schur-complement marginalisation that produces it.
// docs/backend.md derives every residual and Jacobian.
//
// Blocks: the ImuFactor's (core/imu/imu_factor.hpp): pose [tx ty tz qx qy qz qw] = T_world_imu with the manifold
// MakeImuPoseManifold(), speed-bias [v_world bg ba] (9, Euclidean).
//
// Tangent convention of a pose (every information matrix, Jacobian and prior here; the same as the registration
// Hessian, core/registration/scan_to_map.hpp):
//   xi = [dt (m, world); dtheta (rad, world)],   T (+) xi = (t + dt, Exp(dtheta) R)      (translation FIRST)
// i.e. rotations are perturbed on the left, in the world frame. Ceres' pose manifold has the same ordering and
// the same left perturbation, but its rotation coordinate is dtheta / 2 (EigenQuaternionManifold's
// q <- [cos|d|, sin|d| d/|d|] * q turns by 2|d|); ToPoseTangentJacobian() converts.
// Relative poses use the same convention in frame i: T_i_j (+) xi = (t + dt, Exp(dtheta) R), xi in frame i.
//
// Every factor normalises the quaternion it reads; the Jacobians w.r.t. the 4 quaternion coordinates are the exact
// derivatives of r(q / |q|) (as ImuFactor), so Ceres' GradientChecker and the manifold agree.
// Thread safety: factors are immutable after construction; Evaluate is const and may run concurrently.
#include <memory>
#include <string>
#include <vector>

#include <ceres/cost_function.h>
#include <ceres/loss_function.h>
#include <ceres/sized_cost_function.h>
#include <Eigen/Core>

#include "core/imu/imu_factor.hpp"
#include "core/types/geometry.hpp"

namespace rotolidar {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

/// A LiDAR odometry measurement of the imu frame's pose, as the LiDAR factor expects it.
struct LidarPoseMeasurement {
  Pose3 T_world_imu = Pose3::Identity();
  /// Information of the measurement error xi (T_true = T_meas (+) xi), tangent [dt; dtheta] of T_world_imu:
  /// units 1/m^2 (translation), 1/rad^2 (rotation), 1/(m rad) (cross). Symmetric positive SEMI-definite: a zero
  /// (or tiny) eigenvalue leaves that direction to the IMU (a degenerate registration).
  Matrix6d information = Matrix6d::Identity();
  // Used only where the window estimates an offset (core/backend/lidar_offset_factor.hpp):
  /// the rotor-angle offset [rad] already removed from this scan's encoder angles by the deskew (the window's
  /// estimate at that time);
  double rotor_offset_applied_rad = 0.0;
  /// the IMU time offset [s] already removed from the IMU stamps (IMU stamp = rig time + td);
  double time_offset_applied_s = 0.0;
  /// the body rate at the measurement's time (gyro less its bias estimate), imu frame [rad/s].
  Eigen::Vector3d angular_velocity_imu_radps = Eigen::Vector3d::Zero();
};

/// Information of a scan-to-map result: P^T (H / sigma^2) P, symmetrised. H = J^T J of the point residuals [m]
/// (ScanToMapResult::hessian, tangent [dt; dtheta] of T_world_base), point_sigma_m > 0 the effective per-point
/// residual sigma (it absorbs the correlation between points; larger = trust the scan less), P the degeneracy
/// projection (DegeneracyInfo::projection, identity when none): P^T H P has no information along the directions
/// that P removes, so the IMU fills them. Checked: point_sigma_m > 0 (ROTOLIDAR_CHECK).
Matrix6d InformationFromRegistration(const Matrix6d& hessian, double point_sigma_m,
                                     const Matrix6d& projection = Matrix6d::Identity());

/// Converts a registration result in the base frame (T_world_base, information in its tangent) into the measurement
/// of the imu frame: T_world_imu = T_world_base * T_base_imu. The tangent map is exact and linear:
///   xi_imu = A xi_base,  A = [I, -[R_wb t_bi]x; 0, I],  information_imu = A^-T information_base A^-1.
LidarPoseMeasurement LidarMeasurementInImuFrame(const Pose3& T_world_base, const Matrix6d& information_base,
                                                const Pose3& T_base_imu);

/// S with S^T S = information (symmetric eigen-decomposition; negative round-off eigenvalues become 0).
Eigen::MatrixXd SqrtInformation(const Eigen::MatrixXd& information);

/// Maps a Jacobian w.r.t. the ambient pose coordinates [t(3) q(4)] (q read as unit, x y z w) to the tangent
/// [dt; dtheta] above: J_tangent = [J_t, J_q P / 2] with P = the quaternion manifold's PlusJacobian at q.
Eigen::MatrixXd ToPoseTangentJacobian(const Eigen::MatrixXd& J_ambient, const double* pose7);

/// Unary LiDAR odometry factor on one pose block: r = S [t - t_meas; Log(R R_meas^T)], S^T S = information.
class LidarPoseFactor final : public ceres::SizedCostFunction<6, kImuPoseBlockSize> {
 public:
  explicit LidarPoseFactor(const LidarPoseMeasurement& measurement);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;
  /// The unwhitened error [t - t_meas; Log(R R_meas^T)] at a pose block.
  Vector6d Error(const double* pose7) const;
  const LidarPoseMeasurement& measurement() const { return measurement_; }

 private:
  LidarPoseMeasurement measurement_;
  Matrix6d sqrt_information_;
};

/// Relative-pose factor between pose blocks i and j (odometry or loop closure), measurement T_i_j = T_wi^-1 T_wj
/// with information in the tangent of T_i_j (frame i):
///   r = S [R_i^T (t_j - t_i) - t_meas; Log(R_i^T R_j R_meas^T)].
class RelativePoseFactor final : public ceres::SizedCostFunction<6, kImuPoseBlockSize, kImuPoseBlockSize> {
 public:
  RelativePoseFactor(const Pose3& T_i_j_meas, const Matrix6d& information);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;
  Vector6d Error(const double* pose_i7, const double* pose_j7) const;

 private:
  Pose3 T_i_j_meas_;
  Matrix6d sqrt_information_;
};

/// How a prior (or marginalisation) sees one parameter block.
enum class BlockKind {
  kPose,    ///< 7 ambient [t q], 6 tangent [dt; dtheta]; x (-) x0 = [t - t0; Log(R R0^T)]
  kVector,  ///< n ambient = n tangent (speed-bias 9, a future inverse depth 1, ...); x (-) x0 = x - x0
};

/// A parameter block referenced by a prior or a marginalisation term. `values` is owned by the caller and must
/// outlive every factor and problem that uses it.
struct BlockRef {
  double* values = nullptr;
  BlockKind kind = BlockKind::kVector;
  int size = 0;  ///< ambient size: 7 for kPose
  int TangentSize() const { return kind == BlockKind::kPose ? 6 : size; }
};

/// Linearised (Gaussian) prior on a set of blocks: r = r0 + J dx, dx = [x_k (-) x0_k]_k stacked in block order.
/// The marginalisation prior (J, r0 from the Schur complement) and plain priors (J = sqrt information, r0 = 0)
/// are both this factor. Jacobians are exact: d Log(Exp(phi) R R0^T)/d phi = Jl^-1(Log(R R0^T)).
class LinearizedPriorFactor final : public ceres::CostFunction {
 public:
  /// linearization_points: one ambient vector per block (size = block's size). J: rows = r0.size(), cols = the sum
  /// of the blocks' tangent sizes. Mismatched sizes are a programmer error (ROTOLIDAR_CHECK).
  LinearizedPriorFactor(std::vector<BlockRef> blocks, std::vector<Eigen::VectorXd> linearization_points,
                        Eigen::MatrixXd J, Eigen::VectorXd r0);
  /// A prior on one block with information (tangent units) centred at `mean` (ambient, pose quaternion unit).
  static std::unique_ptr<LinearizedPriorFactor> Gaussian(const BlockRef& block, const Eigen::VectorXd& mean,
                                                         const Eigen::MatrixXd& information);

  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;

  const std::vector<BlockRef>& blocks() const { return blocks_; }
  std::vector<double*> block_values() const;  ///< the parameter pointers, for Problem::AddResidualBlock
  const Eigen::MatrixXd& J() const { return J_; }
  const Eigen::VectorXd& r0() const { return r0_; }

 private:
  std::vector<BlockRef> blocks_;
  std::vector<Eigen::VectorXd> x0_;
  Eigen::MatrixXd J_;
  Eigen::VectorXd r0_;
};

/// One factor that touches a block being marginalised. Not owned: the cost and loss must outlive the call.
struct MarginalizationTerm {
  const ceres::CostFunction* cost = nullptr;
  const ceres::LossFunction* loss = nullptr;  ///< may be null
  std::vector<BlockRef> blocks;               ///< in the cost function's parameter order
};

struct MarginalizationResult {
  bool success = false;
  std::string message;                            ///< why it failed
  std::unique_ptr<LinearizedPriorFactor> prior;   ///< on the kept blocks, linearised at their current values
  int rank = 0;                                   ///< rank of the Schur complement (rows of the prior)
};

/// Schur-complement marginalisation (Sibley et al. 2010; VINS-Mono's MarginalizationInfo): linearises every term
/// at the blocks' current values (robust losses through Ceres' corrector, Triggs et al.), and returns the prior on
/// the kept blocks whose J*^T J* = H_kk - H_kd H_dd^+ H_dk and J*^T r0 = b_k - H_kd H_dd^+ b_d for H = J^T J,
/// b = J^T r over [dropped; kept] tangents. Computed by pivoted QR on J (not on H, whose conditioning would be
/// squared); pivots below rank_threshold * the largest count as zero (a dropped direction no factor constrains
/// carries nothing; the prior keeps `rank` rows). Fails (success = false, message) when no block is kept, the
/// marginal is empty, terms disagree about a block, or a residual is not finite. Blocks are identified by their
/// `values` pointer; the prior's blocks are the kept ones in order of first appearance in `terms`.
MarginalizationResult Marginalize(const std::vector<MarginalizationTerm>& terms,
                                  const std::vector<const double*>& dropped, double rank_threshold = 1e-10);

}  // namespace rotolidar
