#pragma once
// The rotor (motor shaft carrying the LiDAR) and its shaft encoder.
//
// Rotor angle theta [rad] is the rotation of the rotor frame about the motor z axis (core/types/calib.hpp:
// T_base_rotor(theta) = T_base_motor * RotZ(theta)). RotorMotion is an interface for rotors known as a function
// of time (ProfileRotor in sim/rig/motor_profile.hpp); a rotor integrated by physics is
// driven through sim/rig/rotor_drive.hpp and sampled by EncoderStream. See docs/motor_model.md.
#include <cstdint>
#include <deque>
#include <string>
#include <vector>

#include "core/types/calib.hpp"
#include "core/types/messages.hpp"
#include "core/types/time.hpp"
#include "core/util/rng.hpp"
#include "sim/rig/rotor_drive.hpp"

namespace rotolidar::sim {

/// True rotor angle as a function of time. Implementations are immutable (thread-safe At/Speed calls).
class RotorMotion {
 public:
  virtual ~RotorMotion() = default;
  /// Unwrapped rotor angle [rad] at time t (continuous; not reduced to [0, 2 pi)).
  virtual double AngleAt(Seconds t) const = 0;
  /// Rotor angular speed d(theta)/dt [rad/s] at time t.
  virtual double SpeedAt(Seconds t) const = 0;
};

/// The largest rotor speed any config accepts [rad/s]: far above any stepper-driven rotor (a NEMA-17 pulls out
/// long before), low enough that a 1 kHz encoder still sees less than half a turn per sample (1000 * pi rad/s).
constexpr double kMaxRotorSpeedRadps = 200.0;

/// An absolute single-turn shaft encoder (e.g. AS5600 12-bit, AS5048 14-bit).
struct EncoderConfig {
  uint32_t counts_per_rev = 4096;   ///< 4096 = 12-bit, 16384 = 14-bit; >= 4 (as RigCalib)
  double noise_sigma_counts = 0.5;  ///< white Gaussian noise before quantisation [counts]; >= 0
  double latency_s = 0.0;           ///< a sample stamped t reports the angle at t - latency_s; >= 0
  double rate_hz = 1000.0;          ///< sample rate for SampleRange; > 0
  double zero_offset_rad = 0.0;     ///< encoder zero: raw angle = theta + zero_offset_rad (see EncoderCalib)

  static EncoderConfig Bits12() { return EncoderConfig{}; }
  static EncoderConfig Bits14() {
    EncoderConfig c;
    c.counts_per_rev = 16384;
    return c;
  }
  bool Validate(std::string* error) const;
  /// The calibration a reader needs to turn counts back into angles (counts_per_rev, zero, rate).
  EncoderCalib ToCalib() const;
};

/// Samples a rotor's TRUE angle, adds seeded noise and quantises, producing what the encoder chip reports:
///   raw   = (theta(t - latency) + zero_offset) / (2 pi) * counts_per_rev + sigma * N(0, 1)
///   count = floor(raw) wrapped to [0, counts_per_rev)
/// so RigCalib::EncoderAngle(count), the centre of the count's bin minus the zero offset, is within half a count
/// of the true angle (plus noise). Noise comes from RandomStream(run_seed, "encoder.noise"). Not thread-safe.
class EncoderModel {
 public:
  EncoderModel(const EncoderConfig& config, uint64_t run_seed);  ///< config must Validate (ROTOLIDAR_CHECK)

  /// One sample stamped `t`.
  EncoderSample Sample(const RotorMotion& rotor, Seconds t);
  /// One sample stamped `t` for a given true angle theta_rad (the caller has already applied the latency:
  /// theta_rad is the angle at t - latency_s). Draws the noise.
  EncoderSample SampleAngle(Seconds t, double theta_rad);
  /// Samples at t0, t0 + 1/rate_hz, ... while t <= t1 (t1 >= t0).
  std::vector<EncoderSample> SampleRange(const RotorMotion& rotor, Seconds t0, Seconds t1);
  /// Quantises a raw encoder angle (theta + zero offset, any real value) to a count in [0, counts_per_rev).
  uint32_t Quantise(double raw_angle_rad, double noise_counts) const;
  const EncoderConfig& config() const { return config_; }

 private:
  EncoderConfig config_;
  RandomStream noise_;
};

/// The same encoder fed by a stream of TRUE joint states (a rotor integrated by physics) instead of a function of
/// time. Samples lie on the grid t_k = k * (1 / rate_hz) (k integer, the grid of EncoderModel::SampleRange from
/// 0); the first is the first grid time >= the first state's time. Sample t_k reports the angle at t_k - latency_s,
/// interpolated (cubic Hermite on theta and omega) between the two pushed states around it; before the first
/// state it extrapolates that state at constant speed. Noise and quantisation as EncoderModel, from the same
/// stream RandomStream(run_seed, "encoder.noise"), so for the same seed and the same true angles both produce
/// the same counts. Not thread-safe.
class EncoderStream {
 public:
  EncoderStream(const EncoderConfig& config, uint64_t run_seed);  ///< config must Validate (ROTOLIDAR_CHECK)

  /// Adds the true state (t_s strictly increasing, ROTOLIDAR_CHECK) and appends to *out every sample stamped
  /// <= state.t_s (+1e-9 s for rounding of accumulated physics times) not emitted yet, in time order.
  void Push(const RotorJointState& state, std::vector<EncoderSample>* out);
  /// The true angle [rad] at time t interpolated from the pushed history (t >= the oldest kept state minus any
  /// amount: extrapolated as described above; kept history covers latency_s plus two pushes).
  double TrueAngleAt(Seconds t) const;
  const EncoderConfig& config() const { return quantiser_.config(); }

 private:
  EncoderModel quantiser_;  // owns the noise stream and the quantisation
  std::deque<RotorJointState> history_;
  int64_t next_k_ = 0;  ///< grid index of the next sample
  bool started_ = false;
};

}  // namespace rotolidar::sim
