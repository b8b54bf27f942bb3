#include "sim/sim_config.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>

#include "core/io/yaml_util.hpp"

#ifndef ROTOLIDAR_SOURCE_DIR
#define ROTOLIDAR_SOURCE_DIR "."
#endif

namespace rotolidar::sim {
namespace {

const char* ReturnModeName(Vlp16ReturnMode mode) {
  switch (mode) {
    case Vlp16ReturnMode::kLast: return "last";
    case Vlp16ReturnMode::kDual: return "dual";
    default: return "strongest";
  }
}

void ParseLidar(const std::string& path, const YAML::Node& n, Vlp16CasterConfig* c) {
  using yaml::Get;
  yaml::CheckKeys(path, n,
                  {"rpm", "rpm_jitter_frac", "rpm_jitter_tau_s", "range_noise_sigma_m", "min_range_m", "max_range_m",
                   "grazing_cutoff_deg", "min_intensity_for_return", "intensity_attenuation_per_m", "beam_rings",
                   "beam_divergence_horizontal_mrad", "beam_divergence_vertical_mrad", "echo_separation_m",
                   "material_transmittance", "max_surfaces_per_ray", "pose_per_firing"},
                  "lidar");
  Get(path, n, "rpm", &c->rpm);
  Get(path, n, "rpm_jitter_frac", &c->rpm_jitter_frac);
  Get(path, n, "rpm_jitter_tau_s", &c->rpm_jitter_tau_s);
  Get(path, n, "range_noise_sigma_m", &c->range_noise_sigma_m);
  Get(path, n, "min_range_m", &c->min_range_m);
  Get(path, n, "max_range_m", &c->max_range_m);
  Get(path, n, "grazing_cutoff_deg", &c->grazing_cutoff_deg);
  Get(path, n, "min_intensity_for_return", &c->min_intensity_for_return);
  Get(path, n, "intensity_attenuation_per_m", &c->intensity_attenuation_per_m);
  Get(path, n, "beam_rings", &c->beam_rings);
  Get(path, n, "beam_divergence_horizontal_mrad", &c->beam_divergence_horizontal_mrad);
  Get(path, n, "beam_divergence_vertical_mrad", &c->beam_divergence_vertical_mrad);
  Get(path, n, "echo_separation_m", &c->echo_separation_m);
  Get(path, n, "max_surfaces_per_ray", &c->max_surfaces_per_ray);
  Get(path, n, "pose_per_firing", &c->pose_per_firing);
  if (const YAML::Node m = n["material_transmittance"]) {
    if (!m.IsMap()) throw yaml::ParseError(yaml::Where(path, m) + "lidar.material_transmittance: a map name -> fraction");
    c->material_transmittance.clear();
    for (const auto& kv : m) {
      double fraction = 0.0;
      Get(path, m, kv.first.as<std::string>(), &fraction);
      c->material_transmittance.emplace_back(kv.first.as<std::string>(), fraction);
    }
  }
}

void EmitLidar(YAML::Emitter& out, const Vlp16CasterConfig& c) {
  out << YAML::BeginMap;
  out << YAML::Key << "rpm" << YAML::Value << c.rpm;
  out << YAML::Key << "rpm_jitter_frac" << YAML::Value << c.rpm_jitter_frac;
  out << YAML::Key << "rpm_jitter_tau_s" << YAML::Value << c.rpm_jitter_tau_s;
  out << YAML::Key << "range_noise_sigma_m" << YAML::Value << c.range_noise_sigma_m;
  out << YAML::Key << "min_range_m" << YAML::Value << c.min_range_m;
  out << YAML::Key << "max_range_m" << YAML::Value << c.max_range_m;
  out << YAML::Key << "grazing_cutoff_deg" << YAML::Value << c.grazing_cutoff_deg;
  out << YAML::Key << "min_intensity_for_return" << YAML::Value << c.min_intensity_for_return;
  out << YAML::Key << "intensity_attenuation_per_m" << YAML::Value << c.intensity_attenuation_per_m;
  out << YAML::Key << "beam_rings" << YAML::Value << c.beam_rings;
  out << YAML::Key << "beam_divergence_horizontal_mrad" << YAML::Value << c.beam_divergence_horizontal_mrad;
  out << YAML::Key << "beam_divergence_vertical_mrad" << YAML::Value << c.beam_divergence_vertical_mrad;
  out << YAML::Key << "echo_separation_m" << YAML::Value << c.echo_separation_m;
  out << YAML::Key << "material_transmittance" << YAML::Value << YAML::BeginMap;
  for (const auto& [name, fraction] : c.material_transmittance) out << YAML::Key << name << YAML::Value << fraction;
  out << YAML::EndMap;
  out << YAML::Key << "max_surfaces_per_ray" << YAML::Value << c.max_surfaces_per_ray;
  out << YAML::Key << "pose_per_firing" << YAML::Value << c.pose_per_firing;
  out << YAML::EndMap;
}

void ParseRigModelSection(const std::string& path, const YAML::Node& n, RigModelConfig* c) {
  if (!n.IsScalar()) {
    ParseRigModelConfig(path, n, c);
    return;
  }
  std::filesystem::path file = n.as<std::string>();
  if (file.is_relative()) file = std::filesystem::path(path).parent_path() / file;
  if (Status s = LoadRigModelConfig(file.string(), c); !s)
    throw yaml::ParseError(yaml::Where(path, n) + "rig_model: " + s.message);
}

void ParseTop(const std::string& path, const YAML::Node& root, SimConfig* c) {
  using yaml::Get;
  yaml::CheckKeys(path, root,
                  {"seed", "duration_s", "scene", "truth_rate_hz", "return_mode", "rig_model", "carrier", "motor",
                   "imu", "lidar", "clocks", "camera"},
                  "sim");
  Get(path, root, "seed", &c->seed);
  Get(path, root, "duration_s", &c->duration_s);
  Get(path, root, "scene", &c->scene);
  Get(path, root, "truth_rate_hz", &c->truth_rate_hz);
  std::string mode = ReturnModeName(c->return_mode);
  Get(path, root, "return_mode", &mode);
  if (mode == "strongest") c->return_mode = Vlp16ReturnMode::kStrongest;
  else if (mode == "last") c->return_mode = Vlp16ReturnMode::kLast;
  else if (mode == "dual") c->return_mode = Vlp16ReturnMode::kDual;
  else throw yaml::ParseError(yaml::Where(path, root["return_mode"]) + "return_mode: strongest, last or dual");
  c->lidar.return_mode = c->return_mode;
  if (const YAML::Node n = root["clocks"]) {
    yaml::CheckKeys(path, n, {"lidar_offset_s", "encoder_offset_s"}, "clocks");
    Get(path, n, "lidar_offset_s", &c->clocks.lidar_offset_s);
    Get(path, n, "encoder_offset_s", &c->clocks.encoder_offset_s);
  }
}

}  // namespace

bool ClockConfig::Validate(std::string* error) const {
  for (const auto& [name, v] : {std::pair{"lidar_offset_s", lidar_offset_s}, {"encoder_offset_s", encoder_offset_s}}) {
    if (!std::isfinite(v) || std::abs(v) > 1.0) {
      if (error) *error = std::string("clocks.") + name + " must be finite with |offset| <= 1 s";
      return false;
    }
  }
  return true;
}

RigCalib DefaultRigCalib() {
  RigCalib c;
  FillRigGeometry(RigModelConfig{}, &c);  // the MJCF's default geometry (docs/frames.md, docs/rig_model.md)
  c.motor_speed_radps = MotorProfileConfig{}.speed_radps;
  return c;
}

RigCalib SimConfig::TrueCalib() const {
  RigCalib c;
  FillRigGeometry(rig_model, &c);
  c.lidar = lidar_intrinsics;
  c.lidar.range_sigma_m = lidar.range_noise_sigma_m;  // the caster's noise, as a rig owner would measure it
  c.lidar.rpm = lidar.rpm;                            // the head's configured speed (its jitter is not known)
  c.imu = imu.noise;
  c.encoder = motor.encoder.ToCalib();
  c.motor_speed_radps = motor.profile.speed_radps;
  c.lidar_clock_offset_s = clocks.lidar_offset_s;
  c.camera = camera.Intrinsics();
  return c;
}

SimConfig DefaultSimConfig() { return SimConfig{}; }

bool SimConfig::Validate(std::string* error) const {
  auto fail = [&](const std::string& m) {
    if (error) *error = m;
    return false;
  };
  if (!(duration_s > 0 && duration_s <= 24 * 3600.0)) return fail("duration_s must be in (0, 86400]");
  if (!(truth_rate_hz > 0)) return fail("truth_rate_hz must be > 0");
  if (scene.empty()) return fail("scene must name a scene");
  std::string why;
  if (!rig_model.Validate(&why)) return fail("rig_model: " + why);
  // Handheld/wheeled without waypoints take the scene's default path: validated once the scene is loaded.
  if (!carrier_from_scene && !UsesSceneDefaultPath(carrier) && !carrier.Validate(&why))
    return fail("carrier: " + why);
  if (!motor.Validate(&why)) return fail("motor: " + why);
  if (!imu.Validate(&why)) return fail("imu: " + why);
  if (!lidar.Validate(&why)) return fail("lidar: " + why);
  if (!clocks.Validate(&why)) return fail(why);
  if (!camera.Validate(&why)) return fail(why);
  if (lidar.return_mode != return_mode) return fail("lidar.return_mode must equal return_mode");
  // The physics loop samples the IMU at step boundaries: its period must be a whole number of steps.
  const double steps_per_imu = 1.0 / (imu.noise.rate_hz * rig_model.physics.timestep_s);
  if (std::abs(steps_per_imu - std::round(steps_per_imu)) > 1e-9 || std::round(steps_per_imu) < 1)
    return fail("imu.rate_hz must divide the physics rate 1 / rig_model.physics.timestep_s");
  if (!(rig_model.physics.timestep_s * truth_rate_hz <= 1.0)) return fail("truth_rate_hz must not exceed the physics rate");
  RigCalib calib = TrueCalib();
  if (!calib.Validate(&why)) return fail("calibration: " + why);
  return true;
}

std::string ResolveScenePath(const std::string& scene) {
  namespace fs = std::filesystem;
  if (fs::exists(scene)) return scene;
  const char* env = std::getenv("ROTOLIDAR_SCENES");
  const std::string dir = env ? env : std::string(ROTOLIDAR_SOURCE_DIR) + "/scenes";
  return dir + "/" + scene + ".yaml";
}

std::vector<std::string> AvailableScenes() {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(ResolveScenePath("")).parent_path();  // "" never exists: "<dir>/.yaml"
  std::vector<std::string> names;
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec))
    if (it->is_regular_file() && it->path().extension() == ".yaml") names.push_back(it->path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

Status FindSceneFile(const std::string& scene, std::string* path) {
  const std::string file = ResolveScenePath(scene);
  if (std::filesystem::is_regular_file(file)) {
    *path = file;
    return Status::Ok();
  }
  std::string names;
  for (const std::string& n : AvailableScenes()) names += (names.empty() ? "" : ", ") + n;
  return Status::Error("unknown scene '" + scene + "' (no file " + file + "); available scenes: " +
                       (names.empty() ? "none found" : names) + " (or give a scene file's path)");
}

Status LoadSimConfig(const std::string& path, SimConfig* config) {
  try {
    return ParseSimConfig(path, yaml::LoadFile(path), config);
  } catch (const yaml::ParseError& e) {
    return Status::Error(e.what());
  }
}

Status ParseSimConfig(const std::string& path, const YAML::Node& root, SimConfig* config) {
  SimConfig c = *config;
  try {
    if (!root.IsMap() && !root.IsNull())
      throw yaml::ParseError(yaml::Where(path, root) + "sim config: expected a mapping");
    ParseTop(path, root, &c);
    if (const YAML::Node n = root["rig_model"]) ParseRigModelSection(path, n, &c.rig_model);
    if (const YAML::Node n = root["carrier"]) {
      ParseCarrierConfig(path, n, &c.carrier);
      if (n.IsMap() && n["type"]) c.carrier_from_scene = false;  // the file names the carrier
    }
    if (const YAML::Node n = root["motor"]) ParseMotorDriveConfig(path, n, &c.motor);
    if (const YAML::Node n = root["imu"]) ParseImuConfig(path, n, &c.imu);
    if (const YAML::Node n = root["lidar"]) ParseLidar(path, n, &c.lidar);
    if (const YAML::Node n = root["camera"]) ParseCameraConfig(path, n, &c.camera);
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
  out << YAML::Key << "rig_model" << YAML::Value;
  EmitRigModelConfig(out, c.rig_model);
  out << YAML::Key << "carrier" << YAML::Value;
  EmitCarrierConfig(out, c.carrier);
  out << YAML::Key << "motor" << YAML::Value;
  EmitMotorDriveConfig(out, c.motor);
  out << YAML::Key << "imu" << YAML::Value;
  EmitImuConfig(out, c.imu);
  out << YAML::Key << "lidar" << YAML::Value;
  EmitLidar(out, c.lidar);
  out << YAML::Key << "clocks" << YAML::Value << YAML::BeginMap << YAML::Key << "lidar_offset_s" << YAML::Value
      << c.clocks.lidar_offset_s << YAML::Key << "encoder_offset_s" << YAML::Value << c.clocks.encoder_offset_s
      << YAML::EndMap;
  out << YAML::Key << "camera" << YAML::Value;
  EmitCameraConfig(out, c.camera);
  out << YAML::EndMap;
}

}  // namespace rotolidar::sim
