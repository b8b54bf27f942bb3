// Rig imperfections: validation, presets, the drawn calibration errors and the wobbled kinematics / vibration
// (the contracts are in rig_errors.hpp; magnitudes and their sources in docs/noise_models.md).
#include "sim/rig/rig_errors.hpp"

#include <cmath>

#include "core/util/rng.hpp"

namespace rotolidar::sim {
namespace {

constexpr double kDegToRad = M_PI / 180.0;

bool CheckField(bool ok, const std::string& field, const std::string& what, std::string* error) {
  if (!ok && error) *error = "rig_errors." + field + " " + what;
  return ok;
}

bool Sigma(double v, double max, const std::string& field, std::string* error) {
  return CheckField(std::isfinite(v) && v >= 0.0 && v <= max, field, "must be in [0, " + std::to_string(max) + "]",
               error);
}

bool ValidateCalib(const CalibErrorConfig& c, std::string* error) {
  const std::string p = "calibration.";
  return Sigma(c.rotor_lidar_lever_sigma_m, 0.1, p + "rotor_lidar_lever_sigma_m", error) &&
         Sigma(c.rotor_lidar_tilt_sigma_deg, 10.0, p + "rotor_lidar_tilt_sigma_deg", error) &&
         Sigma(c.encoder_zero_sigma_rad, 10.0 * kDegToRad, p + "encoder_zero_sigma_rad", error) &&
         Sigma(c.base_imu_translation_sigma_m, 0.1, p + "base_imu_translation_sigma_m", error) &&
         Sigma(c.base_imu_rotation_sigma_deg, 10.0, p + "base_imu_rotation_sigma_deg", error) &&
         Sigma(c.base_cam_translation_sigma_m, 0.1, p + "base_cam_translation_sigma_m", error) &&
         Sigma(c.base_cam_rotation_sigma_deg, 10.0, p + "base_cam_rotation_sigma_deg", error);
}

bool ValidateWobble(const AxisWobbleConfig& w, std::string* error) {
  const double max = 10.0 * kDegToRad;
  return Sigma(w.cone_half_angle_rad, max, "wobble.cone_half_angle_rad", error) &&
         CheckField(std::isfinite(w.cone_phase_rad), "wobble.cone_phase_rad", "must be finite", error) &&
         Sigma(w.axis_tilt_rad, max, "wobble.axis_tilt_rad", error) &&
         CheckField(std::isfinite(w.axis_tilt_azimuth_rad), "wobble.axis_tilt_azimuth_rad", "must be finite", error);
}

bool ValidateVibration(const RotorVibrationConfig& v, std::string* error) {
  const std::string p = "vibration.";
  if (!Sigma(v.imbalance_accel_mps2, 100.0, p + "imbalance_accel_mps2", error) ||
      !Sigma(v.imbalance_gyro_radps, 10.0, p + "imbalance_gyro_radps", error) ||
      !CheckField(std::isfinite(v.reference_speed_radps) && v.reference_speed_radps > 0.0, p + "reference_speed_radps",
             "must be > 0", error) ||
      !CheckField(std::isfinite(v.imbalance_phase_rad), p + "imbalance_phase_rad", "must be finite", error))
    return false;
  for (size_t i = 0; i < v.harmonics.size(); ++i) {
    const VibrationHarmonic& h = v.harmonics[i];
    const std::string f = p + "harmonics[" + std::to_string(i) + "].";
    if (!CheckField(h.order >= 1 && h.order <= 1000, f + "order", "must be in [1, 1000]", error) ||
        !Sigma(h.accel_mps2, 100.0, f + "accel_mps2", error) || !Sigma(h.gyro_radps, 10.0, f + "gyro_radps", error) ||
        !CheckField(std::isfinite(h.phase_rad), f + "phase_rad", "must be finite", error))
      return false;
  }
  return true;
}

Eigen::Vector3d Draw3(RandomStream* rng, double sigma) {
  const double x = rng->Normal(), y = rng->Normal(), z = rng->Normal();  // drawn in this order, always
  return sigma * Eigen::Vector3d(x, y, z);
}

/// T_believed = [ExpSO3(dphi) * R, t + dt]; exact identity when both are zero.
Pose3 Perturb(const Pose3& T, const Eigen::Vector3d& dt, const Eigen::Vector3d& dphi) {
  if (dt.isZero(0.0) && dphi.isZero(0.0)) return T;
  Pose3 out = T;
  out.linear() = ExpSO3(dphi) * T.linear();
  out.translation() = T.translation() + dt;
  return out;
}

Eigen::Matrix3d TiltAbout(double azimuth_rad, double angle_rad) {
  const Eigen::Vector3d axis(std::cos(azimuth_rad), std::sin(azimuth_rad), 0.0);
  return Eigen::AngleAxisd(angle_rad, axis).toRotationMatrix();
}

Eigen::Vector3d Radial(double psi) { return {std::cos(psi), std::sin(psi), 0.0}; }
Eigen::Vector3d Tangential(double psi) { return {-std::sin(psi), std::cos(psi), 0.0}; }

}  // namespace

bool RigErrorConfig::CalibrationEnabled() const {
  const CalibErrorConfig& c = calibration;
  return c.rotor_lidar_lever_sigma_m > 0 || c.rotor_lidar_tilt_sigma_deg > 0 || c.encoder_zero_sigma_rad > 0 ||
         c.base_imu_translation_sigma_m > 0 || c.base_imu_rotation_sigma_deg > 0 ||
         c.base_cam_translation_sigma_m > 0 || c.base_cam_rotation_sigma_deg > 0;
}

bool RigErrorConfig::WobbleEnabled() const { return wobble.cone_half_angle_rad > 0 || wobble.axis_tilt_rad > 0; }

bool RigErrorConfig::VibrationEnabled() const {
  if (vibration.imbalance_accel_mps2 > 0 || vibration.imbalance_gyro_radps > 0) return true;
  for (const VibrationHarmonic& h : vibration.harmonics)
    if (h.accel_mps2 > 0 || h.gyro_radps > 0) return true;
  return false;
}

bool RigErrorConfig::Validate(std::string* error) const {
  return ValidateCalib(calibration, error) && ValidateWobble(wobble, error) && ValidateVibration(vibration, error);
}

RigErrorConfig RigErrorPreset(Realism realism) {
  RigErrorConfig c;
  if (realism == Realism::kIdeal) return c;
  const bool harsh = realism == Realism::kHarsh;
  CalibErrorConfig& k = c.calibration;
  k.rotor_lidar_lever_sigma_m = harsh ? 0.005 : 0.0015;
  k.rotor_lidar_tilt_sigma_deg = harsh ? 0.5 : 0.15;
  k.encoder_zero_sigma_rad = (harsh ? 0.3 : 0.1) * kDegToRad;
  k.base_imu_translation_sigma_m = harsh ? 0.005 : 0.002;
  k.base_imu_rotation_sigma_deg = harsh ? 0.3 : 0.1;
  k.base_cam_translation_sigma_m = harsh ? 0.005 : 0.002;
  k.base_cam_rotation_sigma_deg = harsh ? 0.5 : 0.2;
  c.wobble.cone_half_angle_rad = (harsh ? 0.15 : 0.05) * kDegToRad;
  c.wobble.axis_tilt_rad = (harsh ? 0.2 : 0.05) * kDegToRad;
  c.wobble.axis_tilt_azimuth_rad = 0.25 * M_PI;
  RotorVibrationConfig& v = c.vibration;
  // Imbalance at ISO 1940-1 balance grade G6.3 (typical) / G16 (harsh) of a ~1 kg rotor on a ~2.8 kg rig.
  v.imbalance_accel_mps2 = harsh ? 0.015 : 0.006;
  v.imbalance_gyro_radps = harsh ? 0.001 : 0.0004;
  v.reference_speed_radps = 2.6;
  // Bearing / coupling line at 2 f_r, the hybrid stepper's tooth line (50 f_r) and full-step line (200 f_r).
  v.harmonics = {{2, harsh ? 0.03 : 0.01, 0.0, 0.3},
                 {50, harsh ? 0.4 : 0.1, harsh ? 0.01 : 0.002, 1.1},
                 {200, harsh ? 0.2 : 0.05, harsh ? 0.004 : 0.001, 2.0}};
  return c;
}

CalibErrors DrawCalibErrors(const CalibErrorConfig& c, uint64_t run_seed) {
  RandomStream rng(run_seed, "calib.error");
  CalibErrors e;
  e.rotor_lidar_translation_m = Draw3(&rng, c.rotor_lidar_lever_sigma_m);
  e.rotor_lidar_rotation_rad = Draw3(&rng, c.rotor_lidar_tilt_sigma_deg * kDegToRad);
  e.rotor_lidar_rotation_rad.z() = 0.0;  // tilt only: a rotation about rotor z is the encoder zero's
  e.encoder_zero_rad = c.encoder_zero_sigma_rad * rng.Normal();
  e.base_imu_translation_m = Draw3(&rng, c.base_imu_translation_sigma_m);
  e.base_imu_rotation_rad = Draw3(&rng, c.base_imu_rotation_sigma_deg * kDegToRad);
  e.base_cam_translation_m = Draw3(&rng, c.base_cam_translation_sigma_m);
  e.base_cam_rotation_rad = Draw3(&rng, c.base_cam_rotation_sigma_deg * kDegToRad);
  return e;
}

RigCalib ApplyCalibErrors(const RigCalib& truth, const CalibErrors& e) {
  RigCalib b = truth;
  b.T_rotor_lidar = Perturb(truth.T_rotor_lidar, e.rotor_lidar_translation_m, e.rotor_lidar_rotation_rad);
  b.T_base_imu = Perturb(truth.T_base_imu, e.base_imu_translation_m, e.base_imu_rotation_rad);
  b.T_base_cam = Perturb(truth.T_base_cam, e.base_cam_translation_m, e.base_cam_rotation_rad);
  if (e.encoder_zero_rad != 0.0) b.encoder.zero_offset_rad = truth.encoder.zero_offset_rad + e.encoder_zero_rad;
  return b;
}

TrueRotorKinematics::TrueRotorKinematics(const RigCalib& truth, const AxisWobbleConfig& wobble)
    : truth_(truth), wobble_(wobble), enabled_(wobble.cone_half_angle_rad > 0 || wobble.axis_tilt_rad > 0) {
  T_base_tilted_motor_ = truth.T_base_motor;
  T_base_tilted_motor_.linear() =
      truth.T_base_motor.linear() * TiltAbout(wobble.axis_tilt_azimuth_rad, wobble.axis_tilt_rad);
}

Pose3 TrueRotorKinematics::T_base_rotor(double theta_rad) const {
  if (!enabled_) return truth_.T_base_rotor(theta_rad);
  Pose3 cone = Pose3::Identity();
  cone.linear() = TiltAbout(theta_rad + wobble_.cone_phase_rad, wobble_.cone_half_angle_rad);
  return T_base_tilted_motor_ * RotZ(theta_rad) * cone;
}

Pose3 TrueRotorKinematics::T_base_lidar(double theta_rad) const {
  if (!enabled_) return truth_.T_base_lidar(theta_rad);
  return T_base_rotor(theta_rad) * truth_.T_rotor_lidar;
}

RotorVibration RotorVibrationAt(const RotorVibrationConfig& c, double theta_rad, double omega_radps) {
  RotorVibration v;
  const double s = omega_radps / c.reference_speed_radps;
  const double psi0 = theta_rad + c.imbalance_phase_rad;
  v.accel_motor_mps2 = c.imbalance_accel_mps2 * s * s * Radial(psi0);
  v.gyro_motor_radps = c.imbalance_gyro_radps * s * Tangential(psi0);
  for (const VibrationHarmonic& h : c.harmonics) {
    const double psi = h.order * theta_rad + h.phase_rad;
    v.accel_motor_mps2 += h.accel_mps2 * Radial(psi);
    v.gyro_motor_radps += h.gyro_radps * Tangential(psi);
  }
  return v;
}

void AddRotorVibration(const RotorVibrationConfig& config, const Eigen::Matrix3d& R_imu_motor, double theta_rad,
                       double omega_radps, Eigen::Vector3d* gyro_imu_radps, Eigen::Vector3d* accel_imu_mps2) {
  const RotorVibration v = RotorVibrationAt(config, theta_rad, omega_radps);
  *gyro_imu_radps += R_imu_motor * v.gyro_motor_radps;
  *accel_imu_mps2 += R_imu_motor * v.accel_motor_mps2;
}

}  // namespace rotolidar::sim
