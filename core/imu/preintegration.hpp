#pragma once
// On-manifold IMU preintegration (Forster, Carlone, Dellaert, Scaramuzza, "On-Manifold Preintegration for
// Real-Time Visual-Inertial Odometry", IEEE TRO 2017, arXiv:1512.02363; "eq. N" below is that paper's numbering).
// docs/imu_preintegration.md derives every update implemented here.
//
// Frames: the IMU readings are in the imu frame (ImuSample); a navigation state holds the imu frame's pose in
// the world frame (R_world_imu, p_world_m = the imu origin in world) and its velocity in world. World is z up;
// gravity is a parameter (rotolidar: (0, 0, -9.81) m/s^2). The preintegrated deltas are expressed in the imu
// frame at the first sample time t_i ("frame i"):
//   dR = R_wi^T R_wj,  dv = R_wi^T (v_j - v_i - g dt),  dp = R_wi^T (p_j - p_i - v_i dt - 0.5 g dt^2)  (Sec. VI)
//
// Discretisation: "midpoint". Each step holds the (bias-corrected) readings constant over its interval dt and
// rotates the accelerometer reading into the interval's start frame with the half-step rotation Exp(w dt/2);
// the two-sample overload feeds the mean of the two samples' readings. This is second order in dt (the
// synthetic-trajectory test measures it); Forster's Euler step (Sec. V) is first order in dt for dv and dp.
//
// Noise: Kalibr continuous-time densities (ImuNoise). A step of length dt gets discrete white noise with
// covariance sigma^2 / dt per axis (Sec. V), independently of ImuNoise::rate_hz.
//
// Thread safety: const methods may be called concurrently; Integrate/Repropagate need exclusive access.
#include <vector>

#include <Eigen/Core>

#include "core/types/calib.hpp"
#include "core/types/messages.hpp"
#include "core/util/status.hpp"

namespace rotolidar {

namespace so3 {

/// The skew-symmetric matrix [w]x with [w]x v = w x v.
Eigen::Matrix3d Hat(const Eigen::Vector3d& w);
/// Right Jacobian of SO(3) (eq. 8): Exp(phi + d) ~= Exp(phi) Exp(Jr(phi) d).
Eigen::Matrix3d RightJacobian(const Eigen::Vector3d& phi_rad);
/// Inverse right Jacobian (eq. 9): Log(Exp(phi) Exp(d)) ~= phi + Jr^-1(phi) d. Valid for |phi| < pi.
Eigen::Matrix3d RightJacobianInverse(const Eigen::Vector3d& phi_rad);

}  // namespace so3

/// Pose, velocity and IMU biases of the imu frame at one time.
struct NavState {
  Eigen::Matrix3d R_world_imu = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p_world_m = Eigen::Vector3d::Zero();      ///< imu origin in world [m]
  Eigen::Vector3d v_world_mps = Eigen::Vector3d::Zero();    ///< imu origin's velocity in world [m/s]
  Eigen::Vector3d bias_gyro_radps = Eigen::Vector3d::Zero();  ///< gyro bias, imu frame [rad/s]
  Eigen::Vector3d bias_accel_mps2 = Eigen::Vector3d::Zero();  ///< accelerometer bias, imu frame [m/s^2]
};

/// The preintegrated deltas (expressed in frame i; see the file comment), possibly bias-corrected.
struct ImuDelta {
  Eigen::Matrix3d dR = Eigen::Matrix3d::Identity();
  Eigen::Vector3d dv_mps = Eigen::Vector3d::Zero();
  Eigen::Vector3d dp_m = Eigen::Vector3d::Zero();
  double dt_s = 0.0;
};

/// Accumulates IMU readings between two state times t_i and t_j (Forster Sec. V-VI, App. A-B).
/// Biases are held fixed at the linearisation point given at construction (or to Repropagate); a different
/// bias is applied to first order by Corrected()/Predict() (eq. 44). Every step is kept, so Repropagate() can
/// re-integrate exactly at new biases when the change is too large for the first-order correction (a common
/// rule: re-integrate when |dbg| > ~1e-2 rad/s or |dba| > ~0.1 m/s^2; the window owner decides).
class PreintegratedImu {
 public:
  using Matrix9d = Eigen::Matrix<double, 9, 9>;

