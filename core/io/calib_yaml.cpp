// calib.yaml <-> RigCalib with the project's one idiom (core/io/yaml_fields.hpp): the field lists below drive
// parse (strict keys, file:line + field in every message) and save.
#include "core/io/calib_yaml.hpp"

#include <fstream>

#include "core/io/yaml_fields.hpp"

namespace rotolidar {

// ---- the field lists (in the structs' namespace, so the generic visitors find them) ----

template <class V>
void Visit(V& v, LidarIntrinsics& c) {
  v("model", yaml::Fixed("VLP-16")), v("elevation_deg", &c.elevation_deg);
  v("vertical_offset_m", &c.vertical_offset_m), v("min_range_m", &c.min_range_m), v("max_range_m", &c.max_range_m);
  v("range_sigma_m", &c.range_sigma_m), v("rpm", &c.rpm);
}

template <class V>
void Visit(V& v, ImuNoise& c) {
  v("rate_hz", &c.rate_hz), v("gyro_noise_density", &c.gyro_noise_density);
  v("gyro_random_walk", &c.gyro_random_walk), v("accel_noise_density", &c.accel_noise_density);
  v("accel_random_walk", &c.accel_random_walk);
}

template <class V>
void Visit(V& v, CameraIntrinsics& c) {
  v("width_px", &c.width_px), v("height_px", &c.height_px), v("fx_px", &c.fx_px), v("fy_px", &c.fy_px);
  v("cx_px", &c.cx_px), v("cy_px", &c.cy_px), v("k1", &c.k1), v("k2", &c.k2), v("p1", &c.p1), v("p2", &c.p2);
  v("rate_hz", &c.rate_hz);
}

template <class V>
void Visit(V& v, EncoderCalib& c) {
  v("counts_per_rev", &c.counts_per_rev), v("zero_offset_rad", &c.zero_offset_rad), v("rate_hz", &c.rate_hz);
}

template <class V>
void Visit(V& v, RigCalib& c) {
  v("format_version", yaml::Required(&c.format_version));
  v("T_base_motor", &c.T_base_motor), v("T_rotor_lidar", &c.T_rotor_lidar);
  v("T_base_imu", &c.T_base_imu), v("T_base_cam", &c.T_base_cam);
  v("motor_speed_radps", &c.motor_speed_radps), v("lidar_clock_offset_s", &c.lidar_clock_offset_s);
  v("epoch_unix_s", &c.epoch_unix_s), v("imu_time_offset_s", &c.imu_time_offset_s);
  v("lidar", &c.lidar), v("imu", &c.imu), v("camera", &c.camera), v("encoder", &c.encoder);
}

Status LoadCalibYaml(const std::string& path, RigCalib* calib) {
  RigCalib c;
  try {
    yaml::Parse(yaml::Section(path, "", "calib"), yaml::LoadFile(path), &c);
  } catch (const yaml::ParseError& e) {
    return Status::Error(e.what());
  } catch (const YAML::Exception& e) {
    return Status::Error(path + ": " + e.what());
  }
  std::string why;
  if (!c.Validate(&why)) return Status::Error(path + ": invalid calibration: " + why);
  *calib = c;
  return Status::Ok();
}

Status SaveCalibYaml(const std::string& path, const RigCalib& c) {
  YAML::Emitter out;
  out.SetDoublePrecision(17);
  yaml::Emit(out, c);
  std::ofstream file(path);
  if (!file) return Status::Error(path + ": cannot open for writing");
  file << out.c_str() << "\n";
  return file ? Status::Ok() : Status::Error(path + ": write failed");
}

}  // namespace rotolidar
