#pragma once
// The rotor's motor: a NEMA-17 hybrid stepper on a micro-stepping driver, closed-loop PID on the shaft encoder,
// following a command profile (the seed: "NEMA-17 stepper motor ... micro-stepping driver with a closed-loop PID
// controller ... trapezoidal velocity profile ... real-time motor position feedback"). Every model and number is
// derived in docs/motor_model.md.
//
// StepperDrive implements the physics seam RotorDrive (sim/rig/rotor_drive.hpp): once per physics step it gets the
// TRUE hinge state and answers the motor torque. Inside, per physics step:
//   1. the encoder (EncoderStream) samples the true angle at its own rate, with latency, noise and quantisation;
//   2. each encoder sample is one PID tick (controller rate = encoder rate): the PID compares the decoded,
//      unwrapped encoder angle (never the true angle) with the profile and sets the command theta_ref + u;
//   3. the step generator ramps to that command over the tick (rate-limited); the driver energises the nearest
//      microstep, whose magnetic equilibrium is off by the motor's fixed per-full-step error;
//   4. torque = -T_po(w) (1 + r cos(4 N_r th_e)) sin(N_r (theta - th_e)) - T_detent sin(4 N_r theta) - B omega,
//      N_r = rotor teeth, th_e = commanded equilibrium, T_po(w) = pull-out torque at the step rate.
// A load above T_po drags theta more than half an electrical period (2 full steps) from th_e: the rotor slips to
// the next equilibrium, 4 full steps away - missed steps emerge from the torque law. Optional injected missed
// steps (driver glitches) drop one full step from the driver's counter at random times.
#include <cstdint>
#include <string>
#include <vector>

#include "core/types/calib.hpp"
#include "core/util/log.hpp"
#include "core/util/rng.hpp"
#include "sim/rig/motor.hpp"
#include "sim/rig/motor_profile.hpp"
#include "sim/rig/rotor_drive.hpp"

namespace YAML {
class Node;
class Emitter;
}  // namespace YAML

namespace rotolidar::sim {

/// A two-phase hybrid stepper and its driver. Defaults: 17HS4401 datasheet (1.8 deg, 1.7 A, 1.5 ohm, 2.8 mH,
/// holding >= 0.40 N m, detent <= 0.022 N m, rotor inertia 54 g cm^2) on a 24 V micro-stepping driver at 1/16.
struct StepperConfig {
  int full_steps_per_rev = 200;        ///< 1.8 deg; a multiple of 4 (2 phases: 4 full steps per rotor tooth)
  int microsteps = 16;                 ///< microsteps per full step, 1..256 (A4988/DRV8825 at 1/16)
  double holding_torque_nm = 0.40;     ///< both phases at rated current [N m]; > 0
  double rotor_inertia_kgm2 = 5.4e-6;  ///< 54 g cm^2 [kg m^2]; > 0. NOT applied by the drive: the rig adds it
                                       ///< to the hinge (MuJoCo armature) or the test integrator to its inertia
  double detent_torque_nm = 0.022;     ///< unpowered cogging, 4 cycles per tooth [N m]; [0, holding)
  /// Full-step accuracy: each of the full_steps_per_rev positions has a FIXED error drawn uniformly in
  /// +-step_error_fraction of a full step (RandomStream(run_seed, "stepper.step_error")); microsteps interpolate
  /// linearly between full steps. [0, 0.5). 0.04: datasheets give +-3..5 % non-cumulative.
  double step_error_fraction = 0.04;
  /// Relative ripple of the torque amplitude with the commanded electrical angle (4 cycles per electrical
  /// period, from driver current tables and non-sinusoidal flux); [0, 1). 0: the detent torque already supplies
  /// the motor's 4-per-period ripple; set it for studies.
  double torque_ripple_fraction = 0.0;
  double viscous_damping_nms = 8e-4;  ///< motor's own viscous damping [N m s/rad]; >= 0 (Bodson et al. 1993)
  double rated_current_a = 1.7;        ///< driver current limit = rated phase current [A]; > 0
  double phase_resistance_ohm = 1.5;   ///< [ohm]; > 0
  double phase_inductance_h = 2.8e-3;  ///< [H]; >= 0
  double supply_voltage_v = 24.0;      ///< driver supply [V]; > 0
  /// Injected missed steps (driver glitches), Poisson rate [1/s], >= 0; 0 = off. Each drops one full step of the
  /// driver's counter in the direction the step generator is stepping at that instant (none while it stands
  /// still). Event times: RandomStream(run_seed, "stepper.missed_steps").
  double missed_step_rate_hz = 0.0;

