// YAML for RigModelConfig (rig_model/rig.yaml) with the project's one idiom (core/io/yaml_fields.hpp): the field
// lists below drive parse and emit. Layout (every key optional; docs/rig_model.md):
//   carrier: handheld | wheeled | car
//   platform: {mass_kg, size_m: [x, y, z], center_m: [x, y, z]}
//   motor: {axis: horizontal | vertical | tilted, tilt_deg, position_m: [x, y, z], mass_kg, body_width_m,
//           body_length_m, rotor_inertia_kgm2}
//   rotor: {lidar_offset_m, slip_ring_mass_kg, slip_ring_diameter_m, slip_ring_length_m, bracket_mass_kg,
//           imbalance_kgm, imbalance_radius_m, imbalance_angle_rad, hinge_damping_nms, hinge_frictionloss_nm,
//           hinge_extra_armature_kgm2}
//   lidar: {mass_kg, diameter_m, height_m}
//   T_base_imu / T_base_cam: {translation_m: [x, y, z], rotation_wxyz: [w, x, y, z]}
//   physics: {timestep_s, tracking_natural_hz, tracking_damping_ratio, tracking_impedance, solver_iterations}
//   mjcf_template: path (relative to the YAML file's folder)
#include <filesystem>

#include "core/io/yaml_fields.hpp"
#include "sim/rig/rig_model.hpp"

namespace rotolidar::sim {

// ---- the field lists (in the structs' namespace, so the generic visitors find them) ----

template <class V>
void Visit(V& v, PlatformConfig& c) {
  v("mass_kg", &c.mass_kg), v("size_m", &c.size_m), v("center_m", &c.center_m);
}

template <class V>
void Visit(V& v, MotorMountConfig& c) {
  v("axis", &c.axis), v("tilt_deg", &c.tilt_deg), v("position_m", &c.position_m), v("mass_kg", &c.mass_kg);
  v("body_width_m", &c.body_width_m), v("body_length_m", &c.body_length_m);
  v("rotor_inertia_kgm2", &c.rotor_inertia_kgm2);
}

template <class V>
void Visit(V& v, RotorConfig& c) {
  v("lidar_offset_m", &c.lidar_offset_m), v("slip_ring_mass_kg", &c.slip_ring_mass_kg);
  v("slip_ring_diameter_m", &c.slip_ring_diameter_m), v("slip_ring_length_m", &c.slip_ring_length_m);
  v("bracket_mass_kg", &c.bracket_mass_kg), v("imbalance_kgm", &c.imbalance_kgm);
  v("imbalance_radius_m", &c.imbalance_radius_m), v("imbalance_angle_rad", &c.imbalance_angle_rad);
  v("hinge_damping_nms", &c.hinge_damping_nms), v("hinge_frictionloss_nm", &c.hinge_frictionloss_nm);
  v("hinge_extra_armature_kgm2", &c.hinge_extra_armature_kgm2);
}

template <class V>
void Visit(V& v, LidarBodyConfig& c) {
  v("mass_kg", &c.mass_kg), v("diameter_m", &c.diameter_m), v("height_m", &c.height_m);
}

template <class V>
void Visit(V& v, RigPhysicsConfig& c) {
  v("timestep_s", &c.timestep_s), v("tracking_natural_hz", &c.tracking_natural_hz);
  v("tracking_damping_ratio", &c.tracking_damping_ratio), v("tracking_impedance", &c.tracking_impedance);
  v("solver_iterations", &c.solver_iterations);
}

/// The template path is written only when set (its default is resolved at build time).
template <class V>
void Visit(V& v, RigModelConfig& c) {
  v("carrier", &c.carrier), v("platform", &c.platform), v("motor", &c.motor), v("rotor", &c.rotor);
  v("lidar", &c.lidar), v("T_base_imu", &c.T_base_imu), v("T_base_cam", &c.T_base_cam);
  v("physics", &c.physics);
  v("mjcf_template", yaml::EmitIf(!c.mjcf_template_path.empty(), &c.mjcf_template_path));
}

namespace {

/// Throws yaml::ParseError. `carrier:` first resets the platform to that carrier's default, which `platform:`
/// then overrides; a relative mjcf_template resolves against the file's folder.
void ParseRigModel(const std::string& file, const YAML::Node& node, RigModelConfig* c) {
  const yaml::Section at(file, "", "rig model");
  yaml::CheckKeys(file, node, yaml::Keys(*c), at.Name());
  if (const YAML::Node carrier = node["carrier"]) {
    yaml::ReadValue(at.Child("carrier"), carrier, &c->carrier);
    c->platform = DefaultPlatform(c->carrier);
  }
  yaml::ReadFields(at, node, c);
  if (node["mjcf_template"]) {
    const std::filesystem::path p(c->mjcf_template_path);
    if (p.is_relative()) c->mjcf_template_path = (std::filesystem::path(file).parent_path() / p).string();
  }
}

}  // namespace

Status ParseRigModelConfig(const std::string& file, const YAML::Node& node, RigModelConfig* config) {
  if (!node || node.IsNull()) return Status::Ok();
  RigModelConfig c = *config;
  try {
    ParseRigModel(file, node, &c);
  } catch (const yaml::ParseError& e) {
    return Status::Error(e.what());
  }
  *config = c;
  return Status::Ok();
}

Status LoadRigModelConfig(const std::string& path, RigModelConfig* config) {
  RigModelConfig c = *config;
  try {
    if (Status s = ParseRigModelConfig(path, yaml::LoadFile(path), &c); !s) return s;
  } catch (const yaml::ParseError& e) {
    return Status::Error(e.what());
  }
  std::string why;
  if (!c.Validate(&why)) return Status::Error(path + ": rig model: " + why);
  *config = c;
  return Status::Ok();
}

void EmitRigModelConfig(YAML::Emitter& out, const RigModelConfig& c) { yaml::Emit(out, c); }

}  // namespace rotolidar::sim
