#include "core/imu/preintegration.hpp"

#include <cmath>
#include <sstream>

#include "core/types/geometry.hpp"
#include "core/util/log.hpp"

namespace rotolidar {

namespace so3 {

namespace {
// Below this angle the closed forms lose precision (0/0); their Taylor series are exact to double precision.
constexpr double kSmallAngleRad = 1e-5;
}  // namespace

Eigen::Matrix3d Hat(const Eigen::Vector3d& w) {
  Eigen::Matrix3d W;
  W << 0.0, -w.z(), w.y(),  //
      w.z(), 0.0, -w.x(),   //
      -w.y(), w.x(), 0.0;
  return W;
}

Eigen::Matrix3d RightJacobian(const Eigen::Vector3d& phi_rad) {
  const double theta = phi_rad.norm();
  const Eigen::Matrix3d W = Hat(phi_rad);
  if (theta < kSmallAngleRad) return Eigen::Matrix3d::Identity() - 0.5 * W + (1.0 / 6.0) * W * W;
  const double t2 = theta * theta;
  return Eigen::Matrix3d::Identity() - (1.0 - std::cos(theta)) / t2 * W +
         (theta - std::sin(theta)) / (t2 * theta) * W * W;
}

Eigen::Matrix3d RightJacobianInverse(const Eigen::Vector3d& phi_rad) {
  const double theta = phi_rad.norm();
  const Eigen::Matrix3d W = Hat(phi_rad);
  if (theta < kSmallAngleRad) return Eigen::Matrix3d::Identity() + 0.5 * W + (1.0 / 12.0) * W * W;
  const double coeff = 1.0 / (theta * theta) - (1.0 + std::cos(theta)) / (2.0 * theta * std::sin(theta));
  return Eigen::Matrix3d::Identity() + 0.5 * W + coeff * W * W;
}

}  // namespace so3

namespace {

bool AllFinite(const Eigen::Vector3d& v) { return v.allFinite(); }

}  // namespace

PreintegratedImu::PreintegratedImu(const Eigen::Vector3d& bias_gyro_radps, const Eigen::Vector3d& bias_accel_mps2,
                                   const ImuNoise& noise)
    : bias_gyro_(bias_gyro_radps), bias_accel_(bias_accel_mps2), noise_(noise) {
  ROTOLIDAR_CHECK(noise.gyro_noise_density >= 0 && noise.accel_noise_density >= 0 &&
                      noise.gyro_random_walk >= 0 && noise.accel_random_walk >= 0,
                  "IMU noise densities must be >= 0 (validate RigCalib first)");
  ROTOLIDAR_CHECK(AllFinite(bias_gyro_radps) && AllFinite(bias_accel_mps2), "biases must be finite");
  Reset();
}

void PreintegratedImu::Reset() {
  dR_.setIdentity();
  dv_.setZero();
  dp_.setZero();
  dt_s_ = 0.0;
  cov_.setZero();
  dR_dbg_.setZero();
  dv_dbg_.setZero();
  dv_dba_.setZero();
  dp_dbg_.setZero();
  dp_dba_.setZero();
}

Status PreintegratedImu::Integrate(const Eigen::Vector3d& gyro_radps, const Eigen::Vector3d& accel_mps2,
                                   double dt_s) {
  if (!(dt_s > 0.0) || !std::isfinite(dt_s)) {
    std::ostringstream os;
    os << "PreintegratedImu::Integrate: dt_s = " << dt_s << " must be a positive finite number of seconds";
    return Status::Error(os.str());
  }
  if (!AllFinite(gyro_radps) || !AllFinite(accel_mps2))
    return Status::Error("PreintegratedImu::Integrate: a gyro or accel reading is not finite");
  steps_.push_back(Step{gyro_radps, accel_mps2, dt_s});
  IntegrateStep(steps_.back());
  return Status::Ok();
}

Status PreintegratedImu::Integrate(const ImuSample& a, const ImuSample& b) {
  const double dt_s = b.t_s - a.t_s;
  if (!(dt_s > 0.0) || !std::isfinite(dt_s)) {
    std::ostringstream os;
    os.precision(17);
    os << "PreintegratedImu::Integrate: IMU stamps not increasing (t_a = " << a.t_s << " s, t_b = " << b.t_s
       << " s)";
    return Status::Error(os.str());
  }
  return Integrate(0.5 * (a.gyro_radps + b.gyro_radps), 0.5 * (a.accel_mps2 + b.accel_mps2), dt_s);
}

void PreintegratedImu::Repropagate(const Eigen::Vector3d& bias_gyro_radps, const Eigen::Vector3d& bias_accel_mps2) {
  ROTOLIDAR_CHECK(AllFinite(bias_gyro_radps) && AllFinite(bias_accel_mps2), "biases must be finite");
  bias_gyro_ = bias_gyro_radps;
  bias_accel_ = bias_accel_mps2;
  Reset();
  for (const Step& step : steps_) IntegrateStep(step);
}

// One midpoint step. With w = gyro - bg, a = accel - ba, R_half = Exp(w dt/2) and a_k = R_half a (the reading
// rotated into the start frame of the step):
//   dp += dv dt + 1/2 dR a_k dt^2,   dv += dR a_k dt,   dR = dR Exp(w dt)   (Euler step, a -> a_k)
// The error-state transition A and the noise inputs Bg, Ba follow eq. 59-62 plus the sensitivity of a_k to w:
//   d(dR R_half a)/dw = -dR R_half [a]x Jr(w dt/2) dt/2 =: -G.
// The bias Jacobians (App. B) pick up the same G term.
void PreintegratedImu::IntegrateStep(const Step& step) {
  const double dt = step.dt_s, dt2 = dt * dt;
  const Eigen::Vector3d w = step.gyro_radps - bias_gyro_;
  const Eigen::Vector3d a = step.accel_mps2 - bias_accel_;
  const Eigen::Matrix3d R_step = ExpSO3(w * dt);
  const Eigen::Matrix3d Jr_step = so3::RightJacobian(w * dt);
  const Eigen::Matrix3d R_half = ExpSO3(0.5 * w * dt);
  const Eigen::Vector3d a_k = R_half * a;
  const Eigen::Matrix3d dR_R_half = dR_ * R_half;
  const Eigen::Matrix3d M = dR_ * so3::Hat(a_k);  // d(dR a_k)/d(dphi) = -M
  const Eigen::Matrix3d G = dR_R_half * so3::Hat(a) * so3::RightJacobian(0.5 * w * dt) * (0.5 * dt);

  // Covariance (eq. 63): Sigma = A Sigma A^T + Bg Qg Bg^T + Ba Qa Ba^T, Q = sigma^2 / dt I.
  Matrix9d A = Matrix9d::Identity();
  A.block<3, 3>(0, 0) = R_step.transpose();
  A.block<3, 3>(3, 0) = -M * dt;
  A.block<3, 3>(6, 0) = -0.5 * M * dt2;
  A.block<3, 3>(6, 3) = Eigen::Matrix3d::Identity() * dt;
  Eigen::Matrix<double, 9, 3> Bg, Ba;
  Bg << Jr_step * dt, -G * dt, -0.5 * G * dt2;
  Ba << Eigen::Matrix3d::Zero(), dR_R_half * dt, 0.5 * dR_R_half * dt2;
  const double qg = noise_.gyro_noise_density * noise_.gyro_noise_density / dt;
  const double qa = noise_.accel_noise_density * noise_.accel_noise_density / dt;
  cov_ = A * cov_ * A.transpose() + qg * Bg * Bg.transpose() + qa * Ba * Ba.transpose();

  // Bias Jacobians (App. B), position first: it uses the old velocity Jacobians.
  const Eigen::Matrix3d dacc_dbg = -M * dR_dbg_ + G;  // d(dR a_k)/d(bg)
  dp_dba_ += dv_dba_ * dt - 0.5 * dR_R_half * dt2;
  dp_dbg_ += dv_dbg_ * dt + 0.5 * dacc_dbg * dt2;
  dv_dba_ -= dR_R_half * dt;
  dv_dbg_ += dacc_dbg * dt;
  dR_dbg_ = R_step.transpose() * dR_dbg_ - Jr_step * dt;

  // Deltas, position first.
  dp_ += dv_ * dt + 0.5 * dR_ * a_k * dt2;
  dv_ += dR_ * a_k * dt;
  dR_ = dR_ * R_step;
  dt_s_ += dt;
}

ImuDelta PreintegratedImu::Corrected(const Eigen::Vector3d& d_bias_gyro_radps,
                                     const Eigen::Vector3d& d_bias_accel_mps2) const {
  ImuDelta d;
  d.dR = dR_ * ExpSO3(dR_dbg_ * d_bias_gyro_radps);
  d.dv_mps = dv_ + dv_dbg_ * d_bias_gyro_radps + dv_dba_ * d_bias_accel_mps2;
  d.dp_m = dp_ + dp_dbg_ * d_bias_gyro_radps + dp_dba_ * d_bias_accel_mps2;
  d.dt_s = dt_s_;
  return d;
}

NavState PreintegratedImu::Predict(const NavState& state_i, const Eigen::Vector3d& gravity_world_mps2) const {
  const ImuDelta d = Corrected(state_i.bias_gyro_radps - bias_gyro_, state_i.bias_accel_mps2 - bias_accel_);
  const Eigen::Matrix3d& Ri = state_i.R_world_imu;
  const double T = d.dt_s;
  NavState j = state_i;
  j.R_world_imu = Ri * d.dR;
  j.v_world_mps = state_i.v_world_mps + gravity_world_mps2 * T + Ri * d.dv_mps;
  j.p_world_m = state_i.p_world_m + state_i.v_world_mps * T + 0.5 * gravity_world_mps2 * T * T + Ri * d.dp_m;
  return j;
}

}  // namespace rotolidar