  bool Validate(std::string* error) const;
  int RotorTeeth() const { return full_steps_per_rev / 4; }            ///< N_r (50 for 1.8 deg)
  double FullStepRad() const { return 2.0 * M_PI / full_steps_per_rev; }
  double MicrostepRad() const { return FullStepRad() / microsteps; }
  /// Pull-out torque [N m] at step rate |speed_radps|: the torque constant k_t = holding/rated current times the
  /// phase current the supply can still drive against the winding impedance R + j N_r w L and the back-EMF k_t w
  /// (phasor model, current in phase with the back-EMF), capped at the rated current. Equals holding torque at
  /// low speed, falls with speed (inductance), reaches 0 where the back-EMF uses up the supply.
  double PullOutTorqueNm(double speed_radps) const;
};

/// The closed loop on POSITION feedback from the encoder, run once per encoder sample (controller rate = encoder
/// rate). Position form: the step generator is steered to the command
///   theta_cmd = theta_ref + u,   u = kp e + ki int(e) dt + kd de/dt,   e = theta_ref(t - latency) - theta_encoder
/// (a sample stamped t reports the angle at t - encoder.latency_s, a datasheet number the controller compensates),
/// e passed through a +-deadband_counts dead zone for the P and I terms, de/dt = omega_ref - (low-passed encoder
/// speed). The D term is what damps the rotor's torsional mode (~22 Hz: the stepper's 20 N m/rad against the
/// VLP-16's inertia; open loop damping ratio ~0.003). Limits: the P + I part of u moves at most
/// max_correction_speed (the command's speed stays within that of the profile, inside the loaded rotor's pull-in
/// range, so a rotor that stalled is pulled back in); the D part is bounded by kd |de/dt| and left fast; the step
/// rate |d theta_cmd/dt| <= max_step_rate. Anti-windup: the integrator holds while a
/// limit clips the output in the direction the error pushes, and |ki int(e)| <= integral_limit.
struct PidConfig {
  /// Gains, tuned on a 1-DOF model of the rig (J = 1e-3 kg m^2, docs/motor_model.md): every loop delay turns P and
  /// I into negative damping of the torsional mode (P: ~N_r T_hold kp delay; I: ~N_r T_hold ki / w^2), so both are
  /// kept small next to D. Valid range of the defaults: encoder latency <= 3 ms at 1 kHz (<= 1 ms at 500 Hz),
  /// 1 or 2 ms physics steps (why: docs/motor_model.md, 'The closed loop').
  double kp = 0.3;          ///< [rad/rad]; >= 0
  double ki_per_s = 10.0;   ///< [1/s]; >= 0. Slow pole ki / (1 + kp) = 7.7 /s: removes lag and lost steps
  double kd_s = 5e-3;       ///< [s]; >= 0. N_r T_hold kd = 0.1 N m s/rad: damping ratio ~0.35 on 1e-3 kg m^2
  double speed_filter_hz = 50.0;      ///< first-order low-pass of the encoder's finite-difference speed [Hz]; > 0
  double deadband_counts = 1.0;       ///< P/I dead zone [encoder counts]; >= 0 (ignore what it cannot resolve)
  double integral_limit_rad = M_PI;   ///< bound of ki int(e) [rad]; >= 0 (recovers up to half a turn of slip)
  double max_correction_speed_radps = 2.0;  ///< [rad/s]; > 0. 2.6 + 2 stays below the pull-in speed 5.7 rad/s
  double max_step_rate_radps = 20.0;  ///< [rad/s]; (0, 200] (637 full steps/s; pull-out still = holding torque)

  bool Validate(std::string* error) const;
};

/// Everything the rotor's drive needs; what a run writes as its resolved motor config.
struct MotorDriveConfig {
  MotorProfileConfig profile;
  StepperConfig stepper;
  PidConfig pid;
  EncoderConfig encoder;  ///< also the controller's rate (encoder.rate_hz)

