#include "sim/rig/stepper.hpp"

#include <algorithm>
#include <cmath>

#include "core/util/log.hpp"

namespace rotolidar::sim {
namespace {

constexpr double kRevolutionRad = 2.0 * M_PI;

bool Finite(double x) { return std::isfinite(x); }

double DeadZone(double e, double width) {
  if (std::abs(e) <= width) return 0.0;
  return e > 0 ? e - width : e + width;
}

const MotorDriveConfig& Checked(const MotorDriveConfig& config) {
  std::string error;
  ROTOLIDAR_CHECK(config.Validate(&error), error);
  return config;
}

int64_t FloorDiv(int64_t a, int64_t b) { return a / b - ((a % b != 0) && ((a < 0) != (b < 0))); }

}  // namespace

bool StepperConfig::Validate(std::string* error) const {
  auto fail = [error](const std::string& m) {
    if (error) *error = "StepperConfig: " + m;
    return false;
  };
  if (full_steps_per_rev < 4 || full_steps_per_rev % 4 != 0)
    return fail("full_steps_per_rev must be a positive multiple of 4 (two phases, 4 full steps per tooth)");
  if (microsteps < 1 || microsteps > 256) return fail("microsteps must be in [1, 256]");
  if (!Finite(holding_torque_nm) || holding_torque_nm <= 0) return fail("holding_torque_nm must be finite, > 0");
  if (!Finite(rotor_inertia_kgm2) || rotor_inertia_kgm2 <= 0) return fail("rotor_inertia_kgm2 must be finite, > 0");
  if (!Finite(detent_torque_nm) || detent_torque_nm < 0 || detent_torque_nm >= holding_torque_nm)
    return fail("detent_torque_nm must be finite, in [0, holding_torque_nm)");
  if (!Finite(step_error_fraction) || step_error_fraction < 0 || step_error_fraction >= 0.5)
    return fail("step_error_fraction must be in [0, 0.5)");
  if (!Finite(torque_ripple_fraction) || torque_ripple_fraction < 0 || torque_ripple_fraction >= 1)
    return fail("torque_ripple_fraction must be in [0, 1)");
  if (!Finite(viscous_damping_nms) || viscous_damping_nms < 0) return fail("viscous_damping_nms must be >= 0");
  if (!Finite(rated_current_a) || rated_current_a <= 0) return fail("rated_current_a must be finite, > 0");
  if (!Finite(phase_resistance_ohm) || phase_resistance_ohm <= 0)
    return fail("phase_resistance_ohm must be finite, > 0");
  if (!Finite(phase_inductance_h) || phase_inductance_h < 0) return fail("phase_inductance_h must be >= 0");
  if (!Finite(supply_voltage_v) || supply_voltage_v <= 0) return fail("supply_voltage_v must be finite, > 0");
  if (!Finite(missed_step_rate_hz) || missed_step_rate_hz < 0) return fail("missed_step_rate_hz must be >= 0");
  return true;
}

double StepperConfig::PullOutTorqueNm(double speed_radps) const {
  const double w = std::abs(speed_radps);
  const double kt = holding_torque_nm / rated_current_a;  // [N m/A] = back-EMF constant [V s/rad]
  const double emf = kt * w, r = phase_resistance_ohm, x = RotorTeeth() * w * phase_inductance_h;
  const double z2 = r * r + x * x;
  // |(r + jx) i + emf| = V with i in phase with emf: (r i + emf)^2 + (x i)^2 = V^2, positive root.
  const double disc = supply_voltage_v * supply_voltage_v * z2 - x * x * emf * emf;
  if (disc <= 0) return 0.0;
  const double current = (-r * emf + std::sqrt(disc)) / z2;
  return current <= 0 ? 0.0 : kt * std::min(current, rated_current_a);
}

bool PidConfig::Validate(std::string* error) const {
  auto fail = [error](const std::string& m) {
    if (error) *error = "PidConfig: " + m;
    return false;
  };
  if (!Finite(kp) || kp < 0) return fail("kp must be finite, >= 0");
  if (!Finite(ki_per_s) || ki_per_s < 0) return fail("ki_per_s must be finite, >= 0");
  if (!Finite(kd_s) || kd_s < 0) return fail("kd_s must be finite, >= 0");
  if (!Finite(speed_filter_hz) || speed_filter_hz <= 0) return fail("speed_filter_hz must be finite, > 0");
  if (!Finite(deadband_counts) || deadband_counts < 0) return fail("deadband_counts must be finite, >= 0");
  if (!Finite(integral_limit_rad) || integral_limit_rad < 0) return fail("integral_limit_rad must be finite, >= 0");
  if (!Finite(max_correction_speed_radps) || max_correction_speed_radps <= 0)
    return fail("max_correction_speed_radps must be finite, > 0");
  if (!Finite(max_step_rate_radps) || max_step_rate_radps <= 0 || max_step_rate_radps > kMaxRotorSpeedRadps)
    return fail("max_step_rate_radps must be in (0, " + std::to_string(int(kMaxRotorSpeedRadps)) + "]");
  return true;
}

bool MotorDriveConfig::Validate(std::string* error) const {
  auto fail = [error](const std::string& m) {
    if (error) *error = "MotorDriveConfig: " + m;
    return false;
  };
  std::string why;
  if (!profile.Validate(&why)) return fail("profile: " + why);
  if (!stepper.Validate(&why)) return fail("stepper: " + why);
  if (!pid.Validate(&why)) return fail("pid: " + why);
  if (!encoder.Validate(&why)) return fail("encoder: " + why);
  if (profile.PeakSpeed() > pid.max_step_rate_radps)
    return fail("profile peak speed " + std::to_string(profile.PeakSpeed()) +
                " rad/s exceeds pid.max_step_rate_radps " + std::to_string(pid.max_step_rate_radps));
  if (pid.speed_filter_hz >= 0.5 * encoder.rate_hz)
    return fail("pid.speed_filter_hz must be below half of encoder.rate_hz (the controller rate)");
  return true;
}

StepperDrive::StepperDrive(const MotorDriveConfig& config, uint64_t run_seed)
    : config_(Checked(config)),
      profile_(config_.profile),
      encoder_(config_.encoder, run_seed),
      missed_rng_(run_seed, "stepper.missed_steps") {
  decode_.encoder = config_.encoder.ToCalib();
  const StepperConfig& s = config_.stepper;
  RandomStream rng(run_seed, "stepper.step_error");
  step_error_rad_.resize(static_cast<size_t>(s.full_steps_per_rev));
  const double bound = s.step_error_fraction * s.FullStepRad();
  for (double& e : step_error_rad_) e = bound * (2.0 * rng.Uniform() - 1.0);
}

double StepperDrive::StepErrorRad(int64_t microstep) const {
  const int64_t m = config_.stepper.microsteps, n = config_.stepper.full_steps_per_rev;
  const int64_t q = FloorDiv(microstep, m), r = microstep - q * m;
  const int64_t i = ((q % n) + n) % n;
  const double a = step_error_rad_[static_cast<size_t>(i)];
  const double b = step_error_rad_[static_cast<size_t>((i + 1) % n)];
  return (static_cast<double>(m - r) * a + static_cast<double>(r) * b) / static_cast<double>(m);
}

void StepperDrive::Start(const RotorJointState& state) {
  started_ = true;
  phase_rad_ = state.theta_rad;  // the driver's counter starts where the rotor is (its nearest microstep)
  last_tick_t_s_ = state.t_s;
  const double rate = config_.stepper.missed_step_rate_hz;
  if (rate > 0) next_miss_t_s_ = state.t_s - std::log(1.0 - missed_rng_.Uniform()) / rate;
}

void StepperDrive::ControlTick(const EncoderSample& sample) {
  const PidConfig& p = config_.pid;
  const double period = 1.0 / config_.encoder.rate_hz;
  const double dt = have_tick_ ? sample.t_s - last_tick_t_s_ : 0.0;
  phase_rad_ += step_rate_radps_ * (sample.t_s - last_tick_t_s_);  // the step generator ran at the held rate
  // The sample reports the angle at t - latency: compare it with the reference at that time (the latency is a
  // datasheet number the controller knows), so the true angle, not the late reading, tracks the profile.
  const MotorReference ref = profile_.Reference(sample.t_s - config_.encoder.latency_s);
  // Decode exactly as a reader of encoder.csv does, then unwrap next to the predicted angle.
  const double raw = decode_.EncoderAngle(sample.count);
  const double predicted = have_tick_ ? enc_theta_rad_ + enc_speed_radps_ * dt : ref.theta_rad;
  const double theta = raw + kRevolutionRad * std::round((predicted - raw) / kRevolutionRad);
  if (have_tick_ && dt > 0) {  // first-order low-pass of the finite-difference speed
    const double gain = 1.0 - std::exp(-kRevolutionRad * p.speed_filter_hz * dt);
    enc_speed_radps_ += gain * ((theta - enc_theta_rad_) / dt - enc_speed_radps_);
  }
  enc_theta_rad_ = theta;

  // PID on the position error. The slow part (P, I) may move at most max_correction_speed; the D part, bounded by
  // kd |omega_ref - omega|, stays fast: it is what damps the torsional mode.
  const double count_rad = kRevolutionRad / config_.encoder.counts_per_rev;
  const double e = DeadZone(ref.theta_rad - theta, p.deadband_counts * count_rad);
  const double integral = integral_rad_s_ + e * period;
  const double pi_wanted = p.kp * e + p.ki_per_s * integral;
  const double du = p.max_correction_speed_radps * period;
  const double pi = std::clamp(pi_wanted, correction_rad_ - du, correction_rad_ + du);
  const double u = pi + p.kd_s * (ref.omega_radps - enc_speed_radps_);
  // Steer the step generator to reach theta_ref + u at the next tick, within the step-rate limit.
  const double target = profile_.Reference(sample.t_s + period).theta_rad + u;
  const double wanted_rate = (target - phase_rad_) / period;
  const double rate = std::clamp(wanted_rate, -p.max_step_rate_radps, p.max_step_rate_radps);
  // Conditional integration: keep the new integral unless a limit clips the output the way the error pushes.
  const bool clipped_up = pi_wanted > pi || wanted_rate > rate, clipped_down = pi_wanted < pi || wanted_rate < rate;
  if (!((clipped_up && e > 0) || (clipped_down && e < 0))) integral_rad_s_ = integral;
  if (p.ki_per_s > 0) {
    const double cap = p.integral_limit_rad / p.ki_per_s;
    integral_rad_s_ = std::clamp(integral_rad_s_, -cap, cap);
  }
  correction_rad_ = pi - (wanted_rate - rate) * period;  // the slow correction the generator actually reaches
  step_rate_radps_ = rate;
  last_tick_t_s_ = sample.t_s;
  have_tick_ = true;
  diag_.encoder_theta_rad = theta;
  diag_.position_error_rad = ref.theta_rad - theta;
  ++diag_.pid_ticks;
}

void StepperDrive::InjectMissedSteps(Seconds t) {
  const double rate = config_.stepper.missed_step_rate_hz;
  if (rate <= 0) return;
  while (next_miss_t_s_ <= t) {
    if (step_rate_radps_ != 0) {  // no pulses, no missed pulse, while the generator stands still
      lost_microsteps_ += step_rate_radps_ > 0 ? config_.stepper.microsteps : -config_.stepper.microsteps;
      ++diag_.injected_missed_steps;
    }
    next_miss_t_s_ -= std::log(1.0 - missed_rng_.Uniform()) / rate;
  }
}

double StepperDrive::MotorTorque(const RotorJointState& state, double equilibrium_rad) {
  const StepperConfig& s = config_.stepper;
  const double nr = s.RotorTeeth();
  const double pullout = s.PullOutTorqueNm(step_rate_radps_);
  const double amplitude = pullout * (1.0 + s.torque_ripple_fraction * std::cos(4.0 * nr * equilibrium_rad));
  diag_.pullout_torque_nm = pullout;
  return -amplitude * std::sin(nr * (state.theta_rad - equilibrium_rad)) -
         s.detent_torque_nm * std::sin(4.0 * nr * state.theta_rad) - s.viscous_damping_nms * state.omega_radps;
}

void StepperDrive::TrackSlip(double theta_rad, double equilibrium_rad) {
  // Electrical angle of the rotor from the commanded equilibrium; a slip is a move into a neighbouring
  // period's well. Hysteresis (1.25 pi instead of pi) keeps a rotor balancing on the unstable point from counting.
  const double delta = config_.stepper.RotorTeeth() * (theta_rad - equilibrium_rad);
  if (std::abs(delta - kRevolutionRad * static_cast<double>(slip_index_)) <= 1.25 * M_PI) return;
  const auto index = static_cast<int64_t>(std::llround(delta / kRevolutionRad));
  diag_.slipped_full_steps += 4 * std::abs(index - slip_index_);
  slip_index_ = index;
}

double StepperDrive::Torque(const RotorJointState& state, double dt_s) {
  ROTOLIDAR_CHECK(std::isfinite(dt_s) && dt_s > 0, "dt_s must be > 0, got " << dt_s);
  ROTOLIDAR_CHECK(!started_ || state.t_s > last_t_s_, "Torque() times must increase: " << state.t_s);
  if (!started_) Start(state);
  last_t_s_ = state.t_s;
  const size_t first_new = pending_.size();
  encoder_.Push(state, &pending_);
  for (size_t i = first_new; i < pending_.size(); ++i) ControlTick(pending_[i]);
  InjectMissedSteps(state.t_s);

  const StepperConfig& s = config_.stepper;
  const double phase = phase_rad_ + step_rate_radps_ * (state.t_s - last_tick_t_s_);
  const int64_t count = static_cast<int64_t>(std::llround(phase / s.MicrostepRad())) - lost_microsteps_;
  const double commanded = static_cast<double>(count) * s.MicrostepRad();
  const double equilibrium = commanded + StepErrorRad(count);
  const double torque = MotorTorque(state, equilibrium);
  TrackSlip(state.theta_rad, equilibrium);

  diag_.t_s = state.t_s;
  diag_.reference = profile_.Reference(state.t_s);
  diag_.commanded_microsteps = count;
  diag_.commanded_theta_rad = commanded;
  diag_.equilibrium_theta_rad = equilibrium;
  diag_.step_rate_radps = step_rate_radps_;
  diag_.motor_torque_nm = torque;
  return torque;
}

void StepperDrive::DrainEncoderSamples(std::vector<EncoderSample>* out) {
  out->insert(out->end(), pending_.begin(), pending_.end());
  pending_.clear();
}

}  // namespace rotolidar::sim
