#pragma once
// Visual reprojection factor of the sliding window with inverse-depth landmarks (VINS-Mono's
// ProjectionTwoFrameOneCamFactor and its td variant, as LVI-SAM uses them), in this project's pose conventions.
//
// Landmark: anchored in the camera frame of its first observation (anchor frame a) by u_a = [x_a, y_a, 1], the
// undistorted normalised coordinates there (measured, fixed), and its inverse depth rho [1/m] (a 1-dim block):
// p_ca = u_a / rho. Observation in frame j: u_j = [x_j, y_j] (undistorted normalised coordinates).
//   p_cj = T_cam_imu * T_world_imu_j^-1 * T_world_imu_a * T_imu_cam * p_ca
//   r (2) = S (pi(p_cj) - u_j),   pi([X, Y, Z]) = [X / Z, Y / Z]
// The residual lives on the NORMALISED image plane (unit: 1 = one focal length); S whitens it. For an isotropic
// pixel sigma, S = f_px / sigma_px * I2 (ReprojectionSqrtInformation), so |r| counts pixel errors in sigmas.
// Robust loss (Huber / Cauchy on this whitened r, e.g. ceres::HuberLoss(1.0)) is the caller's choice.
//
// Blocks: pose_a, pose_j [tx ty tz qx qy qz qw] (7) = T_world_imu (the ImuFactor's, core/imu/imu_factor.hpp;
// manifold MakeImuPoseManifold()); inverse depth [rho] (1, Euclidean) [1/m]. T_imu_cam = T_base_imu^-1 *
// T_base_cam (CameraExtrinsic) is a constant in ReprojectionFactor and a 4th block (7, same layout, T_imu_cam,
// same manifold) in ReprojectionExtrinsicFactor (online extrinsic estimation). ReprojectionTimeOffsetFactor adds
// the camera-IMU time offset td [s] (1) as a 4th block: u_a and u_j are moved along their tracked normalised
// velocities, u(td) = u - (td - td_meas) v, td_meas = the td the frame was stamped with (VINS-Mono's td).
// Online extrinsic estimation needs rotation about two axes in the window: with one axis n, t_ic along n cancels
// in T_ic^-1 T_a_j T_ic and is unobservable (hold the extrinsic constant, or add a prior, until then).
// For marginalisation (core/backend/pose_factors.hpp) the inverse depth and td are BlockKind::kVector blocks.
//
// Homogeneous evaluation: pi is scale invariant, so the factor projects q = rho * p_cj, which is linear in rho:
//   q = C u_a + rho b,   C = R_ci R_j^T R_a R_ic,   b = R_ci (R_j^T (R_a t_ic + t_a - t_j) - t_ic)
// with (R_a, t_a), (R_j, t_j), (R_ic, t_ic) the rotations / translations of T_world_imu_a, T_world_imu_j,
// T_imu_cam and R_ci = R_ic^T.
// pi(q) = pi(p_cj) for every rho != 0 and stays finite at rho = 0 (a point at infinity: rotation only).
//
// Jacobians (tangent convention of core/backend/pose_factors.hpp: T (+) xi = (t + dt, Exp(dtheta) R), world-left;
// for the extrinsic the "world" is the imu frame). With A = d pi / d q = [1/z, 0, -x/z^2; 0, 1/z, -y/z^2],
// M = R_ci R_j^T, m = R_ic u_a + rho t_ic (= rho p_imu_a), w = R_a m + rho t_a (= rho p_world):
//   dq/dt_a = rho M           dq/dtheta_a = -M [R_a m]x
//   dq/dt_j = -rho M          dq/dtheta_j = M [w - rho t_j]x
//   dq/drho = b
//   dq/dt_ic = rho R_ci (R_j^T R_a - I)     dq/dtheta_ic = R_ci ([s - rho t_ic]x - R_j^T R_a [R_ic u_a]x),
//                                           s = R_j^T (w - rho t_j)
//   dr/dtd = S (-A C v_a + v_j)   (v = [vx, vy, 0] the tracked normalised velocities [1/s])
// and dr/d. = S A dq/d. . Pose blocks get [dr/dt, 2 dr/dtheta P^T] (P = the quaternion manifold's PlusJacobian):
// every factor reads q / |q|, and at a unit quaternion this is the exact derivative of r(t, q / |q|), as in
// pose_factors.cpp and imu_factor.cpp.
//
// Degenerate geometry (decided): Evaluate ALWAYS returns true with finite values for finite inputs; Ceres would
// treat false as an invalid step, and at the initial point as a failed solve of the whole window. pi cannot tell a
// point from its mirror image (pi(-q) = pi(q)), so a landmark behind a camera (rho <= 0 or Z_cj <= 0) may still
// have a small residual. Only the band |q_z| < kMinProjectiveZ (q_z = Z_cj / Z_ca, or the ray's z at rho = 0) is
// modified: q_z is clamped to +-kMinProjectiveZ (sign kept, + at 0) and its Jacobian column is zero there.
// The CALLER checks LandmarkInFront() for every observation before adding a landmark and after each solve, and
// drops (or re-initialises) the failures, as VINS-Mono's removeFailures does.
//
// Thread safety: factors are immutable after construction; Evaluate is const and may run concurrently. The free
// functions have no state. Bad configuration (sigma_px <= 0) is a programmer error (ROTOLIDAR_CHECK).
#include <ceres/sized_cost_function.h>
#include <Eigen/Core>

