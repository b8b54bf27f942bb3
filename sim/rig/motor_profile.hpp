#pragma once
// Command profiles for the rotor: the reference angle, speed and acceleration the motor controller tracks
// (docs/motor_model.md, "Command profiles").
//
// A profile is a pure function of time on the rig clock. The stepper drive (sim/rig/stepper.hpp) feeds it forward
// and closes its PID around it; ProfileRotor is the ideal rotor that follows it exactly, for analytic and fast
// paths that need no physics. Angles are the rotor angle theta about motor +z [rad], unwrapped.
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "core/types/time.hpp"
#include "sim/rig/motor.hpp"

namespace rotolidar::sim {

enum class MotorProfileType {
  kConstant,   ///< theta = theta0 + speed * t (no ramp: the speed is commanded from t = 0)
  kTrapezoid,  ///< from rest at theta0: ramp at accel to speed, cruise, and (stop_at_s finite) ramp down to rest
  kNodding,    ///< theta = nodding_centre + nodding_amplitude * sin(2 pi f t): sinusoidal back-and-forth
  kStopAndGo,  ///< from rest at theta0: dwell, trapezoidal move of move_angle, dwell, move, ... forever
};

/// The words of the types, in declaration order: "constant", "trapezoid", "nodding", "stop_and_go" (YAML and the
/// command line; core/io/yaml_fields.hpp finds it by argument-dependent lookup).
const std::vector<std::pair<const char*, MotorProfileType>>& EnumWords(MotorProfileType*);
/// The type's word ("unknown" outside the enum).
const char* ToString(MotorProfileType type);
/// Inverse of ToString; false (and *type untouched) for any other name.
bool ParseMotorProfileType(const std::string& name, MotorProfileType* type);

struct MotorProfileConfig {
  MotorProfileType type = MotorProfileType::kTrapezoid;  ///< the seed ramps with a trapezoidal velocity profile
  /// Cruise speed [rad/s] (constant, trapezoid; its sign is the direction) or move speed (stop_and_go; magnitude
  /// only, the direction is move_angle_rad's sign). |speed| <= 200 rad/s. Default: the seed's "2.6", read as
  /// rad/s (docs/motor_model.md, "The seed's angular speed 2.6").
  double speed_radps = 2.6;
  /// Ramp acceleration [rad/s^2] of trapezoid and stop_and_go; > 0. 5.2 reaches 2.6 rad/s in 0.5 s (the seed
  /// gives no number; with the 1e-3 kg m^2 rotor this needs 5.2e-3 N m, 1.3 % of the NEMA-17's holding torque).
  double accel_radps2 = 5.2;
  /// trapezoid: time [s] at which the ramp down starts (infinity = spin forever); >= 0.
  double stop_at_s = std::numeric_limits<double>::infinity();
  double theta0_rad = 0.0;  ///< start angle (constant, trapezoid, stop_and_go; nodding uses its centre)
  double nodding_centre_rad = 0.0;     ///< nodding: centre of the swing
  double nodding_amplitude_rad = M_PI / 4;  ///< nodding: half the swing, > 0 (+-45 deg, a common nodding range)
  double nodding_frequency_hz = 0.5;  ///< nodding: > 0; 0.5 Hz at +-45 deg peaks at 2.47 rad/s, under the seed's 2.6
  double move_angle_rad = M_PI / 2;   ///< stop_and_go: signed angle of each move, != 0 (a quarter turn)
  double dwell_s = 1.0;  ///< stop_and_go: rest before each move [s], >= 0 (10 VLP-16 revolutions at 10 Hz)

  /// False with a message naming the field when a value is unusable for this type.
  bool Validate(std::string* error) const;
  /// The largest |omega| the profile ever commands [rad/s].
  double PeakSpeed() const;
};

/// The constant-speed profile theta(t) = theta0_rad + speed_radps * t (type constant).
MotorProfileConfig ConstantProfile(double speed_radps, double theta0_rad = 0.0);

/// The reference at one instant.
struct MotorReference {
  double theta_rad = 0.0;     ///< unwrapped angle [rad]
  double omega_radps = 0.0;   ///< d(theta)/dt [rad/s]
  double alpha_radps2 = 0.0;  ///< d(omega)/dt [rad/s^2] (one-sided at ramp corners: the value just after t)
};

/// The profile as a pure function of time. Immutable after construction: Reference() is thread-safe.
class MotorProfile {
 public:
  explicit MotorProfile(const MotorProfileConfig& config);  ///< config must Validate (ROTOLIDAR_CHECK)
  /// The reference at rig time t [s]. Defined for every t: before t = 0 trapezoid and stop_and_go rest at theta0,
  /// constant and nodding extend their formulas. theta is continuous in t, omega continuous except the constant
  /// profile's start (none before 0 is ever asked by the sim, which starts at t = 0).
  MotorReference Reference(Seconds t) const;
  const MotorProfileConfig& config() const { return config_; }

 private:
  MotorReference StopAndGo(Seconds t) const;

  MotorProfileConfig config_;
  double move_duration_s_ = 0.0;  ///< stop_and_go: length of one move [s]
};

/// The ideal rotor that follows a profile exactly (no motor, no physics): AngleAt = Reference(t).theta_rad.
/// Immutable, thread-safe.
class ProfileRotor final : public RotorMotion {
 public:
  explicit ProfileRotor(const MotorProfileConfig& config) : profile_(config) {}
  double AngleAt(Seconds t) const override { return profile_.Reference(t).theta_rad; }
  double SpeedAt(Seconds t) const override { return profile_.Reference(t).omega_radps; }
  const MotorProfile& profile() const { return profile_; }

 private:
  MotorProfile profile_;
};

}  // namespace rotolidar::sim
