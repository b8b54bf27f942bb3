// YAML I/O of ImuConfig (declared in sim/sensors/imu_model.hpp) with the project's one idiom
// (core/io/yaml_fields.hpp): the field list below drives parse and emit. `preset` is read here by hand: it is
// no field but resets the noise before the fields override it.
#include <string>

#include "core/io/yaml_fields.hpp"
#include "sim/sensors/imu_model.hpp"

namespace rotolidar::sim {

/// The noise and error fields, flat in one mapping.
template <class V>
void Visit(V& v, ImuConfig& c) {
  ImuNoise& n = c.noise;
  v("rate_hz", &n.rate_hz), v("gyro_noise_density", &n.gyro_noise_density);
  v("gyro_random_walk", &n.gyro_random_walk), v("accel_noise_density", &n.accel_noise_density);
  v("accel_random_walk", &n.accel_random_walk);
  ImuErrorConfig& e = c.errors;
  v("gyro_turn_on_sigma_radps", &e.gyro_turn_on_sigma_radps);
  v("accel_turn_on_sigma_mps2", &e.accel_turn_on_sigma_mps2);
  v("gyro_scale_sigma", &e.gyro_scale_sigma), v("accel_scale_sigma", &e.accel_scale_sigma);
  v("gyro_misalignment_sigma_rad", &e.gyro_misalignment_sigma_rad);
  v("accel_misalignment_sigma_rad", &e.accel_misalignment_sigma_rad);
  v("imu_clock_offset_s", &e.imu_clock_offset_s), v("imu_clock_drift_ppm", &e.imu_clock_drift_ppm);
}

namespace {

void ParseImu(const std::string& file, const YAML::Node& node, ImuConfig* c) {
  std::set<std::string> keys = yaml::Keys(*c);
  keys.insert("preset");
  yaml::CheckKeys(file, node, keys, "imu");
  if (const YAML::Node preset = node["preset"]) {
    std::string name;
    yaml::ReadAs(file, preset, "imu.preset", &name);
    if (name != "bmi055")
      throw yaml::ParseError(yaml::Where(file, preset) + "imu.preset: unknown preset '" + name + "' (known: bmi055)");
    c->noise = Bmi055Noise();
  }
  yaml::ReadFields(yaml::Section(file, "imu"), node, c);
}

}  // namespace

Status ParseImuConfig(const std::string& file, const YAML::Node& node, ImuConfig* config) {
  if (!node) return Status::Ok();
  ImuConfig c = *config;
  try {
    ParseImu(file, node, &c);
  } catch (const yaml::ParseError& e) {
    return Status::Error(e.what());
  }
  std::string why;
  if (!c.Validate(&why)) return Status::Error(yaml::Where(file, node) + "imu: " + why);
  *config = c;
  return Status::Ok();
}

void EmitImuConfig(YAML::Emitter& out, const ImuConfig& config) { yaml::Emit(out, config); }

}  // namespace rotolidar::sim
