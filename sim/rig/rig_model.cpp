#include "sim/rig/rig_model.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>

#include "sim/rig/mujoco_util.hpp"

#ifndef ROTOLIDAR_SOURCE_DIR
#define ROTOLIDAR_SOURCE_DIR "."
#endif

namespace rotolidar::sim {
namespace {

// The same construction as DefaultRigCalib() (sim/sim_config.cpp), so the default geometry matches it bit for bit.
Pose3 PoseFromRpy(const Eigen::Vector3d& t_m, double roll_rad, double pitch_rad, double yaw_rad) {
  Pose3 T = Pose3::Identity();
  T.linear() = (Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(pitch_rad, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(roll_rad, Eigen::Vector3d::UnitX()))
                  .toRotationMatrix();
  T.translation() = t_m;
  return T;
}

bool Finite(const Eigen::Vector3d& v) { return v.allFinite(); }
bool Positive(double x) { return std::isfinite(x) && x > 0.0; }
bool NonNegative(double x) { return std::isfinite(x) && x >= 0.0; }
bool Positive(const Eigen::Vector3d& v) { return v.allFinite() && (v.array() > 0.0).all(); }
bool IsRigid(const Pose3& T) {
  return T.matrix().allFinite() &&
         (T.linear().transpose() * T.linear() - Eigen::Matrix3d::Identity()).norm() < 1e-9 &&
         T.linear().determinant() > 0.0;
}

std::string Num(double x) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%.17g", x);
  return buf;
}
std::string Vec(const Eigen::Vector3d& v) { return Num(v.x()) + " " + Num(v.y()) + " " + Num(v.z()); }
std::string Quat(const Eigen::Matrix3d& R) {
  const Eigen::Quaterniond q(R);
  return Num(q.w()) + " " + Num(q.x()) + " " + Num(q.y()) + " " + Num(q.z());
}

}  // namespace

const std::vector<std::pair<const char*, PlatformType>>& EnumWords(PlatformType*) {
  static const std::vector<std::pair<const char*, PlatformType>> words{
      {"handheld", PlatformType::kHandheld}, {"wheeled", PlatformType::kWheeled}, {"car", PlatformType::kCar}};
  return words;
}

const std::vector<std::pair<const char*, MotorAxis>>& EnumWords(MotorAxis*) {
  static const std::vector<std::pair<const char*, MotorAxis>> words{
      {"horizontal", MotorAxis::kHorizontal}, {"vertical", MotorAxis::kVertical}, {"tilted", MotorAxis::kTilted}};
  return words;
}

const char* PlatformTypeName(PlatformType type) {
  for (const auto& [word, t] : EnumWords(&type))
    if (t == type) return word;
  return "unknown";
}

const char* MotorAxisName(MotorAxis axis) {
  for (const auto& [word, a] : EnumWords(&axis))
    if (a == axis) return word;
  return "unknown";
}

PlatformConfig DefaultPlatform(PlatformType type) {
  PlatformConfig p;  // handheld: frame, battery, computer, IMU and camera board around the hand grip
  if (type == PlatformType::kWheeled) {  // Clearpath Jackal-class UGV: 17 kg, 508 x 430 x 250 mm; rig on its top
    p.mass_kg = 17.0;
    p.size_m = Eigen::Vector3d(0.508, 0.430, 0.250);
    p.center_m = Eigen::Vector3d(-0.15, 0.0, -0.185);
  } else if (type == PlatformType::kCar) {  // compact car: 1500 kg, 4.5 x 1.8 x 1.4 m; rig above the windscreen
    p.mass_kg = 1500.0;
    p.size_m = Eigen::Vector3d(4.5, 1.8, 1.4);
    p.center_m = Eigen::Vector3d(-1.0, 0.0, -0.76);
  }
  return p;
}

Pose3 RigModelConfig::DefaultTBaseImu() { return PoseFromRpy({-0.05, 0.03, -0.04}, 0.01, -0.02, 0.03); }

Pose3 RigModelConfig::DefaultTBaseCam() {
  Pose3 T = Pose3::Identity();  // cam z = base x, cam x = -base y, cam y = -base z
  T.linear() << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  T.translation() = Eigen::Vector3d(0.05, 0.0, 0.10);
  return T;
}

bool RigModelConfig::Validate(std::string* error) const {
  std::string why;
  auto check = [&](bool ok, const char* message) {
    if (!ok && why.empty()) why = message;
  };
  check(Positive(platform.mass_kg), "platform.mass_kg must be > 0");
  check(Positive(platform.size_m), "platform.size_m must be 3 values > 0");
  check(Finite(platform.center_m), "platform.center_m must be finite");
  if (motor.axis == MotorAxis::kTilted)
    check(std::isfinite(motor.tilt_deg) && std::abs(motor.tilt_deg) <= 90.0, "motor.tilt_deg must be in [-90, 90]");
  check(Finite(motor.position_m) && motor.position_m.norm() < 10.0, "motor.position_m must be finite, < 10 m");
  check(Positive(motor.mass_kg), "motor.mass_kg must be > 0");
  check(Positive(motor.body_width_m) && Positive(motor.body_length_m), "motor.body_width_m/body_length_m must be > 0");
  check(NonNegative(motor.rotor_inertia_kgm2), "motor.rotor_inertia_kgm2 must be >= 0");
  check(Positive(rotor.lidar_offset_m) && rotor.lidar_offset_m <= 1.0, "rotor.lidar_offset_m must be in (0, 1]");
  check(Positive(rotor.slip_ring_mass_kg), "rotor.slip_ring_mass_kg must be > 0");
  check(Positive(rotor.slip_ring_diameter_m) && Positive(rotor.slip_ring_length_m),
        "rotor.slip_ring_diameter_m/slip_ring_length_m must be > 0");
  check(Positive(rotor.bracket_mass_kg), "rotor.bracket_mass_kg must be > 0");
  check(NonNegative(rotor.imbalance_kgm), "rotor.imbalance_kgm must be >= 0");
  check(Positive(rotor.imbalance_radius_m) && rotor.imbalance_radius_m <= 0.5,
        "rotor.imbalance_radius_m must be in (0, 0.5]");
  check(!Positive(rotor.imbalance_radius_m) || rotor.imbalance_kgm / rotor.imbalance_radius_m <= 1.0,
        "rotor.imbalance_kgm / imbalance_radius_m (the point mass) must be <= 1 kg");
  check(std::isfinite(rotor.imbalance_angle_rad), "rotor.imbalance_angle_rad must be finite");
  check(NonNegative(rotor.hinge_damping_nms), "rotor.hinge_damping_nms must be >= 0");
  check(NonNegative(rotor.hinge_frictionloss_nm), "rotor.hinge_frictionloss_nm must be >= 0");
  check(NonNegative(rotor.hinge_extra_armature_kgm2), "rotor.hinge_extra_armature_kgm2 must be >= 0");
  check(Positive(lidar.mass_kg), "lidar.mass_kg must be > 0");
  check(Positive(lidar.diameter_m) && Positive(lidar.height_m), "lidar.diameter_m/height_m must be > 0");
  check(IsRigid(T_base_imu), "T_base_imu must be a finite rigid transform");
  check(IsRigid(T_base_cam), "T_base_cam must be a finite rigid transform");
  check(std::isfinite(physics.timestep_s) && physics.timestep_s >= 1e-5 && physics.timestep_s <= 0.01,
        "physics.timestep_s must be in [1e-5, 0.01]");
  check(Positive(physics.tracking_natural_hz), "physics.tracking_natural_hz must be > 0");
  check(Positive(physics.tracking_damping_ratio) && physics.tracking_damping_ratio <= 10.0,
        "physics.tracking_damping_ratio must be in (0, 10]");
  // MuJoCo silently stiffens a weld whose time constant is below 2 timesteps: refuse instead.
  const double timeconst = 1.0 / (2.0 * M_PI * physics.tracking_natural_hz * physics.tracking_damping_ratio);
  check(!(timeconst < 2.0 * physics.timestep_s),
        "physics.tracking_natural_hz * tracking_damping_ratio too high: 1/(2 pi f zeta) must be >= 2 timesteps");
  check(physics.tracking_impedance >= 1e-4 && physics.tracking_impedance <= 0.9999,
        "physics.tracking_impedance must be in [1e-4, 0.9999]");
  check(physics.solver_iterations >= 1 && physics.solver_iterations <= 1000,
        "physics.solver_iterations must be in [1, 1000]");
  if (why.empty()) return true;
  if (error) *error = why;
  return false;
}

std::string ResolveRigTemplatePath(const std::string& path) {
  if (!path.empty()) return path;
  if (const char* dir = std::getenv("ROTOLIDAR_RIG_MODEL_DIR")) return std::string(dir) + "/rig.xml";
  return std::string(ROTOLIDAR_SOURCE_DIR) + "/rig_model/rig.xml";
}

Eigen::Matrix3d MotorAxisRotation(const MotorMountConfig& motor) {
  double pitch_rad = M_PI / 2;  // horizontal: RotY(pi/2) turns motor z onto base +x
  if (motor.axis == MotorAxis::kVertical) pitch_rad = 0.0;
  if (motor.axis == MotorAxis::kTilted) pitch_rad = M_PI / 2 - motor.tilt_deg * M_PI / 180.0;
  return PoseFromRpy(Eigen::Vector3d::Zero(), 0.0, pitch_rad, 0.0).linear();
}

void FillRigGeometry(const RigModelConfig& config, RigCalib* calib) {
  Pose3 T_base_motor = Pose3::Identity();
  T_base_motor.linear() = MotorAxisRotation(config.motor);
  T_base_motor.translation() = config.motor.position_m;
  calib->T_base_motor = T_base_motor;
  // The VLP-16's spin axis (lidar z) along rotor +x: across the motor axis, lidar_offset_m out along it.
  calib->T_rotor_lidar = PoseFromRpy({0.0, 0.0, config.rotor.lidar_offset_m}, 0.0, M_PI / 2, 0.0);
  calib->T_base_imu = config.T_base_imu;
  calib->T_base_cam = config.T_base_cam;
}

namespace {

std::string Geom(const std::string& name, const std::string& type, const std::string& size,
                 const Eigen::Vector3d& pos, double mass_kg, const std::string& extra = "") {
  return "<geom name=\"" + name + "\" type=\"" + type + "\" size=\"" + size + "\" pos=\"" + Vec(pos) +
         "\" mass=\"" + Num(mass_kg) + "\"" + extra + "/>\n      ";
}

// The platform's geoms: a main box plus a grip (handheld) or four wheels about base y (wheeled, car). The
// shares of the platform mass are stated in docs/rig_model.md.
std::string PlatformGeoms(PlatformType type, const PlatformConfig& p) {
  const Eigen::Vector3d c = p.center_m, s = p.size_m;
  if (type == PlatformType::kHandheld) {
    const double grip_half_m = 0.06;  // a 12 cm grip under the frame
    return Geom("platform", "box", Vec(s / 2), c, 0.85 * p.mass_kg) +
           Geom("grip", "cylinder", "0.016 " + Num(grip_half_m), c - Eigen::Vector3d(0, 0, s.z() / 2 + grip_half_m),
                0.15 * p.mass_kg);
  }
  const bool car = type == PlatformType::kCar;
  const double wheel_share = car ? 0.015 : 0.05;          // of the platform mass, per wheel
  const double wheel_radius_m = (car ? 0.22 : 0.40) * s.z();
  const double wheel_half_width_m = (car ? 0.06 : 0.09) * s.y();
  std::string xml = Geom("platform", "box", Vec(s / 2), c, (1.0 - 4 * wheel_share) * p.mass_kg);
  const std::string about_y = " quat=\"0.70710678118654757 0.70710678118654746 0 0\"";
  int i = 0;
  for (double sx : {1.0, -1.0})
    for (double sy : {1.0, -1.0}) {
      const Eigen::Vector3d pos = c + Eigen::Vector3d(sx * 0.35 * s.x(), sy * (s.y() / 2 + wheel_half_width_m),
                                                      -s.z() / 2);
      xml += Geom("wheel" + std::to_string(i++), "cylinder", Num(wheel_radius_m) + " " + Num(wheel_half_width_m),
                  pos, wheel_share * p.mass_kg, about_y);
    }
  return xml;
}

std::map<std::string, std::string> Placeholders(const RigModelConfig& c, double weld_torquescale_m) {
  RigCalib g;
  FillRigGeometry(c, &g);
  const RotorConfig& r = c.rotor;
  const double cheek_half_height_m = (r.lidar_offset_m + 0.02) / 2;  // flange up to just past the VLP-16 centre
  std::map<std::string, std::string> v;
  v["timestep_s"] = Num(c.physics.timestep_s);
  v["solver_iterations"] = std::to_string(c.physics.solver_iterations);
  v["platform_geoms"] = PlatformGeoms(c.carrier, c.platform);
  v["imu_pos"] = Vec(g.T_base_imu.translation());
  v["imu_quat"] = Quat(g.T_base_imu.linear());
  v["cam_pos"] = Vec(g.T_base_cam.translation());
  v["cam_quat"] = Quat(g.T_base_cam.linear());
  v["motor_pos"] = Vec(g.T_base_motor.translation());
  v["motor_quat"] = Quat(g.T_base_motor.linear());
  v["motor_half_size"] = Vec({c.motor.body_width_m / 2, c.motor.body_width_m / 2, c.motor.body_length_m / 2});
  v["motor_body_z"] = Num(-c.motor.body_length_m / 2);
  v["motor_mass_kg"] = Num(c.motor.mass_kg);
  // The slip ring sits on the motor's rear shaft, behind the body; one half is stator, one half turns.
  v["slip_ring_radius"] = Num(r.slip_ring_diameter_m / 2);
  v["slip_ring_rotor_radius"] = Num(0.3 * r.slip_ring_diameter_m);
  v["slip_ring_half_length"] = Num(r.slip_ring_length_m / 2);
  v["slip_ring_z"] = Num(-(c.motor.body_length_m + r.slip_ring_length_m / 2));
  v["slip_ring_half_mass_kg"] = Num(r.slip_ring_mass_kg / 2);
  v["hinge_damping"] = Num(r.hinge_damping_nms);
  v["hinge_armature"] = Num(c.motor.rotor_inertia_kgm2 + r.hinge_extra_armature_kgm2);
  v["hinge_frictionloss"] = Num(r.hinge_frictionloss_nm);
  v["flange_radius"] = Num(0.8 * c.lidar.diameter_m / 2);
  v["bracket_part_mass_kg"] = Num(r.bracket_mass_kg / 3);
  v["cheek_half_width"] = Num(0.03);
  v["cheek_half_height"] = Num(cheek_half_height_m);
  v["cheek_x"] = Num(c.lidar.height_m / 2 + 0.0015);  // against the VLP-16's end faces (rotor +-x)
  v["cheek_z"] = Num(cheek_half_height_m);
  v["imbalance_geom"] = "";
  if (r.imbalance_kgm > 0.0) {
    const Eigen::Vector3d pos(r.imbalance_radius_m * std::cos(r.imbalance_angle_rad),
                              r.imbalance_radius_m * std::sin(r.imbalance_angle_rad), r.lidar_offset_m);
    v["imbalance_geom"] = Geom("imbalance", "sphere", "0.004", pos, r.imbalance_kgm / r.imbalance_radius_m,
                               " rgba=\"1 0 0 1\"");
  }
  v["lidar_pos"] = Vec(g.T_rotor_lidar.translation());
  v["lidar_quat"] = Quat(g.T_rotor_lidar.linear());
  v["lidar_radius"] = Num(c.lidar.diameter_m / 2);
  v["lidar_half_height"] = Num(c.lidar.height_m / 2);
  v["lidar_mass_kg"] = Num(c.lidar.mass_kg);
  v["weld_timeconst"] =
      Num(1.0 / (2.0 * M_PI * c.physics.tracking_natural_hz * c.physics.tracking_damping_ratio));
  v["weld_dampratio"] = Num(c.physics.tracking_damping_ratio);
  v["weld_impedance"] = Num(c.physics.tracking_impedance);
  v["weld_torquescale"] = Num(weld_torquescale_m);
  return v;
}

}  // namespace

std::string BuildRigMjcf(const RigModelConfig& config, std::string* error, double weld_torquescale_m) {
  std::string why;
  if (!config.Validate(&why)) {
    *error = "rig model config: " + why;
    return "";
  }
  const std::string path = ResolveRigTemplatePath(config.mjcf_template_path);
  std::ifstream in(path);
  if (!in) {
    *error = path + ": cannot open the rig MJCF template";
    return "";
  }
  std::stringstream buffer;
  buffer << in.rdbuf();
  const std::string text = buffer.str();
  if (!(weld_torquescale_m > 0.0 && std::isfinite(weld_torquescale_m))) {
    *error = "rig model: weld torquescale must be > 0";
    return "";
  }
  const std::map<std::string, std::string> values = Placeholders(config, weld_torquescale_m);
  std::string out;
  size_t pos = 0;
  for (size_t open; (open = text.find("{{", pos)) != std::string::npos;) {
    const size_t close = text.find("}}", open);
    const std::string key = close == std::string::npos ? "" : text.substr(open + 2, close - open - 2);
    const auto it = values.find(key);
    if (it == values.end()) {
      const int line = 1 + static_cast<int>(std::count(text.begin(), text.begin() + open, '\n'));
      *error = path + ":" + std::to_string(line) + ": unknown placeholder '{{" + key + "}}'";
      return "";
    }
    out += text.substr(pos, open - pos) + it->second;
    pos = close + 2;
  }
  return out + text.substr(pos);
}

RigModel::~RigModel() {
  if (model_) mj_deleteModel(model_);
}

double RigModel::timestep_s() const { return model_->opt.timestep; }

// Two passes: MuJoCo 2.2.2 regularises all six weld rows with the base's translational weight (1/kg), so the
// rotational rows (1/(kg m^2)) would be far stiffer than asked and, with a soft weld, unstable. The first
// compile gives the base's mean translational and rotational inverse weights; the weld's torquescale
// 2 sqrt(w_trn / w_rot) [m] (2: MuJoCo's rotational rows act on half-angles) then equalises them.
Status RigModel::Create(const RigModelConfig& config, std::unique_ptr<RigModel>* model) {
  std::unique_ptr<RigModel> m(new RigModel());
  m->config_ = config;
  std::string error;
  double torquescale_m = 1.0;
  for (int pass = 0; pass < 2; ++pass) {
    if (m->model_) mj_deleteModel(m->model_);
    m->model_ = nullptr;
    m->mjcf_ = BuildRigMjcf(config, &error, torquescale_m);
    if (m->mjcf_.empty()) return Status::Error(error);
    Status status = LoadMjcfFromString(m->mjcf_, "rig.xml", &m->model_);
    if (!status) return status;
    if (!(status = m->LookUpIds())) return status;
    const mjtNum* w = m->model_->body_invweight0 + 2 * m->base_body_;
    torquescale_m = 2.0 * std::sqrt(w[0] / w[1]);
  }
  FillRigGeometry(config, &m->geometry_);
  *model = std::move(m);
  return Status::Ok();
}

double RigModel::weld_torquescale_m() const { return model_->eq_data[mjNEQDATA * weld_ + 10]; }

Status RigModel::LookUpIds() {
  const struct {
    int type;
    const char* name;
    int* id;
  } elements[] = {
      {mjOBJ_BODY, "carrier_target", &target_body_}, {mjOBJ_BODY, "base", &base_body_},
      {mjOBJ_BODY, "motor", &motor_body_},           {mjOBJ_BODY, "rotor", &rotor_body_},
      {mjOBJ_BODY, "lidar", &lidar_body_},           {mjOBJ_JOINT, "base_free", &base_joint_},
      {mjOBJ_JOINT, "rotor_hinge", &hinge_joint_},   {mjOBJ_SITE, "imu", &imu_site_},
      {mjOBJ_SITE, "cam", &cam_site_},               {mjOBJ_SITE, "lidar", &lidar_site_},
      {mjOBJ_SENSOR, "imu_accel", &accel_sensor_},   {mjOBJ_SENSOR, "imu_gyro", &gyro_sensor_},
      {mjOBJ_ACTUATOR, "rotor_motor", &motor_actuator_}, {mjOBJ_EQUALITY, "carrier_track", &weld_},
  };
  for (const auto& e : elements) {
    const Status status = FindMujocoId(model_, e.type, e.name, e.id);
    if (!status) return status;
  }
  target_mocap_ = model_->body_mocapid[target_body_];
  if (target_mocap_ < 0) return Status::Error("rig model: body 'carrier_target' is not a mocap body");
  if (model_->jnt_type[base_joint_] != mjJNT_FREE || model_->jnt_type[hinge_joint_] != mjJNT_HINGE)
    return Status::Error("rig model: 'base_free' must be a free joint and 'rotor_hinge' a hinge");
  return Status::Ok();
}

}  // namespace rotolidar::sim