  /// Biases are the linearisation point (imu frame). Noise densities must be >= 0 (checked; a bug otherwise).
  PreintegratedImu(const Eigen::Vector3d& bias_gyro_radps, const Eigen::Vector3d& bias_accel_mps2,
                   const ImuNoise& noise);

  /// Integrates one interval of length dt_s > 0 with the raw readings (imu frame, biases NOT removed) held
  /// constant over it. Returns an error (and changes nothing) when dt_s is not a positive finite number or a
  /// reading is not finite.
  Status Integrate(const Eigen::Vector3d& gyro_radps, const Eigen::Vector3d& accel_mps2, double dt_s);
  /// Integrates the interval [a.t_s, b.t_s] with the mean of the two samples' readings (midpoint scheme).
  /// Returns an error (and changes nothing) when b.t_s <= a.t_s or a value is not finite.
  Status Integrate(const ImuSample& a, const ImuSample& b);

  /// Re-integrates every stored step at new linearisation biases (exact, not first order).
  void Repropagate(const Eigen::Vector3d& bias_gyro_radps, const Eigen::Vector3d& bias_accel_mps2);

  /// The deltas at biases (linearisation + d_bias), first order (eq. 44). Zero corrections = the raw deltas.
  ImuDelta Corrected(const Eigen::Vector3d& d_bias_gyro_radps, const Eigen::Vector3d& d_bias_accel_mps2) const;

  /// State at t_j from the state at t_i (Sec. VI, with the bias correction of eq. 44, using state_i's biases).
  /// The returned state carries state_i's biases (the random walk's mean does not move).
  NavState Predict(const NavState& state_i, const Eigen::Vector3d& gravity_world_mps2) const;

  // Raw deltas at the linearisation biases (frame i).
  const Eigen::Matrix3d& delta_R() const { return dR_; }
  const Eigen::Vector3d& delta_v_mps() const { return dv_; }
  const Eigen::Vector3d& delta_p_m() const { return dp_; }
  double dt_s() const { return dt_s_; }
  int num_steps() const { return static_cast<int>(steps_.size()); }

  /// Covariance of the preintegration errors [dphi, dv, dp] (eq. 63), units rad^2, (m/s)^2, m^2.
  const Matrix9d& covariance() const { return cov_; }
  /// Bias Jacobians (App. B): derivatives of Log(dR), dv, dp w.r.t. the gyro/accel bias.
  const Eigen::Matrix3d& dR_dbg() const { return dR_dbg_; }
  const Eigen::Matrix3d& dv_dbg() const { return dv_dbg_; }
  const Eigen::Matrix3d& dv_dba() const { return dv_dba_; }
  const Eigen::Matrix3d& dp_dbg() const { return dp_dbg_; }
  const Eigen::Matrix3d& dp_dba() const { return dp_dba_; }

  const Eigen::Vector3d& bias_gyro_radps() const { return bias_gyro_; }
  const Eigen::Vector3d& bias_accel_mps2() const { return bias_accel_; }
  const ImuNoise& noise() const { return noise_; }

 private:
  struct Step {
    Eigen::Vector3d gyro_radps, accel_mps2;  ///< raw readings integrated over the step
    double dt_s;
  };

  void Reset();
  void IntegrateStep(const Step& step);

  Eigen::Vector3d bias_gyro_, bias_accel_;
  ImuNoise noise_;
  std::vector<Step> steps_;
  Eigen::Matrix3d dR_;
  Eigen::Vector3d dv_, dp_;
  double dt_s_ = 0.0;
  Matrix9d cov_;
  Eigen::Matrix3d dR_dbg_, dv_dbg_, dv_dba_, dp_dbg_, dp_dba_;
};

}  // namespace rotolidar
