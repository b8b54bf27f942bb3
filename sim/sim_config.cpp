#include "sim/sim_config.hpp"

#include <cstdlib>
#include <filesystem>

#include "core/io/yaml_util.hpp"

#ifndef ROTOLIDAR_SOURCE_DIR
#define ROTOLIDAR_SOURCE_DIR "."
#endif

namespace rotolidar::sim {
namespace {

Pose3 PoseFromRpy(const Eigen::Vector3d& t_m, double roll_rad, double pitch_rad, double yaw_rad) {
  Pose3 T = Pose3::Identity();
  T.linear() = (Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(pitch_rad, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(roll_rad, Eigen::Vector3d::UnitX()))
                  .toRotationMatrix();
  T.translation() = t_m;
  return T;
}

const char* ReturnModeName(Vlp16ReturnMode mode) {
  switch (mode) {
    case Vlp16ReturnMode::kLast: return "last";
    case Vlp16ReturnMode::kDual: return "dual";
    default: return "strongest";
  }
}

}  // namespace

RigCalib DefaultRigCalib() {
  RigCalib c;
  // Motor frame: z (the motor axis) along base +x, 12 cm ahead of the base origin (the seed's forward scanner).
  c.T_base_motor = PoseFromRpy({0.12, 0.0, 0.0}, 0.0, M_PI / 2, 0.0);
  // The VLP-16 sits 8 cm out along the motor axis, its spin axis (lidar z) along rotor +x, across the motor axis.
  c.T_rotor_lidar = PoseFromRpy({0.0, 0.0, 0.08}, 0.0, M_PI / 2, 0.0);
  // IMU on the platform, slightly offset and rotated (a real board is never perfectly aligned).
  c.T_base_imu = PoseFromRpy({-0.05, 0.03, -0.04}, 0.01, -0.02, 0.03);
  // Forward-looking camera: cam z = base x, cam x = -base y, cam y = -base z.
  Pose3 T_base_cam = Pose3::Identity();
  T_base_cam.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  T_base_cam.translation() = Eigen::Vector3d(0.05, 0.0, 0.10);
  c.T_base_cam = T_base_cam;
  c.motor_speed_radps = 2.6;
  return c;
}

SimConfig DefaultSimConfig() {
  SimConfig c;
  c.rig = DefaultRigCalib();
  c.motor.speed_radps = c.rig.motor_speed_radps;
  c.encoder.counts_per_rev = c.rig.encoder.counts_per_rev;
  return c;
}

bool SimConfig::Validate(std::string* error) const {
  auto fail = [&](const std::string& m) {
    if (error) *error = m;
    return false;
  };
  if (!(duration_s > 0 && duration_s <= 24 * 3600.0)) return fail("duration_s must be in (0, 86400]");
  if (!(truth_rate_hz > 0)) return fail("truth_rate_hz must be > 0");
  if (scene.empty()) return fail("scene must name a scene");
  std::string why;
  if (!rig.Validate(&why)) return fail("rig: " + why);
  if (!motion.Validate(&why)) return fail("motion: " + why);
  if (!motor.Validate(&why)) return fail("motor: " + why);
  if (!encoder.Validate(&why)) return fail("encoder: " + why);
  if (!imu_bias.Validate(&why)) return fail("imu_bias: " + why);
  if (!lidar.Validate(&why)) return fail("lidar: " + why);
  if (encoder.counts_per_rev != rig.encoder.counts_per_rev) return fail("encoder.counts_per_rev != rig's");
  return true;
}

std::string ResolveScenePath(const std::string& scene) {
  namespace fs = std::filesystem;
  if (fs::exists(scene)) return scene;
  const char* env = std::getenv("ROTOLIDAR_SCENES");
  const std::string dir = env ? env : std::string(ROTOLIDAR_SOURCE_DIR) + "/scenes";
  return dir + "/" + scene + ".yaml";
}

Status LoadSimConfig(const std::string& path, SimConfig* config) {
  using yaml::Get;
  SimConfig c = *config;
  try {
    const YAML::Node root = yaml::LoadFile(path);
    yaml::CheckKeys(path, root,
                    {"seed", "duration_s", "scene", "truth_rate_hz", "return_mode", "motor", "encoder", "motion",
                     "lidar", "imu"},
                    "sim");
    Get(path, root, "seed", &c.seed);
    Get(path, root, "duration_s", &c.duration_s);
    Get(path, root, "scene", &c.scene);
    Get(path, root, "truth_rate_hz", &c.truth_rate_hz);
    std::string mode = ReturnModeName(c.return_mode);
    Get(path, root, "return_mode", &mode);
    if (mode == "strongest") c.return_mode = Vlp16ReturnMode::kStrongest;
    else if (mode == "last") c.return_mode = Vlp16ReturnMode::kLast;
    else if (mode == "dual") c.return_mode = Vlp16ReturnMode::kDual;
    else throw yaml::ParseError(yaml::Where(path, root["return_mode"]) + "return_mode: strongest, last or dual");
    if (const YAML::Node n = root["motor"]) {
      yaml::CheckKeys(path, n, {"speed_radps", "theta0_rad"}, "motor");
      Get(path, n, "speed_radps", &c.motor.speed_radps);
      Get(path, n, "theta0_rad", &c.motor.theta0_rad);
      c.rig.motor_speed_radps = c.motor.speed_radps;
    }
    if (const YAML::Node n = root["encoder"]) {
      yaml::CheckKeys(path, n, {"counts_per_rev", "noise_sigma_counts", "latency_s", "rate_hz"}, "encoder");
      Get(path, n, "counts_per_rev", &c.encoder.counts_per_rev);
      Get(path, n, "noise_sigma_counts", &c.encoder.noise_sigma_counts);
      Get(path, n, "latency_s", &c.encoder.latency_s);
      Get(path, n, "rate_hz", &c.encoder.rate_hz);
      c.rig.encoder = c.encoder.ToCalib();
    }
    if (const YAML::Node n = root["motion"]) {
      yaml::CheckKeys(path, n,
                      {"center_x_m", "center_y_m", "radius_x_m", "radius_y_m", "height_m", "loop_period_s",
                       "bounce_amplitude_m", "bounce_hz"},
                      "motion");
      Get(path, n, "center_x_m", &c.motion.center_x_m);
      Get(path, n, "center_y_m", &c.motion.center_y_m);
      Get(path, n, "radius_x_m", &c.motion.radius_x_m);
      Get(path, n, "radius_y_m", &c.motion.radius_y_m);
      Get(path, n, "height_m", &c.motion.height_m);
      Get(path, n, "loop_period_s", &c.motion.loop_period_s);
      Get(path, n, "bounce_amplitude_m", &c.motion.bounce_amplitude_m);
      Get(path, n, "bounce_hz", &c.motion.bounce_hz);
    }
    if (const YAML::Node n = root["lidar"]) {
      yaml::CheckKeys(path, n, {"rpm", "rpm_jitter_frac", "range_noise_sigma_m", "max_range_m"}, "lidar");
      Get(path, n, "rpm", &c.lidar.rpm);
      Get(path, n, "rpm_jitter_frac", &c.lidar.rpm_jitter_frac);
      Get(path, n, "range_noise_sigma_m", &c.lidar.range_noise_sigma_m);
      Get(path, n, "max_range_m", &c.lidar.max_range_m);
    }
    if (const YAML::Node n = root["imu"]) {
      yaml::CheckKeys(path, n, {"gyro_noise_density", "gyro_random_walk", "accel_noise_density", "accel_random_walk"},
                      "imu");
      Get(path, n, "gyro_noise_density", &c.rig.imu.gyro_noise_density);
      Get(path, n, "gyro_random_walk", &c.rig.imu.gyro_random_walk);
      Get(path, n, "accel_noise_density", &c.rig.imu.accel_noise_density);
      Get(path, n, "accel_random_walk", &c.rig.imu.accel_random_walk);
    }
  } catch (const yaml::ParseError& e) {
    return Status::Error(e.what());
  }
  std::string why;
  if (!c.Validate(&why)) return Status::Error(path + ": invalid sim config: " + why);
  *config = c;
  return Status::Ok();
}

void EmitSimConfig(YAML::Emitter& out, const SimConfig& c) {
  out << YAML::BeginMap;
  out << YAML::Key << "seed" << YAML::Value << c.seed;
  out << YAML::Key << "duration_s" << YAML::Value << c.duration_s;
  out << YAML::Key << "scene" << YAML::Value << c.scene;
  out << YAML::Key << "truth_rate_hz" << YAML::Value << c.truth_rate_hz;
  out << YAML::Key << "return_mode" << YAML::Value << ReturnModeName(c.return_mode);
  out << YAML::Key << "motor" << YAML::Value << YAML::BeginMap << YAML::Key << "speed_radps" << YAML::Value
      << c.motor.speed_radps << YAML::Key << "theta0_rad" << YAML::Value << c.motor.theta0_rad << YAML::EndMap;
  out << YAML::Key << "encoder" << YAML::Value << YAML::BeginMap << YAML::Key << "counts_per_rev" << YAML::Value
      << c.encoder.counts_per_rev << YAML::Key << "noise_sigma_counts" << YAML::Value << c.encoder.noise_sigma_counts
      << YAML::Key << "latency_s" << YAML::Value << c.encoder.latency_s << YAML::Key << "rate_hz" << YAML::Value
      << c.encoder.rate_hz << YAML::EndMap;
  const auto& m = c.motion;
  out << YAML::Key << "motion" << YAML::Value << YAML::BeginMap << YAML::Key << "center_x_m" << YAML::Value
      << m.center_x_m << YAML::Key << "center_y_m" << YAML::Value << m.center_y_m << YAML::Key << "radius_x_m"
      << YAML::Value << m.radius_x_m << YAML::Key << "radius_y_m" << YAML::Value << m.radius_y_m << YAML::Key
      << "height_m" << YAML::Value << m.height_m << YAML::Key << "loop_period_s" << YAML::Value << m.loop_period_s
      << YAML::Key << "bounce_amplitude_m" << YAML::Value << m.bounce_amplitude_m << YAML::Key << "bounce_hz"
      << YAML::Value << m.bounce_hz << YAML::EndMap;
  out << YAML::Key << "lidar" << YAML::Value << YAML::BeginMap << YAML::Key << "rpm" << YAML::Value << c.lidar.rpm
      << YAML::Key << "rpm_jitter_frac" << YAML::Value << c.lidar.rpm_jitter_frac << YAML::Key
      << "range_noise_sigma_m" << YAML::Value << c.lidar.range_noise_sigma_m << YAML::Key << "max_range_m"
      << YAML::Value << c.lidar.max_range_m << YAML::EndMap;
  out << YAML::Key << "imu" << YAML::Value << YAML::BeginMap << YAML::Key << "gyro_noise_density" << YAML::Value
      << c.rig.imu.gyro_noise_density << YAML::Key << "gyro_random_walk" << YAML::Value << c.rig.imu.gyro_random_walk
      << YAML::Key << "accel_noise_density" << YAML::Value << c.rig.imu.accel_noise_density << YAML::Key
      << "accel_random_walk" << YAML::Value << c.rig.imu.accel_random_walk << YAML::EndMap;
  out << YAML::EndMap;
}

}  // namespace rotolidar::sim
