// YAML for RigModelConfig (rig_model/rig.yaml). Layout (every key optional; docs/rig_model.md):
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
#include <vector>

#include <yaml-cpp/yaml.h>

#include "core/io/yaml_util.hpp"
#include "sim/rig/rig_model.hpp"

namespace rotolidar::sim {
namespace {

using yaml::Get;
using yaml::ParseError;
using yaml::Where;

void GetVec3(const std::string& file, const YAML::Node& node, const std::string& key, Eigen::Vector3d* v) {
  if (!node[key]) return;
  std::vector<double> values;
  Get(file, node, key, &values);
  if (values.size() != 3) throw ParseError(Where(file, node[key]) + "field '" + key + "': expected 3 numbers");
  *v = Eigen::Vector3d(values[0], values[1], values[2]);
}

void ParseCarrier(const std::string& file, const YAML::Node& root, RigModelConfig* c) {
  if (const YAML::Node n = root["carrier"]) {
    std::string name;
    Get(file, root, "carrier", &name);
    if (name == "handheld") c->carrier = PlatformType::kHandheld;
    else if (name == "wheeled") c->carrier = PlatformType::kWheeled;
    else if (name == "car") c->carrier = PlatformType::kCar;
    else throw ParseError(Where(file, n) + "carrier: expected handheld, wheeled or car, got '" + name + "'");
    c->platform = DefaultPlatform(c->carrier);
  }
  if (const YAML::Node n = root["platform"]) {
    yaml::CheckKeys(file, n, {"mass_kg", "size_m", "center_m"}, "platform");
    Get(file, n, "mass_kg", &c->platform.mass_kg);
    GetVec3(file, n, "size_m", &c->platform.size_m);
    GetVec3(file, n, "center_m", &c->platform.center_m);
  }
}

void ParseMotor(const std::string& file, const YAML::Node& n, MotorMountConfig* m) {
  if (!n) return;
  yaml::CheckKeys(file, n,
                  {"axis", "tilt_deg", "position_m", "mass_kg", "body_width_m", "body_length_m",
                   "rotor_inertia_kgm2"},
                  "motor");
  if (n["axis"]) {
    std::string axis;
    Get(file, n, "axis", &axis);
    if (axis == "horizontal") m->axis = MotorAxis::kHorizontal;
    else if (axis == "vertical") m->axis = MotorAxis::kVertical;
    else if (axis == "tilted") m->axis = MotorAxis::kTilted;
    else throw ParseError(Where(file, n["axis"]) + "motor.axis: expected horizontal, vertical or tilted");
  }
  Get(file, n, "tilt_deg", &m->tilt_deg);
  GetVec3(file, n, "position_m", &m->position_m);
  Get(file, n, "mass_kg", &m->mass_kg);
  Get(file, n, "body_width_m", &m->body_width_m);
  Get(file, n, "body_length_m", &m->body_length_m);
  Get(file, n, "rotor_inertia_kgm2", &m->rotor_inertia_kgm2);
}

void ParseRotor(const std::string& file, const YAML::Node& n, RotorConfig* r) {
  if (!n) return;
  yaml::CheckKeys(file, n,
                  {"lidar_offset_m", "slip_ring_mass_kg", "slip_ring_diameter_m", "slip_ring_length_m",
                   "bracket_mass_kg", "imbalance_kgm", "imbalance_radius_m", "imbalance_angle_rad",
                   "hinge_damping_nms", "hinge_frictionloss_nm", "hinge_extra_armature_kgm2"},
                  "rotor");
  Get(file, n, "lidar_offset_m", &r->lidar_offset_m);
  Get(file, n, "slip_ring_mass_kg", &r->slip_ring_mass_kg);
  Get(file, n, "slip_ring_diameter_m", &r->slip_ring_diameter_m);
  Get(file, n, "slip_ring_length_m", &r->slip_ring_length_m);
  Get(file, n, "bracket_mass_kg", &r->bracket_mass_kg);
  Get(file, n, "imbalance_kgm", &r->imbalance_kgm);
  Get(file, n, "imbalance_radius_m", &r->imbalance_radius_m);
  Get(file, n, "imbalance_angle_rad", &r->imbalance_angle_rad);
  Get(file, n, "hinge_damping_nms", &r->hinge_damping_nms);
  Get(file, n, "hinge_frictionloss_nm", &r->hinge_frictionloss_nm);
  Get(file, n, "hinge_extra_armature_kgm2", &r->hinge_extra_armature_kgm2);
}

void ParsePhysics(const std::string& file, const YAML::Node& n, RigPhysicsConfig* p) {
  if (!n) return;
  yaml::CheckKeys(file, n,
                  {"timestep_s", "tracking_natural_hz", "tracking_damping_ratio", "tracking_impedance",
                   "solver_iterations"},
                  "physics");
  Get(file, n, "timestep_s", &p->timestep_s);
  Get(file, n, "tracking_natural_hz", &p->tracking_natural_hz);
  Get(file, n, "tracking_damping_ratio", &p->tracking_damping_ratio);
  Get(file, n, "tracking_impedance", &p->tracking_impedance);
  Get(file, n, "solver_iterations", &p->solver_iterations);
}

void EmitVec3(YAML::Emitter& out, const char* key, const Eigen::Vector3d& v) {
  out << YAML::Key << key << YAML::Value << YAML::Flow << std::vector<double>{v.x(), v.y(), v.z()};
}

template <typename T>
void EmitKV(YAML::Emitter& out, const char* key, const T& value) {
  out << YAML::Key << key << YAML::Value << value;
}

}  // namespace

void ParseRigModelConfig(const std::string& file, const YAML::Node& node, RigModelConfig* config) {
  if (!node || node.IsNull()) return;
  yaml::CheckKeys(file, node,
                  {"carrier", "platform", "motor", "rotor", "lidar", "T_base_imu", "T_base_cam", "physics",
                   "mjcf_template"},
                  "rig model");
  RigModelConfig c = *config;
  ParseCarrier(file, node, &c);
  ParseMotor(file, node["motor"], &c.motor);
  ParseRotor(file, node["rotor"], &c.rotor);
  if (const YAML::Node n = node["lidar"]) {
    yaml::CheckKeys(file, n, {"mass_kg", "diameter_m", "height_m"}, "lidar");
    Get(file, n, "mass_kg", &c.lidar.mass_kg);
    Get(file, n, "diameter_m", &c.lidar.diameter_m);
    Get(file, n, "height_m", &c.lidar.height_m);
  }
  yaml::GetPose(file, node, "T_base_imu", &c.T_base_imu);
  yaml::GetPose(file, node, "T_base_cam", &c.T_base_cam);
  ParsePhysics(file, node["physics"], &c.physics);
  if (node["mjcf_template"]) {
    Get(file, node, "mjcf_template", &c.mjcf_template_path);
    const std::filesystem::path p(c.mjcf_template_path);
    if (p.is_relative()) c.mjcf_template_path = (std::filesystem::path(file).parent_path() / p).string();
  }
  *config = c;
}

Status LoadRigModelConfig(const std::string& path, RigModelConfig* config) {
  RigModelConfig c = *config;
  try {
    ParseRigModelConfig(path, yaml::LoadFile(path), &c);
  } catch (const yaml::ParseError& e) {
    return Status::Error(e.what());
  }
  std::string why;
  if (!c.Validate(&why)) return Status::Error(path + ": rig model: " + why);
  *config = c;
  return Status::Ok();
}

void EmitRigModelConfig(YAML::Emitter& out, const RigModelConfig& c) {
  out << YAML::BeginMap;
  EmitKV(out, "carrier", PlatformTypeName(c.carrier));
  out << YAML::Key << "platform" << YAML::Value << YAML::BeginMap;
  EmitKV(out, "mass_kg", c.platform.mass_kg);
  EmitVec3(out, "size_m", c.platform.size_m);
  EmitVec3(out, "center_m", c.platform.center_m);
  out << YAML::EndMap << YAML::Key << "motor" << YAML::Value << YAML::BeginMap;
  EmitKV(out, "axis", MotorAxisName(c.motor.axis));
  EmitKV(out, "tilt_deg", c.motor.tilt_deg);
  EmitVec3(out, "position_m", c.motor.position_m);
  EmitKV(out, "mass_kg", c.motor.mass_kg);
  EmitKV(out, "body_width_m", c.motor.body_width_m);
  EmitKV(out, "body_length_m", c.motor.body_length_m);
  EmitKV(out, "rotor_inertia_kgm2", c.motor.rotor_inertia_kgm2);
  out << YAML::EndMap << YAML::Key << "rotor" << YAML::Value << YAML::BeginMap;
  const RotorConfig& r = c.rotor;
  EmitKV(out, "lidar_offset_m", r.lidar_offset_m);
  EmitKV(out, "slip_ring_mass_kg", r.slip_ring_mass_kg);
  EmitKV(out, "slip_ring_diameter_m", r.slip_ring_diameter_m);
  EmitKV(out, "slip_ring_length_m", r.slip_ring_length_m);
  EmitKV(out, "bracket_mass_kg", r.bracket_mass_kg);
  EmitKV(out, "imbalance_kgm", r.imbalance_kgm);
  EmitKV(out, "imbalance_radius_m", r.imbalance_radius_m);
  EmitKV(out, "imbalance_angle_rad", r.imbalance_angle_rad);
  EmitKV(out, "hinge_damping_nms", r.hinge_damping_nms);
  EmitKV(out, "hinge_frictionloss_nm", r.hinge_frictionloss_nm);
  EmitKV(out, "hinge_extra_armature_kgm2", r.hinge_extra_armature_kgm2);
  out << YAML::EndMap << YAML::Key << "lidar" << YAML::Value << YAML::BeginMap;
  EmitKV(out, "mass_kg", c.lidar.mass_kg);
  EmitKV(out, "diameter_m", c.lidar.diameter_m);
  EmitKV(out, "height_m", c.lidar.height_m);
  out << YAML::EndMap;
  yaml::EmitPose(out, "T_base_imu", c.T_base_imu);
  yaml::EmitPose(out, "T_base_cam", c.T_base_cam);
  out << YAML::Key << "physics" << YAML::Value << YAML::BeginMap;
  EmitKV(out, "timestep_s", c.physics.timestep_s);
  EmitKV(out, "tracking_natural_hz", c.physics.tracking_natural_hz);
  EmitKV(out, "tracking_damping_ratio", c.physics.tracking_damping_ratio);
  EmitKV(out, "tracking_impedance", c.physics.tracking_impedance);
  EmitKV(out, "solver_iterations", c.physics.solver_iterations);
  out << YAML::EndMap;
  if (!c.mjcf_template_path.empty()) EmitKV(out, "mjcf_template", c.mjcf_template_path);
  out << YAML::EndMap;
}

}  // namespace rotolidar::sim
