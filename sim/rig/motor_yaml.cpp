// YAML for MotorDriveConfig with the project's one idiom (core/io/yaml_fields.hpp): one field list per struct
// drives parse (strict keys, file:line + field in every message), emit and equality, so the three cannot disagree.
#include <string>

#include "core/io/yaml_fields.hpp"
#include "sim/rig/stepper.hpp"

namespace rotolidar::sim {

// ---- the field lists (in the structs' namespace, so the generic visitors find them) ----

template <class V>
void Visit(V& v, MotorProfileConfig& c) {
  v("type", &c.type), v("speed_radps", &c.speed_radps), v("accel_radps2", &c.accel_radps2);
  v("stop_at_s", &c.stop_at_s), v("theta0_rad", &c.theta0_rad), v("nodding_centre_rad", &c.nodding_centre_rad);
  v("nodding_amplitude_rad", &c.nodding_amplitude_rad), v("nodding_frequency_hz", &c.nodding_frequency_hz);
  v("move_angle_rad", &c.move_angle_rad), v("dwell_s", &c.dwell_s);
}

template <class V>
void Visit(V& v, StepperConfig& c) {
  v("full_steps_per_rev", &c.full_steps_per_rev), v("microsteps", &c.microsteps);
  v("holding_torque_nm", &c.holding_torque_nm), v("rotor_inertia_kgm2", &c.rotor_inertia_kgm2);
  v("detent_torque_nm", &c.detent_torque_nm), v("step_error_fraction", &c.step_error_fraction);
  v("torque_ripple_fraction", &c.torque_ripple_fraction), v("viscous_damping_nms", &c.viscous_damping_nms);
  v("rated_current_a", &c.rated_current_a), v("phase_resistance_ohm", &c.phase_resistance_ohm);
  v("phase_inductance_h", &c.phase_inductance_h), v("supply_voltage_v", &c.supply_voltage_v);
  v("missed_step_rate_hz", &c.missed_step_rate_hz);
}

template <class V>
void Visit(V& v, PidConfig& c) {
  v("kp", &c.kp), v("ki_per_s", &c.ki_per_s), v("kd_s", &c.kd_s), v("speed_filter_hz", &c.speed_filter_hz);
  v("deadband_counts", &c.deadband_counts), v("integral_limit_rad", &c.integral_limit_rad);
  v("max_correction_speed_radps", &c.max_correction_speed_radps), v("max_step_rate_radps", &c.max_step_rate_radps);
}

template <class V>
void Visit(V& v, EncoderConfig& c) {
  v("counts_per_rev", &c.counts_per_rev), v("noise_sigma_counts", &c.noise_sigma_counts);
  v("latency_s", &c.latency_s), v("rate_hz", &c.rate_hz), v("zero_offset_rad", &c.zero_offset_rad);
}

template <class V>
void Visit(V& v, MotorDriveConfig& c) {
  v("profile", &c.profile), v("stepper", &c.stepper), v("pid", &c.pid), v("encoder", &c.encoder);
}

// ---- public functions ----

Status ParseMotorDriveConfig(const std::string& file, const YAML::Node& node, MotorDriveConfig* config) {
  MotorDriveConfig c = *config;
  try {
    yaml::Parse(yaml::Section(file, "motor"), node, &c);
  } catch (const yaml::ParseError& e) {
    return Status::Error(e.what());
  }
  std::string error;
  if (!c.Validate(&error)) return Status::Error(yaml::Where(file, node) + error);
  *config = c;
  return Status::Ok();
}

void EmitMotorDriveConfig(YAML::Emitter& out, const MotorDriveConfig& c) { yaml::Emit(out, c); }

bool operator==(const MotorDriveConfig& a, const MotorDriveConfig& b) { return yaml::Equal(a, b); }

}  // namespace rotolidar::sim
