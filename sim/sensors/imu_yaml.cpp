// YAML I/O of ImuConfig (declared in sim/sensors/imu_model.hpp).
#include <string>

#include "core/io/yaml_util.hpp"
#include "sim/sensors/imu_model.hpp"

namespace rotolidar::sim {

void ParseImuConfig(const std::string& file, const YAML::Node& node, ImuConfig* config) {
  using yaml::Get;
  if (!node) return;
  yaml::CheckKeys(file, node,
                  {"preset", "rate_hz", "gyro_noise_density", "gyro_random_walk", "accel_noise_density",
                   "accel_random_walk", "gyro_turn_on_sigma_radps", "accel_turn_on_sigma_mps2", "gyro_scale_sigma",
                   "accel_scale_sigma", "gyro_misalignment_sigma_rad", "accel_misalignment_sigma_rad",
                   "imu_clock_offset_s"},
                  "imu");
  ImuConfig c = *config;
  if (node["preset"]) {
    std::string preset;
    Get(file, node, "preset", &preset);
    if (preset != "bmi055")
      throw yaml::ParseError(yaml::Where(file, node["preset"]) + "imu.preset: unknown preset '" + preset +
                             "' (known: bmi055)");
    c.noise = Bmi055Noise();
  }
  Get(file, node, "rate_hz", &c.noise.rate_hz);
  Get(file, node, "gyro_noise_density", &c.noise.gyro_noise_density);
  Get(file, node, "gyro_random_walk", &c.noise.gyro_random_walk);
  Get(file, node, "accel_noise_density", &c.noise.accel_noise_density);
  Get(file, node, "accel_random_walk", &c.noise.accel_random_walk);
  ImuErrorConfig& e = c.errors;
  Get(file, node, "gyro_turn_on_sigma_radps", &e.gyro_turn_on_sigma_radps);
  Get(file, node, "accel_turn_on_sigma_mps2", &e.accel_turn_on_sigma_mps2);
  Get(file, node, "gyro_scale_sigma", &e.gyro_scale_sigma);
  Get(file, node, "accel_scale_sigma", &e.accel_scale_sigma);
  Get(file, node, "gyro_misalignment_sigma_rad", &e.gyro_misalignment_sigma_rad);
  Get(file, node, "accel_misalignment_sigma_rad", &e.accel_misalignment_sigma_rad);
  Get(file, node, "imu_clock_offset_s", &e.imu_clock_offset_s);
  std::string why;
  if (!c.Validate(&why)) throw yaml::ParseError(yaml::Where(file, node) + "imu: " + why);
  *config = c;
}

void EmitImuConfig(YAML::Emitter& out, const ImuConfig& config) {
  const ImuNoise& n = config.noise;
  const ImuErrorConfig& e = config.errors;
  const std::pair<const char*, double> fields[] = {
      {"rate_hz", n.rate_hz},
      {"gyro_noise_density", n.gyro_noise_density},
      {"gyro_random_walk", n.gyro_random_walk},
      {"accel_noise_density", n.accel_noise_density},
      {"accel_random_walk", n.accel_random_walk},
      {"gyro_turn_on_sigma_radps", e.gyro_turn_on_sigma_radps},
      {"accel_turn_on_sigma_mps2", e.accel_turn_on_sigma_mps2},
      {"gyro_scale_sigma", e.gyro_scale_sigma},
      {"accel_scale_sigma", e.accel_scale_sigma},
      {"gyro_misalignment_sigma_rad", e.gyro_misalignment_sigma_rad},
      {"accel_misalignment_sigma_rad", e.accel_misalignment_sigma_rad},
      {"imu_clock_offset_s", e.imu_clock_offset_s}};
  out << YAML::BeginMap;
  for (const auto& [key, value] : fields) out << YAML::Key << key << YAML::Value << value;
  out << YAML::EndMap;
}

}  // namespace rotolidar::sim
