// Command profiles (sim/rig/motor_profile), the motor-drive configs and their YAML (sim/rig/motor_yaml.cpp).
// The drive's closed-loop behaviour is tested in stepper_test.cpp.
#include "sim/rig/motor_profile.hpp"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <limits>
#include <string>

#include "core/util/log.hpp"
#include "sim/rig/stepper.hpp"

namespace rotolidar::sim {
namespace {

MotorProfileConfig Config(MotorProfileType type) {
  MotorProfileConfig c;
  c.type = type;
  return c;
}

// omega is the derivative of theta and alpha that of omega: central differences (h = 1e-5 s) agree to O(h^2)
// except within h of a ramp corner, where alpha jumps (there the difference quotient of omega lies between the two
// one-sided values, checked separately). theta must be continuous everywhere (no jump over 2h).
void ExpectConsistentDerivatives(const MotorProfile& p, double t_end) {
  const double h = 1e-5;
  for (double t = 0.0123; t < t_end; t += 0.0371) {
    const MotorReference a = p.Reference(t - h), b = p.Reference(t), c = p.Reference(t + h);
    EXPECT_NEAR((c.theta_rad - a.theta_rad) / (2 * h), b.omega_radps, 1e-6) << "t " << t;
    const double domega = (c.omega_radps - a.omega_radps) / (2 * h);
    const double lo = std::min(a.alpha_radps2, c.alpha_radps2), hi = std::max(a.alpha_radps2, c.alpha_radps2);
    EXPECT_GE(domega, lo - 1e-4) << "t " << t;
    EXPECT_LE(domega, hi + 1e-4) << "t " << t;
    if (a.alpha_radps2 == c.alpha_radps2) {
      EXPECT_NEAR(domega, b.alpha_radps2, 1e-4) << "t " << t;
    }
  }
}

TEST(MotorProfile, DerivativesAreConsistentForEveryType) {
  MotorProfileConfig trapezoid = Config(MotorProfileType::kTrapezoid);
  trapezoid.stop_at_s = 6.0;
  for (const MotorProfileConfig& c :
       {Config(MotorProfileType::kConstant), trapezoid, Config(MotorProfileType::kNodding),
        Config(MotorProfileType::kStopAndGo)}) {
    SCOPED_TRACE(ToString(c.type));
    ExpectConsistentDerivatives(MotorProfile(c), 12.0);
  }
}

TEST(MotorProfile, TrapezoidRampsHoldsAndStops) {
  MotorProfileConfig c = Config(MotorProfileType::kTrapezoid);
  c.theta0_rad = 0.3;
  c.stop_at_s = 5.0;
  const MotorProfile p(c);
  const double t1 = c.speed_radps / c.accel_radps2;  // 0.5 s
  EXPECT_DOUBLE_EQ(p.Reference(-1.0).theta_rad, 0.3);
  EXPECT_DOUBLE_EQ(p.Reference(0.25).omega_radps, 0.5 * c.speed_radps);
  EXPECT_NEAR(p.Reference(t1).theta_rad, 0.3 + 0.5 * c.speed_radps * t1, 1e-12);
  for (double t = t1; t <= 5.0; t += 0.1) EXPECT_DOUBLE_EQ(p.Reference(t).omega_radps, c.speed_radps);
  // Ramp down from 5 s, rest from 5.5 s: distance = v (stop - t1) + v t1 (two half ramps).
  const double end = 0.3 + c.speed_radps * 5.0;
  EXPECT_NEAR(p.Reference(5.5).theta_rad, end, 1e-12);
  EXPECT_NEAR(p.Reference(100.0).theta_rad, end, 1e-12);
  EXPECT_EQ(p.Reference(100.0).omega_radps, 0.0);
  // Stopping before the cruise speed: a triangle peaking at a * stop_at_s, negative direction.
  c.speed_radps = -2.6;
  c.stop_at_s = 0.2;
  const MotorProfile tri(c);
  EXPECT_NEAR(tri.Reference(0.2).omega_radps, -c.accel_radps2 * 0.2, 1e-12);
  EXPECT_NEAR(tri.Reference(1.0).theta_rad, 0.3 - c.accel_radps2 * 0.2 * 0.2, 1e-12);
  EXPECT_NEAR(c.PeakSpeed(), c.accel_radps2 * 0.2, 1e-12);
}

TEST(MotorProfile, NoddingSwingsWithItsAmplitudeAndFrequency) {
  MotorProfileConfig c = Config(MotorProfileType::kNodding);
  c.nodding_centre_rad = 1.0;
  c.nodding_amplitude_rad = 0.4;
  c.nodding_frequency_hz = 0.8;
  const MotorProfile p(c);
  double lo = 1e9, hi = -1e9;
  for (double t = 0; t < 5.0; t += 1e-4) {
    lo = std::min(lo, p.Reference(t).theta_rad);
    hi = std::max(hi, p.Reference(t).theta_rad);
  }
  EXPECT_NEAR(hi, 1.4, 1e-6);
  EXPECT_NEAR(lo, 0.6, 1e-6);
  for (double t = 0.1; t < 5.0; t += 0.3)
    EXPECT_NEAR(p.Reference(t + 1.0 / 0.8).theta_rad, p.Reference(t).theta_rad, 1e-12);  // period 1/f
  EXPECT_NEAR(c.PeakSpeed(), 0.4 * 2 * M_PI * 0.8, 1e-12);
}

TEST(MotorProfile, StopAndGoDwellsThenMovesTheSetAngle) {
  MotorProfileConfig c = Config(MotorProfileType::kStopAndGo);
  c.theta0_rad = 0.1;
  c.move_angle_rad = -M_PI / 2;
  c.dwell_s = 0.7;
  const MotorProfile p(c);
  // Move: ramp 0.5 s to 2.6 rad/s (0.65 rad), cruise (pi/2 - 1.3) / 2.6 s, ramp 0.5 s.
  const double move_s = 1.0 + (M_PI / 2 - 1.3) / 2.6, period = 0.7 + move_s;
  for (int k = 0; k < 5; ++k) {
    const double start = k * period, base = 0.1 - k * M_PI / 2;
    for (double t = start + 1e-9; t < start + 0.7; t += 0.05) {
      EXPECT_NEAR(p.Reference(t).theta_rad, base, 1e-9) << "dwell, cycle " << k;
      EXPECT_EQ(p.Reference(t).omega_radps, 0.0);
    }
    EXPECT_NEAR(p.Reference(start + period - 1e-9).theta_rad, base - M_PI / 2, 1e-7) << "cycle " << k;
    EXPECT_NEAR(p.Reference(start + 0.7 + move_s / 2).omega_radps, -2.6, 1e-9);
  }
  // A move too short to reach the speed is a triangle: 0.1 rad at 5.2 rad/s^2 peaks at sqrt(0.1 * 5.2).
  c.move_angle_rad = 0.1;
  EXPECT_NEAR(c.PeakSpeed(), std::sqrt(0.1 * 5.2), 1e-12);
  const MotorProfile tri(c);
  EXPECT_NEAR(tri.Reference(0.7 + 2 * std::sqrt(0.1 / 5.2)).theta_rad, 0.2, 1e-12);
}

TEST(MotorProfile, ConstantIsLinearInTimeAndProfileRotorMatchesReference) {
  const ProfileRotor profile_rotor(ConstantProfile(-3.1, 0.25));
  MotorProfileConfig nod = Config(MotorProfileType::kNodding);
  const ProfileRotor nodding(nod);
  for (double t = 0; t < 10; t += 0.37) {
    EXPECT_DOUBLE_EQ(profile_rotor.AngleAt(t), 0.25 - 3.1 * t);
    EXPECT_DOUBLE_EQ(profile_rotor.SpeedAt(t), -3.1);
    EXPECT_EQ(nodding.AngleAt(t), nodding.profile().Reference(t).theta_rad);
    EXPECT_EQ(nodding.SpeedAt(t), nodding.profile().Reference(t).omega_radps);
  }
}

TEST(MotorProfile, TypeNamesRoundTripAndValidateNamesTheField) {
  for (MotorProfileType t : {MotorProfileType::kConstant, MotorProfileType::kTrapezoid, MotorProfileType::kNodding,
                             MotorProfileType::kStopAndGo}) {
    MotorProfileType back = MotorProfileType::kConstant;
    EXPECT_TRUE(ParseMotorProfileType(ToString(t), &back));
    EXPECT_EQ(back, t);
  }
  MotorProfileType untouched = MotorProfileType::kNodding;
  EXPECT_FALSE(ParseMotorProfileType("trapezoidal", &untouched));
  EXPECT_EQ(untouched, MotorProfileType::kNodding);

  struct Case {
    const char* field;
    void (*bad)(MotorProfileConfig*);
  };
  const Case cases[] = {
      {"speed_radps", [](MotorProfileConfig* c) { c->speed_radps = 250.0; }},
      {"accel_radps2", [](MotorProfileConfig* c) { c->accel_radps2 = 0.0; }},
      {"stop_at_s", [](MotorProfileConfig* c) { c->stop_at_s = std::nan(""); }},
      {"theta0_rad", [](MotorProfileConfig* c) { c->theta0_rad = std::numeric_limits<double>::infinity(); }},
      {"nodding_amplitude_rad", [](MotorProfileConfig* c) { c->nodding_amplitude_rad = -0.1; }},
      {"nodding_frequency_hz", [](MotorProfileConfig* c) { c->nodding_frequency_hz = 0.0; }},
      {"move_angle_rad", [](MotorProfileConfig* c) { c->move_angle_rad = 0.0; }},
      {"dwell_s", [](MotorProfileConfig* c) { c->dwell_s = -1.0; }},
  };
  for (const Case& k : cases) {
    MotorProfileConfig c;
    std::string error;
    ASSERT_TRUE(c.Validate(&error)) << error;
    k.bad(&c);
    EXPECT_FALSE(c.Validate(&error)) << k.field;
    EXPECT_NE(error.find(k.field), std::string::npos) << error;
  }
  MotorProfileConfig stop = Config(MotorProfileType::kStopAndGo);
  stop.speed_radps = 0.0;
  std::string error;
  EXPECT_FALSE(stop.Validate(&error));
  EXPECT_NE(error.find("speed_radps"), std::string::npos) << error;
}

// Every field set to a non-default value survives emit -> parse (doubles are written round-trip exact).
TEST(MotorDriveYaml, EmitParseRoundTripIsExact) {
  for (double stop_at_s : {std::numeric_limits<double>::infinity(), 12.5}) {
    MotorDriveConfig c;
    c.profile = {MotorProfileType::kStopAndGo, -1.7, 3.3, stop_at_s, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6};
    c.stepper.full_steps_per_rev = 400;
    c.stepper.microsteps = 32;
    c.stepper.holding_torque_nm = 0.55;
    c.stepper.rotor_inertia_kgm2 = 8.2e-6;
    c.stepper.detent_torque_nm = 0.03;
    c.stepper.step_error_fraction = 0.05;
    c.stepper.torque_ripple_fraction = 0.02;
    c.stepper.viscous_damping_nms = 1e-3;
    c.stepper.rated_current_a = 2.0;
    c.stepper.phase_resistance_ohm = 1.1;
    c.stepper.phase_inductance_h = 2.6e-3;
    c.stepper.supply_voltage_v = 36.0;
    c.stepper.missed_step_rate_hz = 0.25;
    c.pid = {1.5, 30.0, 4e-3, 45.0, 0.5, 1.0, 1.5, 25.0};
    c.encoder = EncoderConfig::Bits14();
    c.encoder.noise_sigma_counts = 0.7;
    c.encoder.latency_s = 3e-4;
    c.encoder.rate_hz = 2000.0;
    c.encoder.zero_offset_rad = 0.123456789;
    std::string error;
    ASSERT_TRUE(c.Validate(&error)) << error;

    YAML::Emitter out;
    EmitMotorDriveConfig(out, c);
    ASSERT_TRUE(out.good()) << out.GetLastError();
    MotorDriveConfig back;
    const Status parsed = ParseMotorDriveConfig("motor.yaml", YAML::Load(out.c_str()), &back);
    ASSERT_TRUE(parsed.ok) << parsed.message;
    EXPECT_TRUE(back == c) << out.c_str();
    MotorDriveConfig defaults;
    EXPECT_FALSE(back == defaults);
  }
}

/// The error message of parsing `text` ("" when it parses); a failed parse leaves the config untouched.
std::string ParseError(const std::string& text) {
  MotorDriveConfig c;
  const Status s = ParseMotorDriveConfig("rig/motor.yaml", YAML::Load(text), &c);
  if (s.ok) return "";
  EXPECT_TRUE(c == MotorDriveConfig()) << "a failed parse must leave the config untouched";
  return s.message;
}

TEST(MotorDriveYaml, ErrorsNameFileLineAndField) {
  std::string e = ParseError("profile:\n  type: nodding\n  speed_radps: 2.0\nstepper:\n  microstep: 8\n");
  EXPECT_NE(e.find("rig/motor.yaml:5"), std::string::npos) << e;
  EXPECT_NE(e.find("microstep"), std::string::npos) << e;
  e = ParseError("pid:\n  kp: 1\nmotor_speed: 3\n");
  EXPECT_NE(e.find("rig/motor.yaml:3"), std::string::npos) << e;
  EXPECT_NE(e.find("motor_speed"), std::string::npos) << e;
  e = ParseError("profile:\n  type: trapezoidal\n");
  EXPECT_NE(e.find("rig/motor.yaml:2"), std::string::npos) << e;
  EXPECT_NE(e.find("trapezoidal"), std::string::npos) << e;
  e = ParseError("encoder:\n  rate_hz: fast\n");
  EXPECT_NE(e.find("rig/motor.yaml:2"), std::string::npos) << e;
  EXPECT_NE(e.find("rate_hz"), std::string::npos) << e;
  e = ParseError("stepper:\n  microsteps: 0\n");  // parses, but does not Validate
  EXPECT_NE(e.find("rig/motor.yaml:1"), std::string::npos) << e;
  EXPECT_NE(e.find("microsteps"), std::string::npos) << e;
  // Partial files keep the defaults of everything they do not name.
  MotorDriveConfig c;
  ASSERT_TRUE(ParseMotorDriveConfig("m.yaml", YAML::Load("profile:\n  type: constant\n"), &c).ok);
  MotorDriveConfig expected;
  expected.profile.type = MotorProfileType::kConstant;
  EXPECT_TRUE(c == expected);
}

// Pull-out torque: holding torque at low speed (current-limited), then the phasor model's current
// |(R + j N_r w L) i + k_t w| = V (checked by substituting back), falling to 0 where the back-EMF uses up the supply.
TEST(StepperConfig, PullOutTorqueFallsWithSpeed) {
  const StepperConfig s;
  EXPECT_DOUBLE_EQ(s.PullOutTorqueNm(0.0), 0.40);
  EXPECT_DOUBLE_EQ(s.PullOutTorqueNm(-2.6), 0.40);
  double prev = 0.41;
  bool uncapped = false;
  for (double w = 1.0; w < 150.0; w += 1.0) {
    const double t = s.PullOutTorqueNm(w);
    EXPECT_LE(t, prev + 1e-12) << "w " << w;
    prev = t;
    if (t > 0 && t < 0.4) {
      uncapped = true;
      const double kt = 0.40 / 1.7, i = t / kt, x = 50 * w * 2.8e-3, emf = kt * w;
      EXPECT_NEAR(std::hypot(1.5 * i + emf, x * i), 24.0, 1e-9) << "w " << w;
    }
  }
  EXPECT_TRUE(uncapped);
  EXPECT_EQ(s.PullOutTorqueNm(150.0), 0.0);
  EXPECT_GT(s.PullOutTorqueNm(40.0), 0.39);  // the corner lies above 40 rad/s (380 rpm)
}

TEST(MotorDriveConfig, ValidateNamesTheField) {
  struct Case {
    const char* field;
    void (*bad)(MotorDriveConfig*);
  };
  const Case cases[] = {
      {"microsteps", [](MotorDriveConfig* c) { c->stepper.microsteps = 0; }},
      {"full_steps_per_rev", [](MotorDriveConfig* c) { c->stepper.full_steps_per_rev = 202; }},
      {"step_error_fraction", [](MotorDriveConfig* c) { c->stepper.step_error_fraction = 0.6; }},
      {"detent_torque_nm", [](MotorDriveConfig* c) { c->stepper.detent_torque_nm = 0.5; }},
      {"missed_step_rate_hz", [](MotorDriveConfig* c) { c->stepper.missed_step_rate_hz = -1; }},
      {"kd_s", [](MotorDriveConfig* c) { c->pid.kd_s = -1e-3; }},
      {"max_step_rate_radps", [](MotorDriveConfig* c) { c->profile.speed_radps = 30.0; }},
      {"speed_filter_hz", [](MotorDriveConfig* c) { c->pid.speed_filter_hz = 600.0; }},
      {"encoder: EncoderConfig: rate_hz", [](MotorDriveConfig* c) { c->encoder.rate_hz = 0.0; }},
      {"profile: MotorProfileConfig: dwell_s", [](MotorDriveConfig* c) { c->profile.dwell_s = -2; }},
  };
  for (const Case& k : cases) {
    MotorDriveConfig c;
    std::string error;
    ASSERT_TRUE(c.Validate(&error)) << error;
    k.bad(&c);
    EXPECT_FALSE(c.Validate(&error)) << k.field;
    EXPECT_NE(error.find(k.field), std::string::npos) << error;
    EXPECT_THROW(StepperDrive(c, 1), InternalError) << k.field;
  }
}

}  // namespace
}  // namespace rotolidar::sim
