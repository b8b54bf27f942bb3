// YAML of the fault injection (declared in sim/faults/faults.hpp) with the project's one idiom
// (core/io/yaml_fields.hpp): the sim config's `faults:` section and the truth file truth/faults.yaml.
#include <fstream>

#include "core/io/yaml_fields.hpp"
#include "sim/faults/faults.hpp"

namespace rotolidar::sim {

template <class V>
void Visit(V& v, FaultInterval& c) {
  v("start_s", &c.start_s), v("duration_s", &c.duration_s);
}

template <class V>
void Visit(V& v, LidarLossFault& c) {
  v("probability", &c.probability), v("burst_rate_hz", &c.burst_rate_hz);
  v("burst_length_packets", &c.burst_length_packets);
}

template <class V>
void Visit(V& v, LidarDuplicateFault& c) {
  v("probability", &c.probability);
}

template <class V>
void Visit(V& v, LidarReorderFault& c) {
  v("probability", &c.probability), v("max_distance_packets", &c.max_distance_packets);
}

template <class V>
void Visit(V& v, ImuDropoutFault& c) {
  v("start_s", &c.start_s), v("duration_s", &c.duration_s), v("probability", &c.probability);
}

template <class V>
void Visit(V& v, ImuSaturationFault& c) {
  v("gyro_range_radps", &c.gyro_range_radps), v("accel_range_mps2", &c.accel_range_mps2);
}

template <class V>
void Visit(V& v, FaultConfig& c) {
  v("lidar_loss", &c.lidar_loss), v("lidar_duplicate", &c.lidar_duplicate), v("lidar_reorder", &c.lidar_reorder);
  v("lidar_blind", &c.lidar_blind), v("encoder_freeze", &c.encoder_freeze), v("imu_dropout", &c.imu_dropout);
  v("imu_saturation", &c.imu_saturation);
}

template <class V>
void Visit(V& v, LidarFaultTruth& c) {
  v("data_packets_in", &c.data_packets_in), v("data_packets_out", &c.data_packets_out);
  v("lost_random", &c.lost_random), v("lost_burst", &c.lost_burst), v("bursts", &c.bursts);
  v("duplicated", &c.duplicated), v("swaps", &c.swaps), v("arrived_after_newer", &c.arrived_after_newer);
  v("blinded", &c.blinded), v("blinded_interval_s", &c.blinded_interval_s);
}

template <class V>
void Visit(V& v, EncoderFaultTruth& c) {
  v("frozen_samples", &c.frozen_samples), v("frozen_count", &c.frozen_count);
  v("frozen_interval_s", &c.frozen_interval_s);
}

template <class V>
void Visit(V& v, ImuFaultTruth& c) {
  v("samples_in", &c.samples_in), v("dropped_interval", &c.dropped_interval);
  v("dropped_interval_s", &c.dropped_interval_s), v("dropped_random", &c.dropped_random);
  v("saturated_samples", &c.saturated_samples);
}

template <class V>
void Visit(V& v, FaultTruth& c) {
  v("config", &c.config), v("lidar", &c.lidar), v("encoder", &c.encoder), v("imu", &c.imu);
}

namespace {
std::string FaultsTruthPath(const std::string& dir) { return dir + "/truth/faults.yaml"; }
}  // namespace

Status ParseFaultConfig(const std::string& file, const YAML::Node& node, FaultConfig* config) {
  if (!node) return Status::Ok();
  FaultConfig c = *config;
  try {
    yaml::Parse(yaml::Section(file, "faults"), node, &c);
  } catch (const yaml::ParseError& e) {
    return Status::Error(e.what());
  }
  std::string why;
  if (!c.Validate(&why)) return Status::Error(yaml::Where(file, node) + why);
  *config = c;
  return Status::Ok();
}

void EmitFaultConfig(YAML::Emitter& out, const FaultConfig& config) { yaml::Emit(out, config); }

Status WriteFaultTruth(const std::string& recording_dir, const FaultTruth& truth) {
  YAML::Emitter out;
  out.SetDoublePrecision(17);  // reads back to the identical double
  yaml::Emit(out, truth);
  const std::string path = FaultsTruthPath(recording_dir);
  std::ofstream file(path);
  file << "# Faults injected into this recording (sim/faults/faults.hpp): the configuration and what it did.\n"
       << "# Intervals are [first, last] stamp of the messages hit [s]; bursts: [first, last, packets].\n"
       << out.c_str() << "\n";
  return file ? Status::Ok() : Status::Error(path + ": write failed");
}

Status ReadFaultTruth(const std::string& recording_dir, FaultTruth* truth) {
  const std::string path = FaultsTruthPath(recording_dir);
  FaultTruth t;
  try {
    yaml::Parse(yaml::Section(path, "", "faults"), yaml::LoadFile(path), &t);
  } catch (const yaml::ParseError& e) {
    return Status::Error(e.what());
  }
  *truth = t;
  return Status::Ok();
}

}  // namespace rotolidar::sim
