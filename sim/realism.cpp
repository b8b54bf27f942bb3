// What each realism preset sets. The magnitudes and their sources are tabulated in docs/noise_models.md
// ("Realism presets"); keep the two in step.
#include "sim/realism.hpp"

#include "core/io/yaml_fields.hpp"
#include "sim/lidar/lidar_realism.hpp"
#include "sim/sim_config.hpp"

namespace rotolidar::sim {

const std::vector<std::pair<const char*, Realism>>& EnumWords(Realism*) {
  static const std::vector<std::pair<const char*, Realism>> words = {
      {"ideal", Realism::kIdeal}, {"typical", Realism::kTypical}, {"harsh", Realism::kHarsh}};
  return words;
}

Status RealismFromWord(const std::string& word, Realism* r) {
  if (yaml::EnumFromWord(word, r)) return Status::Ok();
  return Status::Error(yaml::EnumWordsText<Realism>() + " (got '" + word + "')");
}

namespace {

/// Sensor clocks. typical: a PPS-disciplined VLP-16, an idle host's sub-millisecond receive delay, the other
/// sensors stamped on quartz clocks (+-20 ppm) with millisecond-level unmodelled latencies; harsh: a free-running
/// head and a loaded host, with the latencies of unsynchronised consumer sensors.
ClockConfig ClockPreset(Realism r) {
  ClockConfig c;  // ideal: no offset, no drift, PPS synced, no capture delay
  if (r == Realism::kTypical) {
    c.lidar_capture = {0.0003, 0.0001};
    c.encoder_offset_s = 0.0005, c.encoder_drift_ppm = 20.0;
    c.camera_offset_s = 0.003, c.camera_drift_ppm = 20.0;
  } else if (r == Realism::kHarsh) {
    c.lidar_pps_synced = false, c.lidar_drift_ppm = 50.0;
    c.lidar_capture = {0.001, 0.001};
    c.encoder_offset_s = 0.002, c.encoder_drift_ppm = 50.0;
    c.camera_offset_s = 0.02, c.camera_drift_ppm = 50.0;
  }
  return c;
}

/// IMU errors beyond its noise. typical: an IMU whose scale and alignment were calibrated once (residuals a
/// quarter of the uncalibrated unit's); harsh: uncalibrated, with the datasheet's uncompensated zero-rate offset.
void ApplyImuPreset(Realism r, ImuErrorConfig* e) {
  *e = ImuErrorConfig{};
  if (r == Realism::kTypical) {
    e->gyro_scale_sigma = e->accel_scale_sigma = 0.005;
    e->gyro_misalignment_sigma_rad = e->accel_misalignment_sigma_rad = 0.002;
    e->imu_clock_offset_s = 0.001, e->imu_clock_drift_ppm = 20.0;
  } else if (r == Realism::kHarsh) {
    e->gyro_turn_on_sigma_radps = 0.017, e->accel_turn_on_sigma_mps2 = 0.1;
    e->gyro_scale_sigma = e->accel_scale_sigma = 0.02;
    e->gyro_misalignment_sigma_rad = e->accel_misalignment_sigma_rad = 0.01;
    e->imu_clock_offset_s = 0.005, e->imu_clock_drift_ppm = 50.0;
  }
}

}  // namespace

void ApplyRealism(Realism r, SimConfig* config) {
  config->realism = r;
  config->clocks = ClockPreset(r);
  config->rig_errors = RigErrorPreset(r);  // calibration errors, axis wobble, rotor vibration (sim/rig/rig_errors)
  ApplyImuPreset(r, &config->imu.errors);
  ApplyLidarRealism(r, &config->lidar);  // range noise model, range walk, blooming, mirrors, beam footprint
  // The head's spin-rate wander (1-sigma, Gauss-Markov): invisible to a decoder that reads the packets' azimuths.
  config->lidar.rpm_jitter_frac = r == Realism::kIdeal ? 0.0 : r == Realism::kTypical ? 0.005 : 0.02;
}

}  // namespace rotolidar::sim