  /// Each part, plus: profile.PeakSpeed() <= pid.max_step_rate_radps, pid.speed_filter_hz < encoder.rate_hz / 2.
  bool Validate(std::string* error) const;
};

/// Read-only state of the drive after the latest Torque() call (the TRUE side: for truth/ and tests, never for
/// the estimator).
struct StepperDiagnostics {
  Seconds t_s = 0.0;                  ///< time of the latest Torque() call
  MotorReference reference;           ///< the profile at t_s
  int64_t commanded_microsteps = 0;   ///< the driver's microstep counter (after injected missed steps)
  double commanded_theta_rad = 0.0;   ///< commanded_microsteps * microstep angle (ideal motor)
  double equilibrium_theta_rad = 0.0; ///< where the field holds the rotor: commanded + fixed step error
  double step_rate_radps = 0.0;       ///< the step generator's rate over the current tick [rad/s]
  double encoder_theta_rad = 0.0;     ///< latest decoded, unwrapped encoder angle (what the PID sees)
  double position_error_rad = 0.0;    ///< reference - encoder at the latest PID tick
  double pullout_torque_nm = 0.0;     ///< T_po at the step rate
  double motor_torque_nm = 0.0;       ///< the torque returned
  int64_t slipped_full_steps = 0;     ///< cumulative full steps lost by slipping (4 per electrical period)
  int64_t injected_missed_steps = 0;  ///< cumulative injected missed full steps
  int64_t pid_ticks = 0;              ///< encoder samples consumed by the PID
};

/// The stepper + driver + PID + encoder as a RotorDrive. Deterministic for (config, run_seed, input states).
/// Not thread-safe (one physics loop calls it).
class StepperDrive final : public RotorDrive {
 public:
  /// config must Validate (ROTOLIDAR_CHECK). Streams: "stepper.step_error", "stepper.missed_steps",
  /// "encoder.noise".
  StepperDrive(const MotorDriveConfig& config, uint64_t run_seed);

  /// Motor torque [N m] about motor +z for [state.t_s, state.t_s + dt_s). state.t_s strictly increasing, dt_s > 0
  /// (ROTOLIDAR_CHECK). The first call powers the driver with its counter at the rotor's current angle.
  double Torque(const RotorJointState& state, double dt_s) override;
  /// Encoder samples produced so far (the PID's feedback), stamped on the rig clock, in time order.
  void DrainEncoderSamples(std::vector<EncoderSample>* out) override;

  const StepperDiagnostics& diagnostics() const { return diag_; }
  /// The TRUE rotor angle [rad] at t from the encoder's short history (t within the last latency + 2 steps):
  /// for tests that compare encoder samples with the truth they measured.
  double EncoderTrueAngleRad(Seconds t) const { return encoder_.TrueAngleAt(t); }
  const MotorDriveConfig& config() const { return config_; }
  const MotorProfile& profile() const { return profile_; }
  /// The fixed step error [rad] of the equilibrium of microstep position `microstep` (an angle of
  /// microstep * MicrostepRad()); |error| <= step_error_fraction * FullStepRad().
  double StepErrorRad(int64_t microstep) const;

 private:
  void Start(const RotorJointState& state);
  void ControlTick(const EncoderSample& sample);
  void InjectMissedSteps(Seconds t);
  double MotorTorque(const RotorJointState& state, double equilibrium_rad);
  void TrackSlip(double theta_rad, double equilibrium_rad);

  MotorDriveConfig config_;
  MotorProfile profile_;
  EncoderStream encoder_;
  RigCalib decode_;  ///< only .encoder is used: decodes counts exactly as the estimator does
  std::vector<double> step_error_rad_;  ///< per full-step position
  RandomStream missed_rng_;
  std::vector<EncoderSample> pending_;

  bool started_ = false;
  double last_t_s_ = 0.0;
  // Step generator: the command angle phase_rad_ at last_tick_t_s_, advancing at step_rate_radps_ since.
  double phase_rad_ = 0.0;
  double step_rate_radps_ = 0.0;
  int64_t lost_microsteps_ = 0;  ///< injected missed steps, subtracted from the counter
  Seconds next_miss_t_s_ = 0.0;
  // PID state.
  bool have_tick_ = false;
  Seconds last_tick_t_s_ = 0.0;
  double enc_theta_rad_ = 0.0;
  double enc_speed_radps_ = 0.0;  ///< low-passed encoder speed
  double integral_rad_s_ = 0.0;  ///< int(e) dt [rad s]
  double correction_rad_ = 0.0;  ///< the P + I part of u reached at the end of the current tick interval
  int64_t slip_index_ = 0;       ///< electrical periods the rotor sits from the commanded equilibrium
  StepperDiagnostics diag_;
};

/// Parses a motor-drive mapping {profile, stepper, pid, encoder} (each optional; keys as the struct fields,
/// profile.type one of constant|trapezoid|nodding|stop_and_go) over the values already in *config, then
/// Validates. Unknown keys, unreadable values and invalid configs give an error naming file:line and the field;
/// *config is untouched then. Defined in motor_yaml.cpp (needs yaml-cpp).
Status ParseMotorDriveConfig(const std::string& file, const YAML::Node& node, MotorDriveConfig* config);
/// Emits every field as one mapping (the value; the caller writes the key): ParseMotorDriveConfig of the output
/// gives back an equal config (doubles are written round-trip exact; infinity as .inf).
void EmitMotorDriveConfig(YAML::Emitter& out, const MotorDriveConfig& config);
/// Field-wise equality (for round-trip checks).
bool operator==(const MotorDriveConfig& a, const MotorDriveConfig& b);

}  // namespace rotolidar::sim
