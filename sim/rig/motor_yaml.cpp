// YAML for MotorDriveConfig (the edge: parse with yaml::Get/CheckKeys, throw yaml::ParseError naming file:line).
// One field list per struct drives parse, emit and equality, so the three cannot disagree.
#include <yaml-cpp/yaml.h>

#include <string>
#include <utility>
#include <vector>

#include "core/io/yaml_util.hpp"
#include "sim/rig/stepper.hpp"

namespace rotolidar::sim {
namespace {

template <typename S>
using DoubleFields = std::vector<std::pair<const char*, double S::*>>;

const DoubleFields<MotorProfileConfig>& ProfileDoubles() {
  static const DoubleFields<MotorProfileConfig> f = {
      {"speed_radps", &MotorProfileConfig::speed_radps},
      {"accel_radps2", &MotorProfileConfig::accel_radps2},
      {"stop_at_s", &MotorProfileConfig::stop_at_s},
      {"theta0_rad", &MotorProfileConfig::theta0_rad},
      {"nodding_centre_rad", &MotorProfileConfig::nodding_centre_rad},
      {"nodding_amplitude_rad", &MotorProfileConfig::nodding_amplitude_rad},
      {"nodding_frequency_hz", &MotorProfileConfig::nodding_frequency_hz},
      {"move_angle_rad", &MotorProfileConfig::move_angle_rad},
      {"dwell_s", &MotorProfileConfig::dwell_s}};
  return f;
}

const std::vector<std::pair<const char*, int StepperConfig::*>>& StepperInts() {
  static const std::vector<std::pair<const char*, int StepperConfig::*>> f = {
      {"full_steps_per_rev", &StepperConfig::full_steps_per_rev}, {"microsteps", &StepperConfig::microsteps}};
  return f;
}

const DoubleFields<StepperConfig>& StepperDoubles() {
  static const DoubleFields<StepperConfig> f = {
      {"holding_torque_nm", &StepperConfig::holding_torque_nm},
      {"rotor_inertia_kgm2", &StepperConfig::rotor_inertia_kgm2},
      {"detent_torque_nm", &StepperConfig::detent_torque_nm},
      {"step_error_fraction", &StepperConfig::step_error_fraction},
      {"torque_ripple_fraction", &StepperConfig::torque_ripple_fraction},
      {"viscous_damping_nms", &StepperConfig::viscous_damping_nms},
      {"rated_current_a", &StepperConfig::rated_current_a},
      {"phase_resistance_ohm", &StepperConfig::phase_resistance_ohm},
      {"phase_inductance_h", &StepperConfig::phase_inductance_h},
      {"supply_voltage_v", &StepperConfig::supply_voltage_v},
      {"missed_step_rate_hz", &StepperConfig::missed_step_rate_hz}};
  return f;
}

const DoubleFields<PidConfig>& PidDoubles() {
  static const DoubleFields<PidConfig> f = {
      {"kp", &PidConfig::kp},
      {"ki_per_s", &PidConfig::ki_per_s},
      {"kd_s", &PidConfig::kd_s},
      {"speed_filter_hz", &PidConfig::speed_filter_hz},
      {"deadband_counts", &PidConfig::deadband_counts},
      {"integral_limit_rad", &PidConfig::integral_limit_rad},
      {"max_correction_speed_radps", &PidConfig::max_correction_speed_radps},
      {"max_step_rate_radps", &PidConfig::max_step_rate_radps}};
  return f;
}

const DoubleFields<EncoderConfig>& EncoderDoubles() {
  static const DoubleFields<EncoderConfig> f = {
      {"noise_sigma_counts", &EncoderConfig::noise_sigma_counts},
      {"latency_s", &EncoderConfig::latency_s},
      {"rate_hz", &EncoderConfig::rate_hz},
      {"zero_offset_rad", &EncoderConfig::zero_offset_rad}};
  return f;
}

template <typename S, typename T>
void AddKeys(const std::vector<std::pair<const char*, T S::*>>& fields, std::set<std::string>* keys) {
  for (const auto& f : fields) keys->insert(f.first);
}

template <typename S, typename T>
void GetAll(const std::string& file, const YAML::Node& node,
            const std::vector<std::pair<const char*, T S::*>>& fields, S* s) {
  for (const auto& f : fields) yaml::Get(file, node, f.first, &(s->*f.second));
}

template <typename S, typename T>
void EmitAll(YAML::Emitter& out, const std::vector<std::pair<const char*, T S::*>>& fields, const S& s) {
  for (const auto& f : fields) out << YAML::Key << f.first << YAML::Value << s.*f.second;
}

template <typename S, typename T>
bool EqualAll(const std::vector<std::pair<const char*, T S::*>>& fields, const S& a, const S& b) {
  for (const auto& f : fields)
    if (!(a.*f.second == b.*f.second)) return false;
  return true;
}

void ParseProfile(const std::string& file, const YAML::Node& n, MotorProfileConfig* c) {
  std::set<std::string> keys{"type"};
  AddKeys(ProfileDoubles(), &keys);
  yaml::CheckKeys(file, n, keys, "motor.profile");
  std::string type = ToString(c->type);
  yaml::Get(file, n, "type", &type);
  if (!ParseMotorProfileType(type, &c->type))
    throw yaml::ParseError(yaml::Where(file, n["type"]) + "field 'type': unknown motor profile type '" + type +
                           "' (constant, trapezoid, nodding, stop_and_go)");
  GetAll(file, n, ProfileDoubles(), c);
}

void ParseStepper(const std::string& file, const YAML::Node& n, StepperConfig* c) {
  std::set<std::string> keys;
  AddKeys(StepperInts(), &keys);
  AddKeys(StepperDoubles(), &keys);
  yaml::CheckKeys(file, n, keys, "motor.stepper");
  GetAll(file, n, StepperInts(), c);
  GetAll(file, n, StepperDoubles(), c);
}

void ParsePid(const std::string& file, const YAML::Node& n, PidConfig* c) {
  std::set<std::string> keys;
  AddKeys(PidDoubles(), &keys);
  yaml::CheckKeys(file, n, keys, "motor.pid");
  GetAll(file, n, PidDoubles(), c);
}

void ParseEncoder(const std::string& file, const YAML::Node& n, EncoderConfig* c) {
  std::set<std::string> keys{"counts_per_rev"};
  AddKeys(EncoderDoubles(), &keys);
  yaml::CheckKeys(file, n, keys, "motor.encoder");
  yaml::Get(file, n, "counts_per_rev", &c->counts_per_rev);
  GetAll(file, n, EncoderDoubles(), c);
}

}  // namespace

void ParseMotorDriveConfig(const std::string& file, const YAML::Node& node, MotorDriveConfig* config) {
  yaml::CheckKeys(file, node, {"profile", "stepper", "pid", "encoder"}, "motor");
  if (const YAML::Node n = node["profile"]) ParseProfile(file, n, &config->profile);
  if (const YAML::Node n = node["stepper"]) ParseStepper(file, n, &config->stepper);
  if (const YAML::Node n = node["pid"]) ParsePid(file, n, &config->pid);
  if (const YAML::Node n = node["encoder"]) ParseEncoder(file, n, &config->encoder);
  std::string error;
  if (!config->Validate(&error)) throw yaml::ParseError(yaml::Where(file, node) + error);
}

void EmitMotorDriveConfig(YAML::Emitter& out, const MotorDriveConfig& c) {
  out << YAML::BeginMap;
  out << YAML::Key << "profile" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "type" << YAML::Value << ToString(c.profile.type);
  EmitAll(out, ProfileDoubles(), c.profile);
  out << YAML::EndMap;
  out << YAML::Key << "stepper" << YAML::Value << YAML::BeginMap;
  EmitAll(out, StepperInts(), c.stepper);
  EmitAll(out, StepperDoubles(), c.stepper);
  out << YAML::EndMap;
  out << YAML::Key << "pid" << YAML::Value << YAML::BeginMap;
  EmitAll(out, PidDoubles(), c.pid);
  out << YAML::EndMap;
  out << YAML::Key << "encoder" << YAML::Value << YAML::BeginMap;
  out << YAML::Key << "counts_per_rev" << YAML::Value << c.encoder.counts_per_rev;
  EmitAll(out, EncoderDoubles(), c.encoder);
  out << YAML::EndMap;
  out << YAML::EndMap;
}

bool operator==(const MotorDriveConfig& a, const MotorDriveConfig& b) {
  return a.profile.type == b.profile.type && EqualAll(ProfileDoubles(), a.profile, b.profile) &&
         EqualAll(StepperInts(), a.stepper, b.stepper) && EqualAll(StepperDoubles(), a.stepper, b.stepper) &&
         EqualAll(PidDoubles(), a.pid, b.pid) && a.encoder.counts_per_rev == b.encoder.counts_per_rev &&
         EqualAll(EncoderDoubles(), a.encoder, b.encoder);
}

}  // namespace rotolidar::sim
