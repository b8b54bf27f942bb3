// SimConfig: YAML with the project's one idiom (core/io/yaml_fields.hpp; each section a field list or another
// module's own parser), validation, the true calibration and scene lookup.
#include "sim/sim_config.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>

#include "core/io/yaml_fields.hpp"

#ifndef ROTOLIDAR_SOURCE_DIR
#define ROTOLIDAR_SOURCE_DIR "."
#endif

namespace rotolidar::sim {
namespace {

/// lidar.material_transmittance: a mapping material name -> fraction, kept in file order.
void ReadTransmittance(const yaml::Section& at, const YAML::Node& m, std::vector<std::pair<std::string, double>>* out) {
  if (!m.IsMap()) throw yaml::ParseError(yaml::Where(at.file, m) + at.path + ": a map name -> fraction");
  out->clear();
  for (const auto& kv : m) {
    const std::string name = yaml::KeyName(at.file, kv.first, at.path);
    double fraction = 0.0;
    yaml::ReadAs(at.file, kv.second, at.Field(name), &fraction);
    out->emplace_back(name, fraction);
  }
}

void EmitTransmittance(YAML::Emitter& out, const std::vector<std::pair<std::string, double>>& m) {
  out << YAML::BeginMap;
  for (const auto& [name, fraction] : m) out << YAML::Key << name << YAML::Value << fraction;
  out << YAML::EndMap;
}

/// rig_model: a mapping of overrides, or the path of a rig parameter file (relative to the config's folder).
Status ReadRigModel(const yaml::Section& at, const YAML::Node& n, RigModelConfig* c) {
  if (!n.IsScalar()) return ParseRigModelConfig(at.file, n, c);
  std::filesystem::path file = n.as<std::string>();
  if (file.is_relative()) file = std::filesystem::path(at.file).parent_path() / file;
  if (Status s = LoadRigModelConfig(file.string(), c); !s)
    return Status::Error(yaml::Where(at.file, n) + "rig_model: " + s.message);
  return Status::Ok();
}

/// A section another module parses (with its own validation) and emits.
template <class T>
auto Module(T* value, Status (*parse)(const std::string&, const YAML::Node&, T*),
            void (*emit)(YAML::Emitter&, const T&)) {
  return yaml::Custom(
      value, [parse](const yaml::Section& at, const YAML::Node& n, T* v) { return parse(at.file, n, v); }, emit);
}

}  // namespace

// ---- the field lists (in the structs' namespace, so the generic visitors find them) ----

template <class V>
void Visit(V& v, Vlp16CasterConfig& c) {
  v("rpm", &c.rpm), v("rpm_jitter_frac", &c.rpm_jitter_frac), v("rpm_jitter_tau_s", &c.rpm_jitter_tau_s);
  v("range_noise_sigma_m", &c.range_noise_sigma_m), v("min_range_m", &c.min_range_m);
  v("max_range_m", &c.max_range_m), v("grazing_cutoff_deg", &c.grazing_cutoff_deg);
  v("min_intensity_for_return", &c.min_intensity_for_return);
  v("intensity_attenuation_per_m", &c.intensity_attenuation_per_m), v("beam_rings", &c.beam_rings);
  v("beam_divergence_horizontal_mrad", &c.beam_divergence_horizontal_mrad);
  v("beam_divergence_vertical_mrad", &c.beam_divergence_vertical_mrad);
  v("echo_separation_m", &c.echo_separation_m);
  v("material_transmittance", yaml::Custom(&c.material_transmittance, ReadTransmittance, EmitTransmittance));
  v("max_surfaces_per_ray", &c.max_surfaces_per_ray), v("pose_per_firing", &c.pose_per_firing);
  v("range_noise_per_m", &c.range_noise_per_m);
  v("range_noise_incidence_exponent", &c.range_noise_incidence_exponent);
  v("range_noise_min_cos", &c.range_noise_min_cos), v("range_noise_weak_power", &c.range_noise_weak_power);
  v("range_noise_weak_max_gain", &c.range_noise_weak_max_gain), v("range_bias_curve", &c.range_bias_curve);
  v("bloom_halo_mrad", &c.bloom_halo_mrad), v("bloom_power_fraction", &c.bloom_power_fraction);
  v("specular_reflections", &c.specular_reflections);
}

template <class V>
void Visit(V& v, ClockConfig& c) {
  v("lidar_offset_s", &c.lidar_offset_s), v("lidar_drift_ppm", &c.lidar_drift_ppm);
  v("lidar_pps_synced", &c.lidar_pps_synced), v("encoder_offset_s", &c.encoder_offset_s);
  v("encoder_drift_ppm", &c.encoder_drift_ppm), v("camera_offset_s", &c.camera_offset_s);
  v("camera_drift_ppm", &c.camera_drift_ppm), v("lidar_capture_latency_s", &c.lidar_capture.latency_s);
  v("lidar_capture_jitter_scale_s", &c.lidar_capture.jitter_scale_s);
}

/// A config file that names carrier.type clears carrier_from_scene (the file chose the carrier).
template <class V>
void Visit(V& v, SimConfig& c) {
  v("seed", &c.seed), v("realism", &c.realism), v("duration_s", &c.duration_s), v("scene", &c.scene), v("truth_rate_hz", &c.truth_rate_hz);
  v("return_mode", &c.return_mode);
  v("rig_model", yaml::Custom(&c.rig_model, ReadRigModel, EmitRigModelConfig));
  const auto read_carrier = [&c](const yaml::Section& at, const YAML::Node& n, CarrierConfig* carrier) {
    if (Status s = ParseCarrierConfig(at.file, n, carrier); !s) return s;
    if (n.IsMap() && n["type"]) c.carrier_from_scene = false;
    return Status::Ok();
  };
  v("carrier", yaml::Custom(&c.carrier, read_carrier, EmitCarrierConfig));
  v("motor", Module(&c.motor, ParseMotorDriveConfig, EmitMotorDriveConfig));
  v("imu", Module(&c.imu, ParseImuConfig, EmitImuConfig)), v("lidar", &c.lidar), v("clocks", &c.clocks);
  v("camera", Module(&c.camera, ParseCameraConfig, EmitCameraConfig));
  // Written only when enabled: a run without rig errors keeps its sim_config.yaml as before.
  v("rig_errors",
    yaml::EmitIf(c.rig_errors.Enabled(), Module(&c.rig_errors, ParseRigErrorConfig, EmitRigErrorConfig)));
  v("faults", yaml::EmitIf(c.faults.Enabled(), Module(&c.faults, ParseFaultConfig, EmitFaultConfig)));
}

bool ClockConfig::Validate(std::string* error) const {
  // The raw lidar drift is checked even when the PPS makes it inert: a bad value is a bad file either way.
  return SensorClock{lidar_offset_s, lidar_drift_ppm}.Validate("clocks.lidar", error) &&
         Encoder().Validate("clocks.encoder", error) && Camera().Validate("clocks.camera", error) &&
         lidar_capture.Validate("clocks.lidar_capture", error);
}

ClockTruth SimConfig::TrueClocks() const {
  ClockTruth t;
  t.lidar = clocks.Lidar();
  t.lidar_pps_synced = clocks.lidar_pps_synced;
  t.imu = {imu.errors.imu_clock_offset_s, imu.errors.imu_clock_drift_ppm};
  t.encoder = clocks.Encoder();
  t.camera = clocks.Camera();
  t.lidar_capture = clocks.lidar_capture;
  return t;
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
  c.lidar_clock_offset_s = clocks.lidar_offset_s;  // nominal: the drift and capture jitter are not known
  c.imu_time_offset_s = imu.errors.imu_clock_offset_s;  // at rig time 0 (its drift is in truth/clocks.yaml)
  c.camera = camera.Intrinsics();
  return c;
}

RigCalib SimConfig::BelievedCalib() const {
  RigCalib c = ApplyCalibErrors(TrueCalib(), DrawCalibErrors(rig_errors.calibration, seed));
  c.imu_time_offset_s = 0.0;  // the IMU's clock error is the twin's, unknown to the rig's owner (a fault to find)
  return c;
}

SimConfig DefaultSimConfig() { return SimConfig{}; }

SimConfig PresetSimConfig(Realism r) {
  SimConfig c = DefaultSimConfig();
  ApplyRealism(r, &c);
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
  if (!rig_model.Validate(&why)) return fail("rig_model: " + why);
  // Handheld/wheeled without waypoints take the scene's default path: validated once the scene is loaded.
  if (!carrier_from_scene && !UsesSceneDefaultPath(carrier) && !carrier.Validate(&why))
    return fail("carrier: " + why);
  if (!motor.Validate(&why)) return fail("motor: " + why);
  if (!imu.Validate(&why)) return fail("imu: " + why);
  if (!lidar.Validate(&why)) return fail("lidar: " + why);
  if (!clocks.Validate(&why)) return fail(why);
  if (!camera.Validate(&why)) return fail(why);
  if (!rig_errors.Validate(&why)) return fail(why);
  if (!faults.Validate(&why)) return fail(why);
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
  if (fs::is_regular_file(scene)) return scene;  // a folder named like a scene (a recording) is not one
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
    // The preset first, so that the file's other keys override single sources (a bad word is reported below).
    if (Realism r; root.IsMap() && root["realism"] && root["realism"].IsScalar() &&
                   yaml::EnumFromWord(root["realism"].Scalar(), &r))
      ApplyRealism(r, &c);
    yaml::Parse(yaml::Section(path, "", "sim"), root, &c);
    c.lidar.return_mode = c.return_mode;  // the caster's echoes follow the encoder's mode
  } catch (const yaml::ParseError& e) {
    return Status::Error(e.what());
  } catch (const YAML::Exception& e) {  // what a field reader did not foresee: still a message, never a crash
    return Status::Error(path + ": " + e.what());
  }
  std::string why;
  if (!c.Validate(&why)) return Status::Error(path + ": invalid sim config: " + why);
  *config = c;
  return Status::Ok();
}

void EmitSimConfig(YAML::Emitter& out, const SimConfig& c) { yaml::Emit(out, c); }

}  // namespace rotolidar::sim
