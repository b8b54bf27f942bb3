#include "core/io/calib_yaml.hpp"

#include <fstream>
#include <vector>

#include "core/io/yaml_util.hpp"

namespace rotolidar {
namespace {

using yaml::CheckKeys;
using yaml::Get;

void ParseLidar(const std::string& f, const YAML::Node& n, LidarIntrinsics* l) {
  CheckKeys(f, n, {"model", "elevation_deg", "vertical_offset_m", "min_range_m", "max_range_m", "range_sigma_m",
                "rpm"},
            "lidar");
  std::string model = "VLP-16";
  Get(f, n, "model", &model);
  if (model != "VLP-16") throw yaml::ParseError(yaml::Where(f, n["model"]) + "lidar.model: only VLP-16 is supported");
  std::vector<double> elev(l->elevation_deg.begin(), l->elevation_deg.end());
  std::vector<double> off(l->vertical_offset_m.begin(), l->vertical_offset_m.end());
  Get(f, n, "elevation_deg", &elev);
  Get(f, n, "vertical_offset_m", &off);
  if (elev.size() != 16 || off.size() != 16)
    throw yaml::ParseError(yaml::Where(f, n) + "lidar: elevation_deg and vertical_offset_m need 16 values each");
  std::copy(elev.begin(), elev.end(), l->elevation_deg.begin());
  std::copy(off.begin(), off.end(), l->vertical_offset_m.begin());
  Get(f, n, "min_range_m", &l->min_range_m);
  Get(f, n, "max_range_m", &l->max_range_m);
  Get(f, n, "range_sigma_m", &l->range_sigma_m);
  Get(f, n, "rpm", &l->rpm);
}

void ParseImu(const std::string& f, const YAML::Node& n, ImuNoise* imu) {
  CheckKeys(f, n, {"rate_hz", "gyro_noise_density", "gyro_random_walk", "accel_noise_density", "accel_random_walk"},
            "imu");
  Get(f, n, "rate_hz", &imu->rate_hz);
  Get(f, n, "gyro_noise_density", &imu->gyro_noise_density);
  Get(f, n, "gyro_random_walk", &imu->gyro_random_walk);
  Get(f, n, "accel_noise_density", &imu->accel_noise_density);
  Get(f, n, "accel_random_walk", &imu->accel_random_walk);
}

void ParseCamera(const std::string& f, const YAML::Node& n, CameraIntrinsics* c) {
  CheckKeys(f, n, {"width_px", "height_px", "fx_px", "fy_px", "cx_px", "cy_px", "k1", "k2", "p1", "p2", "rate_hz"},
            "camera");
  Get(f, n, "width_px", &c->width_px);
  Get(f, n, "height_px", &c->height_px);
  Get(f, n, "fx_px", &c->fx_px);
  Get(f, n, "fy_px", &c->fy_px);
  Get(f, n, "cx_px", &c->cx_px);
  Get(f, n, "cy_px", &c->cy_px);
  Get(f, n, "k1", &c->k1);
  Get(f, n, "k2", &c->k2);
  Get(f, n, "p1", &c->p1);
  Get(f, n, "p2", &c->p2);
  Get(f, n, "rate_hz", &c->rate_hz);
}

void ParseEncoder(const std::string& f, const YAML::Node& n, EncoderCalib* e) {
  CheckKeys(f, n, {"counts_per_rev", "zero_offset_rad", "rate_hz"}, "encoder");
  Get(f, n, "counts_per_rev", &e->counts_per_rev);
  Get(f, n, "zero_offset_rad", &e->zero_offset_rad);
  Get(f, n, "rate_hz", &e->rate_hz);
}

void ParseCalib(const std::string& f, const YAML::Node& root, RigCalib* c) {
  CheckKeys(f, root,
            {"format_version", "T_base_motor", "T_rotor_lidar", "T_base_imu", "T_base_cam", "motor_speed_radps",
             "lidar_clock_offset_s", "epoch_unix_s", "lidar", "imu", "camera", "encoder"},
            "calib");
  if (!root["format_version"]) throw yaml::ParseError(f + ": missing required key 'format_version'");
  Get(f, root, "format_version", &c->format_version);
  yaml::GetPose(f, root, "T_base_motor", &c->T_base_motor);
  yaml::GetPose(f, root, "T_rotor_lidar", &c->T_rotor_lidar);
  yaml::GetPose(f, root, "T_base_imu", &c->T_base_imu);
  yaml::GetPose(f, root, "T_base_cam", &c->T_base_cam);
  Get(f, root, "motor_speed_radps", &c->motor_speed_radps);
  Get(f, root, "lidar_clock_offset_s", &c->lidar_clock_offset_s);
  Get(f, root, "epoch_unix_s", &c->epoch_unix_s);
  if (root["lidar"]) ParseLidar(f, root["lidar"], &c->lidar);
  if (root["imu"]) ParseImu(f, root["imu"], &c->imu);
  if (root["camera"]) ParseCamera(f, root["camera"], &c->camera);
  if (root["encoder"]) ParseEncoder(f, root["encoder"], &c->encoder);
}

}  // namespace

Status LoadCalibYaml(const std::string& path, RigCalib* calib) {
  RigCalib c;
  try {
    ParseCalib(path, yaml::LoadFile(path), &c);
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
  out << YAML::BeginMap;
  out << YAML::Key << "format_version" << YAML::Value << c.format_version;
  yaml::EmitPose(out, "T_base_motor", c.T_base_motor);
  yaml::EmitPose(out, "T_rotor_lidar", c.T_rotor_lidar);
  yaml::EmitPose(out, "T_base_imu", c.T_base_imu);
  yaml::EmitPose(out, "T_base_cam", c.T_base_cam);
  out << YAML::Key << "motor_speed_radps" << YAML::Value << c.motor_speed_radps;
  out << YAML::Key << "lidar_clock_offset_s" << YAML::Value << c.lidar_clock_offset_s;
  out << YAML::Key << "epoch_unix_s" << YAML::Value << c.epoch_unix_s;
  out << YAML::Key << "lidar" << YAML::Value << YAML::BeginMap << YAML::Key << "model" << YAML::Value << "VLP-16"
      << YAML::Key << "elevation_deg" << YAML::Value << YAML::Flow
      << std::vector<double>(c.lidar.elevation_deg.begin(), c.lidar.elevation_deg.end()) << YAML::Key
      << "vertical_offset_m" << YAML::Value << YAML::Flow
      << std::vector<double>(c.lidar.vertical_offset_m.begin(), c.lidar.vertical_offset_m.end()) << YAML::Key
      << "min_range_m" << YAML::Value << c.lidar.min_range_m << YAML::Key << "max_range_m" << YAML::Value
      << c.lidar.max_range_m << YAML::Key << "range_sigma_m" << YAML::Value << c.lidar.range_sigma_m
      << YAML::Key << "rpm" << YAML::Value << c.lidar.rpm << YAML::EndMap;
  out << YAML::Key << "imu" << YAML::Value << YAML::BeginMap << YAML::Key << "rate_hz" << YAML::Value
      << c.imu.rate_hz << YAML::Key << "gyro_noise_density" << YAML::Value << c.imu.gyro_noise_density << YAML::Key
      << "gyro_random_walk" << YAML::Value << c.imu.gyro_random_walk << YAML::Key << "accel_noise_density"
      << YAML::Value << c.imu.accel_noise_density << YAML::Key << "accel_random_walk" << YAML::Value
      << c.imu.accel_random_walk << YAML::EndMap;
  const CameraIntrinsics& k = c.camera;
  out << YAML::Key << "camera" << YAML::Value << YAML::BeginMap << YAML::Key << "width_px" << YAML::Value
      << k.width_px << YAML::Key << "height_px" << YAML::Value << k.height_px << YAML::Key << "fx_px" << YAML::Value
      << k.fx_px << YAML::Key << "fy_px" << YAML::Value << k.fy_px << YAML::Key << "cx_px" << YAML::Value << k.cx_px
      << YAML::Key << "cy_px" << YAML::Value << k.cy_px << YAML::Key << "k1" << YAML::Value << k.k1 << YAML::Key
      << "k2" << YAML::Value << k.k2 << YAML::Key << "p1" << YAML::Value << k.p1 << YAML::Key << "p2" << YAML::Value
      << k.p2 << YAML::Key << "rate_hz" << YAML::Value << k.rate_hz << YAML::EndMap;
  out << YAML::Key << "encoder" << YAML::Value << YAML::BeginMap << YAML::Key << "counts_per_rev" << YAML::Value
      << c.encoder.counts_per_rev << YAML::Key << "zero_offset_rad" << YAML::Value << c.encoder.zero_offset_rad
      << YAML::Key << "rate_hz" << YAML::Value << c.encoder.rate_hz << YAML::EndMap;
  out << YAML::EndMap;
  std::ofstream file(path);
  if (!file) return Status::Error(path + ": cannot open for writing");
  file << out.c_str() << "\n";
  return file ? Status::Ok() : Status::Error(path + ": write failed");
}

}  // namespace rotolidar