#include "core/imu/imu_factor.hpp"
#include "core/types/calib.hpp"
#include "core/types/geometry.hpp"

namespace rotolidar {

inline constexpr int kReprojectionResidualSize = 2;  ///< [r_x r_y] on the normalised plane, whitened
inline constexpr int kInverseDepthBlockSize = 1;     ///< [rho] [1/m]
inline constexpr int kTimeOffsetBlockSize = 1;       ///< [td] [s], t_imu = t_cam + td
inline constexpr double kMinProjectiveZ = 1e-6;      ///< |q_z| clamp of pi, q = rho p_cj (dimensionless)

/// One observation of a landmark in frame j together with its anchor observation.
struct ReprojectionMeasurement {
  Eigen::Vector2d anchor_normalized = Eigen::Vector2d::Zero();  ///< u_a in the anchor camera (undistorted)
  Eigen::Vector2d normalized = Eigen::Vector2d::Zero();         ///< u_j in camera j (undistorted)
  /// S (2x2) of the normalised-plane residual, e.g. ReprojectionSqrtInformation(f_px, sigma_px) [1/normalised].
  Eigen::Matrix2d sqrt_information = Eigen::Matrix2d::Identity();
};

/// Feature motion for the time-offset variant: tracked velocities on the normalised plane [1/s]
/// (visual::TrackedFeature::velocity_normalized_ps) and the td [s] each frame was stamped with (VINS-Mono's
/// velocity_i / td_i and velocity_j / td_j).
struct FeatureMotion {
  Eigen::Vector2d anchor_velocity = Eigen::Vector2d::Zero();
  Eigen::Vector2d velocity = Eigen::Vector2d::Zero();
  double anchor_td_s = 0.0;
  double td_s = 0.0;
};

/// T_imu_cam = T_base_imu^-1 * T_base_cam of the rig calibration.
Pose3 CameraExtrinsic(const RigCalib& calib);

/// S = focal_px / sigma_px * I2: the whitening of a normalised-plane residual for an isotropic pixel sigma.
/// Checked: focal_px > 0, sigma_px > 0.
Eigen::Matrix2d ReprojectionSqrtInformation(double focal_px, double sigma_px);
/// S = diag(fx, fy) / sigma_px: the same for a camera with different focal lengths.
Eigen::Matrix2d ReprojectionSqrtInformation(const CameraIntrinsics& camera, double sigma_px);

/// The predicted normalised observation pi(p_cj) of a landmark (anchor u_a, inverse depth rho) in frame j; the
/// same function the factors evaluate (including the |q_z| clamp), so r = S (PredictNormalized(...) - u_j).
Eigen::Vector2d PredictNormalized(const Pose3& T_world_imu_a, const Pose3& T_world_imu_j, const Pose3& T_imu_cam,
                                  const Eigen::Vector2d& anchor_normalized, double inverse_depth);

/// True when rho > 0 and the landmark's depth Z_cj in camera j is >= min_depth_m [m] (with j = a: 1 / rho >=
/// min_depth_m). For gating landmarks before they are added and after each solve.
bool LandmarkInFront(const Pose3& T_world_imu_a, const Pose3& T_world_imu_j, const Pose3& T_imu_cam,
                     const Eigen::Vector2d& anchor_normalized, double inverse_depth, double min_depth_m = 0.1);

/// Anchors a world point (e.g. a LiDAR depth, as LVI-SAM associates) in camera a: writes u_a and rho = 1 / Z_ca.
/// Returns false (outputs untouched) unless the point is in front of the camera (Z_ca > 0).
bool AnchorLandmark(const Pose3& T_world_imu_a, const Pose3& T_imu_cam, const Eigen::Vector3d& p_world_m,
                    Eigen::Vector2d* anchor_normalized, double* inverse_depth);

/// Reprojection with a constant extrinsic. parameters: {pose_a, pose_j, inverse_depth}. Always returns true.
class ReprojectionFactor final
    : public ceres::SizedCostFunction<kReprojectionResidualSize, kImuPoseBlockSize, kImuPoseBlockSize,
                                      kInverseDepthBlockSize> {
 public:
  ReprojectionFactor(const ReprojectionMeasurement& measurement, const Pose3& T_imu_cam);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;
  /// The unwhitened residual pi(p_cj) - u_j.
  Eigen::Vector2d Error(const double* pose_a, const double* pose_j, const double* inverse_depth) const;
  const ReprojectionMeasurement& measurement() const { return measurement_; }

 private:
  ReprojectionMeasurement measurement_;
  double extrinsic_[kImuPoseBlockSize];
};

/// Reprojection with the extrinsic T_imu_cam as a block. parameters: {pose_a, pose_j, inverse_depth, T_imu_cam}.
class ReprojectionExtrinsicFactor final
    : public ceres::SizedCostFunction<kReprojectionResidualSize, kImuPoseBlockSize, kImuPoseBlockSize,
                                      kInverseDepthBlockSize, kImuPoseBlockSize> {
 public:
  explicit ReprojectionExtrinsicFactor(const ReprojectionMeasurement& measurement);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;
  Eigen::Vector2d Error(const double* pose_a, const double* pose_j, const double* inverse_depth,
                        const double* extrinsic) const;

 private:
  ReprojectionMeasurement measurement_;
};

/// Reprojection with the time offset td as a block and a constant extrinsic.
/// parameters: {pose_a, pose_j, inverse_depth, td}.
class ReprojectionTimeOffsetFactor final
    : public ceres::SizedCostFunction<kReprojectionResidualSize, kImuPoseBlockSize, kImuPoseBlockSize,
                                      kInverseDepthBlockSize, kTimeOffsetBlockSize> {
 public:
  ReprojectionTimeOffsetFactor(const ReprojectionMeasurement& measurement, const FeatureMotion& motion,
                               const Pose3& T_imu_cam);
  bool Evaluate(double const* const* parameters, double* residuals, double** jacobians) const override;
  Eigen::Vector2d Error(const double* pose_a, const double* pose_j, const double* inverse_depth,
                        const double* td) const;

 private:
  ReprojectionMeasurement measurement_;
  FeatureMotion motion_;
  double extrinsic_[kImuPoseBlockSize];
};

}  // namespace rotolidar
