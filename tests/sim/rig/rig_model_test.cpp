// RigModelConfig, the MJCF built from rig_model/rig.xml, RigModel and the RigCalib geometry it implies.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>

#include <mujoco/mujoco.h>
#include <yaml-cpp/yaml.h>

#include "sim/rig/mujoco_util.hpp"
#include "sim/rig/rig_model.hpp"
#include "sim/rig/rig_physics.hpp"
#include "sim/sim_config.hpp"

namespace rotolidar::sim {
namespace {

std::string TempPath(const std::string& name) { return ::testing::TempDir() + "/" + name; }

void WriteFile(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

Pose3 PoseOf(const mjtNum* pos, const mjtNum* mat) {
  Pose3 T = Pose3::Identity();
  for (int r = 0; r < 3; ++r) {
    T.translation()[r] = pos[r];
    for (int c = 0; c < 3; ++c) T.linear()(r, c) = mat[3 * r + c];
  }
  return T;
}

// Largest entry of the difference of two poses' 4x4 matrices (metres / unitless rotation entries).
double PoseGap(const Pose3& a, const Pose3& b) { return (a.matrix() - b.matrix()).cwiseAbs().maxCoeff(); }

// Same keys and strings; numbers equal within `tol` (absolute).
void ExpectYamlNear(const YAML::Node& a, const YAML::Node& b, const std::string& where, double tol) {
  ASSERT_EQ(a.Type(), b.Type()) << where;
  if (a.IsMap()) {
    ASSERT_EQ(a.size(), b.size()) << where;
    for (const auto& kv : a) {
      const std::string key = kv.first.as<std::string>();
      ASSERT_TRUE(b[key]) << where << "." << key;
      ExpectYamlNear(kv.second, b[key], where + "." + key, tol);
    }
  } else if (a.IsSequence()) {
    ASSERT_EQ(a.size(), b.size()) << where;
    for (size_t i = 0; i < a.size(); ++i) ExpectYamlNear(a[i], b[i], where + "[" + std::to_string(i) + "]", tol);
  } else if (a.IsScalar()) {
    double x = 0, y = 0;
    if (YAML::convert<double>::decode(a, x) && YAML::convert<double>::decode(b, y)) EXPECT_NEAR(x, y, tol) << where;
    else EXPECT_EQ(a.Scalar(), b.Scalar()) << where;
  }
}

std::vector<RigModelConfig> AllVariants() {
  std::vector<RigModelConfig> configs;
  for (PlatformType carrier : {PlatformType::kHandheld, PlatformType::kWheeled, PlatformType::kCar})
    for (MotorAxis axis : {MotorAxis::kHorizontal, MotorAxis::kVertical, MotorAxis::kTilted}) {
      RigModelConfig c;
      c.carrier = carrier;
      c.platform = DefaultPlatform(carrier);
      c.motor.axis = axis;
      c.motor.tilt_deg = 35.0;
      configs.push_back(c);
    }
  return configs;
}

TEST(RigModelConfig, DefaultReproducesDefaultRigCalibGeometryExactly) {
  const RigModelConfig config;
  std::string why;
  ASSERT_TRUE(config.Validate(&why)) << why;
  RigCalib from_model;
  FillRigGeometry(config, &from_model);
  const RigCalib expected = DefaultRigCalib();
  // Bitwise: the recording pipeline and its tests were built on these exact transforms.
  EXPECT_TRUE(from_model.T_base_motor.matrix() == expected.T_base_motor.matrix());
  EXPECT_TRUE(from_model.T_rotor_lidar.matrix() == expected.T_rotor_lidar.matrix());
  EXPECT_TRUE(from_model.T_base_imu.matrix() == expected.T_base_imu.matrix());
  EXPECT_TRUE(from_model.T_base_cam.matrix() == expected.T_base_cam.matrix());
}

TEST(RigModelConfig, AxisOptionsOnlyTurnTheMotorFrame) {
  RigModelConfig config;
  RigCalib horizontal, other;
  FillRigGeometry(config, &horizontal);
  for (MotorAxis axis : {MotorAxis::kVertical, MotorAxis::kTilted}) {
    config.motor.axis = axis;
    config.motor.tilt_deg = 30.0;
    FillRigGeometry(config, &other);
    EXPECT_TRUE(other.T_rotor_lidar.matrix() == horizontal.T_rotor_lidar.matrix());
    EXPECT_TRUE(other.T_base_imu.matrix() == horizontal.T_base_imu.matrix());
    EXPECT_TRUE(other.T_base_motor.translation() == horizontal.T_base_motor.translation());
    const Eigen::Vector3d motor_z = other.T_base_motor.linear().col(2);
    const Eigen::Vector3d expected = axis == MotorAxis::kVertical
                                         ? Eigen::Vector3d(0, 0, 1)
                                         : Eigen::Vector3d(std::cos(M_PI / 6), 0, std::sin(M_PI / 6));
    EXPECT_LT((motor_z - expected).norm(), 1e-15) << MotorAxisName(axis);
  }
}

TEST(RigModelConfig, ValidateNamesTheField) {
  const std::vector<std::pair<std::function<void(RigModelConfig*)>, std::string>> cases = {
      {[](RigModelConfig* c) { c->rotor.imbalance_kgm = -1e-3; }, "rotor.imbalance_kgm"},
      {[](RigModelConfig* c) { c->lidar.mass_kg = 0.0; }, "lidar.mass_kg"},
      {[](RigModelConfig* c) { c->platform.size_m.y() = -0.1; }, "platform.size_m"},
      {[](RigModelConfig* c) { c->motor.axis = MotorAxis::kTilted; c->motor.tilt_deg = 120; }, "motor.tilt_deg"},
      {[](RigModelConfig* c) { c->physics.timestep_s = 0.05; }, "physics.timestep_s"},
      {[](RigModelConfig* c) { c->physics.tracking_natural_hz = 200.0; }, "physics.tracking_natural_hz"},
      {[](RigModelConfig* c) { c->T_base_imu.linear() *= 2.0; }, "T_base_imu"},
  };
  for (const auto& [mutate, field] : cases) {
    RigModelConfig c;
    mutate(&c);
    std::string why;
    EXPECT_FALSE(c.Validate(&why)) << field;
    EXPECT_NE(why.find(field), std::string::npos) << why;
  }
}

TEST(RigModel, LoadsForEveryCarrierAndAxisAndMatchesTheCalibGeometry) {
  const Pose3 T_world_base = MakePose({1.0, -2.0, 0.7}, Eigen::Quaterniond(0.9, 0.1, -0.2, 0.3));
  const double theta_rad = 0.83;
  for (const RigModelConfig& config : AllVariants()) {
    const std::string name = std::string(PlatformTypeName(config.carrier)) + "/" + MotorAxisName(config.motor.axis);
    std::unique_ptr<RigModel> model;
    const Status status = RigModel::Create(config, &model);
    ASSERT_TRUE(status.ok) << name << ": " << status.message;
    const mjModel* m = model->model();
    EXPECT_EQ(m->nq, 7 + 1) << name;  // free base + hinge
    EXPECT_EQ(m->nu, 1) << name;
    RigState state(*model);
    state.Reset(T_world_base, theta_rad, 0.0);
    const mjData* d = state.data();
    const RigCalib& g = model->geometry();
    auto body = [&](int id) { return PoseOf(d->xpos + 3 * id, d->xmat + 9 * id); };
    auto site = [&](int id) { return PoseOf(d->site_xpos + 3 * id, d->site_xmat + 9 * id); };
    // Quaternions are written with 17 digits and renormalised by MuJoCo: agreement to ~1e-15 (1e-12 allowed).
    EXPECT_LT(PoseGap(body(model->base_body_id()), T_world_base), 1e-12) << name;
    EXPECT_LT(PoseGap(body(model->motor_body_id()), T_world_base * g.T_base_motor), 1e-12) << name;
    EXPECT_LT(PoseGap(body(model->rotor_body_id()), T_world_base * g.T_base_rotor(theta_rad)), 1e-12) << name;
    EXPECT_LT(PoseGap(body(model->lidar_body_id()), T_world_base * g.T_base_lidar(theta_rad)), 1e-12) << name;
    EXPECT_LT(PoseGap(site(model->lidar_site_id()), T_world_base * g.T_base_lidar(theta_rad)), 1e-12) << name;
    EXPECT_LT(PoseGap(site(model->imu_site_id()), T_world_base * g.T_base_imu), 1e-12) << name;
    EXPECT_LT(PoseGap(site(model->cam_site_id()), T_world_base * g.T_base_cam), 1e-12) << name;
    EXPECT_LT(PoseGap(state.T_world_lidar(), T_world_base * g.T_base_lidar(theta_rad)), 1e-12) << name;
  }
}

TEST(RigModel, MassesAndImbalanceAreTheConfiguredOnes) {
  RigModelConfig config;
  config.rotor.imbalance_kgm = 2.0e-3;
  config.rotor.imbalance_angle_rad = 0.7;
  std::unique_ptr<RigModel> model;
  ASSERT_TRUE(RigModel::Create(config, &model).ok);
  const mjModel* m = model->model();
  double total_kg = 0.0;
  for (int b = 0; b < m->nbody; ++b) total_kg += m->body_mass[b];
  const double imbalance_mass_kg = config.rotor.imbalance_kgm / config.rotor.imbalance_radius_m;
  const double expected_kg = config.platform.mass_kg + config.motor.mass_kg + config.rotor.slip_ring_mass_kg +
                             config.rotor.bracket_mass_kg + config.lidar.mass_kg + imbalance_mass_kg;
  EXPECT_NEAR(total_kg, expected_kg, 1e-12);
  // Mass-offset product of everything that turns, about the hinge axis (rotor frame x-y): exactly the imbalance,
  // pointing at imbalance_angle_rad (the cradle, slip ring and VLP-16 are balanced by construction).
  const int rotor = model->rotor_body_id(), lidar = model->lidar_body_id();
  const Eigen::Vector3d rotor_com(m->body_ipos + 3 * rotor);
  Pose3 T_rotor_lidar = model->geometry().T_rotor_lidar;
  const Eigen::Vector3d lidar_com = T_rotor_lidar * Eigen::Vector3d(m->body_ipos + 3 * lidar);
  const Eigen::Vector3d moment = m->body_mass[rotor] * rotor_com + m->body_mass[lidar] * lidar_com;
  EXPECT_NEAR(moment.head<2>().norm(), config.rotor.imbalance_kgm, 1e-12);
  EXPECT_NEAR(std::atan2(moment.y(), moment.x()), 0.7, 1e-9);
  // Hinge armature = the NEMA-17's rotor inertia (54 g cm^2).
  EXPECT_DOUBLE_EQ(m->dof_armature[m->jnt_dofadr[model->hinge_joint_id()]], 5.4e-6);
}

TEST(RigModel, MjcfErrorsNameTheFile) {
  RigModelConfig config;
  config.mjcf_template_path = TempPath("no_such_dir/rig.xml");
  std::string error;
  EXPECT_EQ(BuildRigMjcf(config, &error), "");
  EXPECT_NE(error.find("no_such_dir/rig.xml"), std::string::npos) << error;
  config.mjcf_template_path = TempPath("bad_template.xml");
  WriteFile(config.mjcf_template_path, "<mujoco>\n  <option timestep=\"{{timestep_s}}\"/>\n  {{no_such_key}}\n");
  EXPECT_EQ(BuildRigMjcf(config, &error), "");
  EXPECT_NE(error.find("bad_template.xml:3: unknown placeholder '{{no_such_key}}'"), std::string::npos) << error;
  std::unique_ptr<RigModel> model;
  EXPECT_FALSE(RigModel::Create(config, &model).ok);
  EXPECT_EQ(model, nullptr);
}

TEST(MujocoUtil, MujocoErrorsBecomeStatusNotExit) {
  // An mjData whose stack is far too small: mj_forward calls mju_error (the default handler would exit).
  mjModel* m = nullptr;
  const std::string xml = "<mujoco><worldbody><body><freejoint/><geom size=\"0.1\"/></body></worldbody></mujoco>";
  const Status loaded = LoadMjcfFromString(xml, "tiny_stack.xml", &m);
  ASSERT_TRUE(loaded.ok) << loaded.message;
  m->nstack = 10;
  mjData* d = mj_makeData(m);
  const Status status = GuardMujoco("forward", [&] { mj_forward(m, d); });
  EXPECT_FALSE(status.ok);
  EXPECT_NE(status.message.find("forward: MuJoCo error"), std::string::npos) << status.message;
  mj_deleteData(d);
  mj_deleteModel(m);
  // A compile error comes back as a Status with MuJoCo's message.
  const Status bad = LoadMjcfFromString("<mujoco><worldbody><geom type=\"nonsense\"/></worldbody></mujoco>",
                                        "bad.xml", &m);
  EXPECT_FALSE(bad.ok);
  EXPECT_EQ(m, nullptr);
}

TEST(RigModelYaml, ShippedFileHoldsTheDefaults) {
  RigModelConfig loaded;
  loaded.rotor.imbalance_kgm = 0.5;  // must be overwritten by the file
  const Status status = LoadRigModelConfig(std::string(ROTOLIDAR_SOURCE_DIR) + "/rig_model/rig.yaml", &loaded);
  ASSERT_TRUE(status.ok) << status.message;
  YAML::Emitter a, b;
  EmitRigModelConfig(a, loaded);
  EmitRigModelConfig(b, RigModelConfig());
  // Poses pass through quaternions: equal to 1e-15, not bit for bit.
  ExpectYamlNear(YAML::Load(a.c_str()), YAML::Load(b.c_str()), "rig", 1e-15);
}

TEST(RigModelYaml, EmitParseRoundTrip) {
  RigModelConfig c;
  c.carrier = PlatformType::kWheeled;
  c.platform = DefaultPlatform(c.carrier);
  c.platform.mass_kg = 21.5;
  c.motor.axis = MotorAxis::kTilted;
  c.motor.tilt_deg = 20.0;
  c.rotor.imbalance_kgm = 3e-3;
  c.physics.timestep_s = 0.002;
  YAML::Emitter out;
  EmitRigModelConfig(out, c);
  const std::string path = TempPath("rig_roundtrip.yaml");
  WriteFile(path, out.c_str());
  RigModelConfig back;
  ASSERT_TRUE(LoadRigModelConfig(path, &back).ok);
  YAML::Emitter again;
  EmitRigModelConfig(again, back);
  ExpectYamlNear(YAML::Load(out.c_str()), YAML::Load(again.c_str()), "rig", 1e-15);
  EXPECT_EQ(back.carrier, PlatformType::kWheeled);
  EXPECT_EQ(back.platform.mass_kg, 21.5);
}

TEST(RigModelYaml, CarrierKeySelectsItsPlatform) {
  const std::string path = TempPath("rig_car.yaml");
  WriteFile(path, "carrier: car\n");
  RigModelConfig c;
  ASSERT_TRUE(LoadRigModelConfig(path, &c).ok);
  EXPECT_EQ(c.platform.mass_kg, DefaultPlatform(PlatformType::kCar).mass_kg);
}

TEST(RigModelYaml, ErrorsNameFileLineAndField) {
  const std::string path = TempPath("rig_bad.yaml");
  WriteFile(path, "carrier: handheld\nrotor:\n  lidar_offset_m: 0.1\n  imbalance_kg: 0.001\n");
  RigModelConfig c;
  Status status = LoadRigModelConfig(path, &c);
  EXPECT_FALSE(status.ok);
  EXPECT_NE(status.message.find(path + ":4: unknown key 'imbalance_kg'"), std::string::npos) << status.message;
  WriteFile(path, "motor:\n  axis: sideways\n");
  status = LoadRigModelConfig(path, &c);
  EXPECT_NE(status.message.find(path + ":2:"), std::string::npos) << status.message;
  EXPECT_NE(status.message.find("motor.axis"), std::string::npos) << status.message;
  WriteFile(path, "rotor:\n  imbalance_kgm: -1\n");
  status = LoadRigModelConfig(path, &c);
  EXPECT_NE(status.message.find("rotor.imbalance_kgm"), std::string::npos) << status.message;
}

}  // namespace
}  // namespace rotolidar::sim
