#pragma once
// Rig imperfections of the twin (docs/noise_models.md, "Rig imperfections"): what makes a real rotary rig differ
// from the geometry its owner believes. All off by default (a zero config leaves every output byte as before).
//
//  * Calibration errors: drawn once per run from the random stream "calib.error" (RandomStream(run_seed, name))
//    as zero-mean Gaussians with the configured 1-sigma values. The sim simulates with the TRUE geometry
//    (SimConfig::TrueCalib()); calib.yaml holds what the owner believes: truth + drawn error (ApplyCalibErrors).
//    A pose error is applied in the parent frame: T_believed = [ExpSO3(dphi) * R_true, t_true + dt].
//    The encoder zero error d makes the believed angle theta_believed = theta_true - d.
//  * Axis wobble (TrueRotorKinematics): the rotor frame the lidar is mounted on is not the ideal one:
//      T_base_rotor_true(theta) = T_base_motor * Tilt * RotZ(theta) * Cone(theta)
//    Tilt: a fixed tilt of the motor axis by axis_tilt_rad about the motor-frame axis at azimuth
//    axis_tilt_azimuth_rad from motor +x (a T_base_motor error the owner does not know about).
//    Cone(theta): a tilt of cone_half_angle_rad about the rotor-frame axis at angle theta + cone_phase_rad from
//    rotor +x: the tilt direction turns with the rotor relative to the ideal rotor frame (a bent coupling that
//    makes the mount wobble at twice the running speed as seen from the base), so the lidar's z axis leaves the
//    ideal one by exactly the half angle at every theta. (A tilt fixed in the rotor frame would be a constant
//    T_rotor_lidar error: that is the calibration tilt above.) calib.yaml knows nothing of the wobble; the
//    truth's lidar poses and the caster use it.
//  * Rotor vibration felt by the IMU (RotorVibrationAt): sinusoids added to the TRUE specific force and angular
//    rate before the IMU's noise model, coherent with the true rotor angle theta:
//      a = A0 (omega/omega_ref)^2 u(theta + phi0) + sum_h A_h u(n_h theta + phi_h)       (motor frame)
//      w = G0 (omega/omega_ref)   t(theta + phi0) + sum_h G_h t(n_h theta + phi_h)
//    u(psi) = (cos psi, sin psi, 0), t(psi) = (-sin psi, cos psi, 0): radial (the imbalance's rotating force)
//    and tangential (the rocking it causes) in the plane across the motor axis. A0 is the imbalance's
//    acceleration at omega_ref (equivalent to an imbalance U = A0 * M_rig / omega_ref^2); the harmonics (bearing,
//    stepper tooth) have fixed amplitudes. IMU-only: the mount's local vibration, not a motion of the rig (the
//    truth poses do not move with it; the rig model's rotor imbalance already moves the rigid rig in the physics).
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/types/calib.hpp"
#include "core/types/geometry.hpp"
#include "core/util/status.hpp"
#include "sim/realism.hpp"

namespace YAML {
class Node;
class Emitter;
}  // namespace YAML

namespace rotolidar::sim {

/// 1-sigma calibration errors (per axis unless said otherwise); 0 = exact.
struct CalibErrorConfig {
  double rotor_lidar_lever_sigma_m = 0.0;     ///< T_rotor_lidar translation [m]
  double rotor_lidar_tilt_sigma_deg = 0.0;    ///< T_rotor_lidar rotation about rotor x and y [deg]
  double encoder_zero_sigma_rad = 0.0;        ///< encoder zero offset [rad]
  double base_imu_translation_sigma_m = 0.0;  ///< T_base_imu translation [m]
  double base_imu_rotation_sigma_deg = 0.0;   ///< T_base_imu rotation, about each base axis [deg]
  double base_cam_translation_sigma_m = 0.0;  ///< T_base_cam translation [m]
  double base_cam_rotation_sigma_deg = 0.0;   ///< T_base_cam rotation, about each base axis [deg]
};

struct AxisWobbleConfig {
  double cone_half_angle_rad = 0.0;    ///< coning half angle of the lidar mount about the ideal rotor axis
  double cone_phase_rad = 0.0;         ///< the cone's tilt axis at theta = 0, from rotor +x
  double axis_tilt_rad = 0.0;          ///< fixed tilt of the motor axis
  double axis_tilt_azimuth_rad = 0.0;  ///< the axis the fixed tilt turns about, from motor +x about motor z
};

/// One vibration line at `order` times the rotor frequency, fixed amplitude.
struct VibrationHarmonic {
  int order = 2;               ///< multiple of the rotor frequency, >= 1
  double accel_mps2 = 0.0;     ///< specific-force amplitude [m/s^2]
  double gyro_radps = 0.0;     ///< angular-rate amplitude [rad/s]
  double phase_rad = 0.0;
};

struct RotorVibrationConfig {
  double imbalance_accel_mps2 = 0.0;   ///< specific-force amplitude at f_r when omega = reference_speed_radps
  double imbalance_gyro_radps = 0.0;   ///< angular-rate amplitude at f_r when omega = reference_speed_radps
  double reference_speed_radps = 2.6;  ///< the speed the two amplitudes above are given at (default motor speed)
  double imbalance_phase_rad = 0.0;    ///< direction of the imbalance at theta = 0, from rotor +x
  std::vector<VibrationHarmonic> harmonics;  ///< bearing / stepper lines
};

struct RigErrorConfig {
  CalibErrorConfig calibration;
  AxisWobbleConfig wobble;
  RotorVibrationConfig vibration;

