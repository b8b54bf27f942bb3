#include "sim/rig/motor_profile.hpp"

#include <algorithm>
#include <cmath>

#include "core/util/log.hpp"

namespace rotolidar::sim {
namespace {


/// A move from rest along +: accelerate at a for t1, cruise at a*t1 for tc (may be infinite), decelerate at a for
/// t1, then rest. Evaluated at tau >= 0 after the move starts; theta is the distance covered.
struct Ramp {
  double a = 0.0, t1 = 0.0, tc = 0.0;

  MotorReference At(double tau) const {
    if (tau < 0.0) return {};
    const double peak = a * t1, d1 = 0.5 * a * t1 * t1;
    if (tau < t1) return {0.5 * a * tau * tau, a * tau, a};
    if (tau < t1 + tc) return {d1 + peak * (tau - t1), peak, 0.0};
    const double u = tau - t1 - tc;  // only reached with a finite tc
    if (u < t1) return {d1 + peak * tc + peak * u - 0.5 * a * u * u, peak - a * u, -a};
    return {2.0 * d1 + peak * tc, 0.0, 0.0};
  }
};

/// Trapezoid of the continuous profile: ramp to |speed|, cruise until stop_at_s, ramp down.
Ramp TrapezoidRamp(const MotorProfileConfig& c) {
  Ramp r;
  r.a = c.accel_radps2;
  r.t1 = std::min(std::abs(c.speed_radps) / c.accel_radps2, c.stop_at_s);
  r.tc = c.stop_at_s - r.t1;  // infinite when stop_at_s is
  return r;
}

/// One stop-and-go move of |move_angle| at |speed| (a triangle when the move is too short to reach the speed).
Ramp MoveRamp(const MotorProfileConfig& c) {
  const double d = std::abs(c.move_angle_rad), v = std::abs(c.speed_radps), a = c.accel_radps2;
  Ramp r;
  r.a = a;
  if (d >= v * v / a) {
    r.t1 = v / a;
    r.tc = (d - v * v / a) / v;
  } else {
    r.t1 = std::sqrt(d / a);
  }
  return r;
}

MotorReference Scaled(const MotorReference& r, double sign, double offset) {
  return {offset + sign * r.theta_rad, sign * r.omega_radps, sign * r.alpha_radps2};
}

double Sign(double x) { return x < 0.0 ? -1.0 : 1.0; }

}  // namespace

const std::vector<std::pair<const char*, MotorProfileType>>& EnumWords(MotorProfileType*) {
  static const std::vector<std::pair<const char*, MotorProfileType>> words{
      {"constant", MotorProfileType::kConstant},
      {"trapezoid", MotorProfileType::kTrapezoid},
      {"nodding", MotorProfileType::kNodding},
      {"stop_and_go", MotorProfileType::kStopAndGo}};
  return words;
}

const char* ToString(MotorProfileType type) {
  for (const auto& [word, t] : EnumWords(static_cast<MotorProfileType*>(nullptr)))
    if (t == type) return word;
  return "unknown";
}

bool ParseMotorProfileType(const std::string& name, MotorProfileType* type) {
  for (const auto& [word, t] : EnumWords(static_cast<MotorProfileType*>(nullptr)))
    if (name == word) return *type = t, true;
  return false;
}

bool MotorProfileConfig::Validate(std::string* error) const {
  auto fail = [error](const std::string& m) {
    if (error) *error = "MotorProfileConfig: " + m;
    return false;
  };
  if (std::string(ToString(type)) == "unknown") return fail("type is not a known profile type");
  if (!std::isfinite(speed_radps) || std::abs(speed_radps) > kMaxRotorSpeedRadps)
    return fail("speed_radps must be finite with |speed_radps| <= " + std::to_string(int(kMaxRotorSpeedRadps)) + " rad/s");
  if (!std::isfinite(accel_radps2) || accel_radps2 <= 0) return fail("accel_radps2 must be finite and > 0");
  if (std::isnan(stop_at_s) || stop_at_s < 0) return fail("stop_at_s must be >= 0 (infinity: never stop)");
  if (!std::isfinite(theta0_rad)) return fail("theta0_rad must be finite");
  if (!std::isfinite(nodding_centre_rad)) return fail("nodding_centre_rad must be finite");
  if (!std::isfinite(nodding_amplitude_rad) || nodding_amplitude_rad <= 0)
    return fail("nodding_amplitude_rad must be finite and > 0");
  if (!std::isfinite(nodding_frequency_hz) || nodding_frequency_hz <= 0)
    return fail("nodding_frequency_hz must be finite and > 0");
  if (type == MotorProfileType::kNodding && PeakSpeed() > kMaxRotorSpeedRadps)
    return fail("nodding_amplitude_rad * 2 pi * nodding_frequency_hz must be <= " +
                std::to_string(int(kMaxRotorSpeedRadps)) + " rad/s");
  if (!std::isfinite(move_angle_rad) || move_angle_rad == 0) return fail("move_angle_rad must be finite and != 0");
  if (!std::isfinite(dwell_s) || dwell_s < 0) return fail("dwell_s must be finite and >= 0");
  if (type == MotorProfileType::kStopAndGo && speed_radps == 0)
    return fail("speed_radps must be != 0 for stop_and_go (the move speed)");
  return true;
}

double MotorProfileConfig::PeakSpeed() const {
  switch (type) {
    case MotorProfileType::kConstant: return std::abs(speed_radps);
    case MotorProfileType::kTrapezoid: {
      const Ramp r = TrapezoidRamp(*this);
      return r.a * r.t1;
    }
    case MotorProfileType::kNodding: return nodding_amplitude_rad * 2.0 * M_PI * nodding_frequency_hz;
    case MotorProfileType::kStopAndGo: {
      const Ramp r = MoveRamp(*this);
      return r.a * r.t1;
    }
  }
  return 0.0;
}

MotorProfileConfig ConstantProfile(double speed_radps, double theta0_rad) {
  MotorProfileConfig c;
  c.type = MotorProfileType::kConstant;
  c.speed_radps = speed_radps;
  c.theta0_rad = theta0_rad;
  return c;
}

MotorProfile::MotorProfile(const MotorProfileConfig& config) : config_(config) {
  std::string error;
  ROTOLIDAR_CHECK(config_.Validate(&error), error);
  const Ramp move = MoveRamp(config_);
  move_duration_s_ = 2.0 * move.t1 + move.tc;
}

MotorReference MotorProfile::Reference(Seconds t) const {
  const MotorProfileConfig& c = config_;
  switch (c.type) {
    case MotorProfileType::kConstant: return {c.theta0_rad + c.speed_radps * t, c.speed_radps, 0.0};
    case MotorProfileType::kTrapezoid: return Scaled(TrapezoidRamp(c).At(t), Sign(c.speed_radps), c.theta0_rad);
    case MotorProfileType::kNodding: {
      const double w = 2.0 * M_PI * c.nodding_frequency_hz, s = std::sin(w * t);
      const double a = c.nodding_amplitude_rad;
      return {c.nodding_centre_rad + a * s, a * w * std::cos(w * t), -a * w * w * s};
    }
    case MotorProfileType::kStopAndGo: return StopAndGo(t);
  }
  return {};
}

MotorReference MotorProfile::StopAndGo(Seconds t) const {
  const MotorProfileConfig& c = config_;
  if (t <= 0.0) return {c.theta0_rad, 0.0, 0.0};
  const double period = c.dwell_s + move_duration_s_;
  const double k = std::floor(t / period);
  const double tau = t - k * period;  // [0, period) up to rounding
  const double base = c.theta0_rad + k * c.move_angle_rad;
  if (tau < c.dwell_s) return {base, 0.0, 0.0};
  return Scaled(MoveRamp(c).At(tau - c.dwell_s), Sign(c.move_angle_rad), base);
}

}  // namespace rotolidar::sim
