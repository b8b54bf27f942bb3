// YAML of the rig imperfections (declared in sim/rig/rig_errors.hpp) with the project's one idiom
// (core/io/yaml_fields.hpp): the sim config's `rig_errors:` section and the truth file truth/rig_errors.yaml.
#include <fstream>

#include "core/io/calib_yaml.hpp"
#include "core/io/yaml_fields.hpp"
#include "sim/rig/rig_errors.hpp"

namespace rotolidar::sim {

template <class V>
void Visit(V& v, CalibErrorConfig& c) {
  v("rotor_lidar_lever_sigma_m", &c.rotor_lidar_lever_sigma_m);
  v("rotor_lidar_tilt_sigma_deg", &c.rotor_lidar_tilt_sigma_deg);
  v("encoder_zero_sigma_rad", &c.encoder_zero_sigma_rad);
  v("base_imu_translation_sigma_m", &c.base_imu_translation_sigma_m);
  v("base_imu_rotation_sigma_deg", &c.base_imu_rotation_sigma_deg);
  v("base_cam_translation_sigma_m", &c.base_cam_translation_sigma_m);
  v("base_cam_rotation_sigma_deg", &c.base_cam_rotation_sigma_deg);
}

template <class V>
void Visit(V& v, AxisWobbleConfig& c) {
  v("cone_half_angle_rad", &c.cone_half_angle_rad), v("cone_phase_rad", &c.cone_phase_rad);
  v("axis_tilt_rad", &c.axis_tilt_rad), v("axis_tilt_azimuth_rad", &c.axis_tilt_azimuth_rad);
}

template <class V>
void Visit(V& v, VibrationHarmonic& c) {
  v("order", &c.order), v("accel_mps2", &c.accel_mps2), v("gyro_radps", &c.gyro_radps);
  v("phase_rad", &c.phase_rad);
}

template <class V>
void Visit(V& v, RotorVibrationConfig& c) {
  v("imbalance_accel_mps2", &c.imbalance_accel_mps2), v("imbalance_gyro_radps", &c.imbalance_gyro_radps);
  v("reference_speed_radps", &c.reference_speed_radps), v("imbalance_phase_rad", &c.imbalance_phase_rad);
  v("harmonics", &c.harmonics);
}

template <class V>
void Visit(V& v, RigErrorConfig& c) {
  v("calibration", &c.calibration), v("wobble", &c.wobble), v("vibration", &c.vibration);
}

template <class V>
void Visit(V& v, CalibErrors& c) {
  v("rotor_lidar_translation_m", &c.rotor_lidar_translation_m);
  v("rotor_lidar_rotation_rad", &c.rotor_lidar_rotation_rad), v("encoder_zero_rad", &c.encoder_zero_rad);
  v("base_imu_translation_m", &c.base_imu_translation_m), v("base_imu_rotation_rad", &c.base_imu_rotation_rad);
  v("base_cam_translation_m", &c.base_cam_translation_m), v("base_cam_rotation_rad", &c.base_cam_rotation_rad);
}

namespace {

/// truth/rig_errors.yaml: what was configured and what was drawn.
struct RigErrorTruth {
  RigErrorConfig config;
  CalibErrors drawn;
};

template <class V>
void Visit(V& v, RigErrorTruth& c) {
  v("config", &c.config), v("calibration_errors", &c.drawn);
}

std::string RigErrorsTruthPath(const std::string& dir) { return dir + "/truth/rig_errors.yaml"; }

}  // namespace

Status ParseRigErrorConfig(const std::string& file, const YAML::Node& node, RigErrorConfig* config) {
  if (!node) return Status::Ok();
  RigErrorConfig c = *config;
  try {
    yaml::Parse(yaml::Section(file, "rig_errors"), node, &c);
  } catch (const yaml::ParseError& e) {
    return Status::Error(e.what());
  }
  std::string why;
  if (!c.Validate(&why)) return Status::Error(yaml::Where(file, node) + why);
  *config = c;
  return Status::Ok();
}

void EmitRigErrorConfig(YAML::Emitter& out, const RigErrorConfig& config) { yaml::Emit(out, config); }

Status WriteRigErrorTruth(const std::string& recording_dir, const RigErrorConfig& config, const CalibErrors& errors,
                          const RigCalib& true_calib) {
  if (Status s = SaveCalibYaml(recording_dir + "/truth/calib_true.yaml", true_calib); !s) return s;
  RigErrorTruth truth{config, errors};
  YAML::Emitter out;
  out.SetDoublePrecision(17);  // reads back to the identical double
  yaml::Emit(out, truth);
  const std::string path = RigErrorsTruthPath(recording_dir);
  std::ofstream file(path);
  file << "# Rig imperfections of this run (sim/rig/rig_errors.hpp). calib.yaml = truth/calib_true.yaml with\n"
       << "# calibration_errors applied (rotations as rotation vectors [rad], parent frame) and imu_time_offset_s 0;\n"
       << "# the wobble and the vibration are in the simulated motion and IMU only.\n"
       << out.c_str() << "\n";
  return file ? Status::Ok() : Status::Error(path + ": write failed");
}

Status ReadRigErrorTruth(const std::string& recording_dir, RigErrorConfig* config, CalibErrors* errors) {
  const std::string path = RigErrorsTruthPath(recording_dir);
  RigErrorTruth t;
  try {
    yaml::Parse(yaml::Section(path, "", "rig_errors"), yaml::LoadFile(path), &t);
  } catch (const yaml::ParseError& e) {
    return Status::Error(e.what());
  }
  *config = t.config;
  *errors = t.drawn;
  return Status::Ok();
}

}  // namespace rotolidar::sim