  bool CalibrationEnabled() const;
  bool WobbleEnabled() const;
  bool VibrationEnabled() const;
  bool Enabled() const { return CalibrationEnabled() || WobbleEnabled() || VibrationEnabled(); }
  /// False naming the field ("rig_errors.calibration.rotor_lidar_tilt_sigma_deg ...") unless every value is
  /// finite, sigmas and amplitudes are >= 0, sigmas of translations <= 0.1 m and of angles <= 10 deg (0.1745
  /// rad), the wobble angles <= 0.1745 rad, reference_speed_radps > 0 and harmonic orders in [1, 1000].
  bool Validate(std::string* error) const;
};

/// The presets (sim/realism.hpp; magnitudes and sources in docs/noise_models.md): kIdeal = all zero.
RigErrorConfig RigErrorPreset(Realism realism);

/// One run's drawn calibration errors (rotations as rotation vectors [rad], parent frame).
struct CalibErrors {
  Eigen::Vector3d rotor_lidar_translation_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d rotor_lidar_rotation_rad = Eigen::Vector3d::Zero();  ///< z is always 0 (tilt only)
  double encoder_zero_rad = 0.0;
  Eigen::Vector3d base_imu_translation_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d base_imu_rotation_rad = Eigen::Vector3d::Zero();
  Eigen::Vector3d base_cam_translation_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d base_cam_rotation_rad = Eigen::Vector3d::Zero();
};

/// Draws every component, always in the same order (so one sigma never shifts another's draw), from
/// RandomStream(run_seed, "calib.error"). Zero sigmas give exact zeros.
CalibErrors DrawCalibErrors(const CalibErrorConfig& config, uint64_t run_seed);

/// What the owner believes: `truth` with `errors` applied (see the file comment). All-zero errors return
/// `truth` unchanged, bit for bit.
RigCalib ApplyCalibErrors(const RigCalib& truth, const CalibErrors& errors);

/// The rotor's true kinematics: the true calibration plus the wobble. Without wobble it is exactly
/// truth.T_base_lidar(theta).
class TrueRotorKinematics {
 public:
  TrueRotorKinematics(const RigCalib& truth, const AxisWobbleConfig& wobble);
  Pose3 T_base_rotor(double theta_rad) const;
  Pose3 T_base_lidar(double theta_rad) const;

 private:
  RigCalib truth_;
  AxisWobbleConfig wobble_;
  bool enabled_ = false;
  Pose3 T_base_tilted_motor_ = Pose3::Identity();
};

/// The vibration at true rotor angle theta and speed omega, in the motor frame.
struct RotorVibration {
  Eigen::Vector3d accel_motor_mps2 = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_motor_radps = Eigen::Vector3d::Zero();
};
RotorVibration RotorVibrationAt(const RotorVibrationConfig& config, double theta_rad, double omega_radps);

/// Adds the vibration to true IMU signals (imu frame); R_imu_motor from the TRUE calibration.
void AddRotorVibration(const RotorVibrationConfig& config, const Eigen::Matrix3d& R_imu_motor, double theta_rad,
                       double omega_radps, Eigen::Vector3d* gyro_imu_radps, Eigen::Vector3d* accel_imu_mps2);

/// YAML (sim/rig/rig_errors_yaml.cpp), the sim config's `rig_errors:` section, keys as the fields above:
///   calibration: {rotor_lidar_lever_sigma_m, ...}, wobble: {...},
///   vibration: {imbalance_accel_mps2, ..., harmonics: [{order, accel_mps2, gyro_radps, phase_rad}, ...]}
/// Unknown keys, wrong types and invalid values name file:line and the field; *config is untouched then.
Status ParseRigErrorConfig(const std::string& file, const YAML::Node& node, RigErrorConfig* config);
void EmitRigErrorConfig(YAML::Emitter& out, const RigErrorConfig& config);

/// Writes the truth of the rig's imperfections (only call when config.Enabled()): truth/calib_true.yaml (the
/// true calibration, calib.yaml's format) and truth/rig_errors.yaml (the config and the drawn errors).
/// The truth/ folder must exist. Errors name the file.
Status WriteRigErrorTruth(const std::string& recording_dir, const RigErrorConfig& config, const CalibErrors& errors,
                          const RigCalib& true_calib);
/// Reads truth/rig_errors.yaml back (config and drawn errors); errors name file:line and the field.
Status ReadRigErrorTruth(const std::string& recording_dir, RigErrorConfig* config, CalibErrors* errors);

}  // namespace rotolidar::sim
