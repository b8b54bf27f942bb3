#pragma once
// The rig's MuJoCo model: its parameters (RigModelConfig, rig_model/rig.yaml), the MJCF built from the template
// rig_model/rig.xml, and RigModel, the compiled mjModel (immutable after load). The mutable physics state that
// steps it is RigState (sim/rig/rig_physics.hpp). docs/rig_model.md explains the parts, masses and choices.
//
// Bodies (MJCF names): carrier_target (mocap, the intended carrier pose) -- weld `carrier_track` -- base (free
// joint; sites `imu`, `cam`; the carrier's platform) > motor (fixed on base at T_base_motor; NEMA-17 body) >
// rotor (hinge `rotor_hinge` about motor z; slip ring, bracket, imbalance mass) > lidar (VLP-16 at T_rotor_lidar;
// site `lidar`). Actuator `rotor_motor` (torque on the hinge, gear 1); sensors `imu_accel`, `imu_gyro` at `imu`.
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "core/types/calib.hpp"
#include "core/types/geometry.hpp"
#include "core/util/status.hpp"

typedef struct mjModel_ mjModel;  // MuJoCo's model (mujoco/mjmodel.h); this header stays MuJoCo-free
namespace YAML {
class Node;
class Emitter;
}  // namespace YAML

namespace rotolidar::sim {

enum class PlatformType { kHandheld, kWheeled, kCar };
enum class MotorAxis {
  kHorizontal,  ///< motor z along base +x (the seed's forward scanner; the default)
  kVertical,    ///< motor z along base +z
  kTilted,      ///< motor z in the base x-z plane, tilt_deg above base +x towards +z
};
/// The words of the enums in YAML and on the command line (core/io/yaml_fields.hpp finds them by
/// argument-dependent lookup), and a value's word ("unknown" outside the enum).
const std::vector<std::pair<const char*, PlatformType>>& EnumWords(PlatformType*);
const std::vector<std::pair<const char*, MotorAxis>>& EnumWords(MotorAxis*);
const char* PlatformTypeName(PlatformType type);  ///< "handheld", "wheeled", "car"
const char* MotorAxisName(MotorAxis axis);      ///< "horizontal", "vertical", "tilted"

/// The carrier's platform: a box (plus a grip or wheels by carrier type, see docs/rig_model.md) that carries
/// the rig. Everything on the base that is not the motor (frame, battery, computer, IMU, camera, chassis).
struct PlatformConfig {
  double mass_kg = 1.5;                                   ///< total mass of the platform's geoms
  Eigen::Vector3d size_m = Eigen::Vector3d(0.30, 0.14, 0.08);     ///< full extents of the main box (base axes)
  Eigen::Vector3d center_m = Eigen::Vector3d(-0.04, 0.0, -0.07);  ///< the main box's centre in the base frame
};
/// Defaults per carrier: handheld 1.5 kg frame; wheeled 17 kg (Clearpath Jackal-class UGV); car 1500 kg.
PlatformConfig DefaultPlatform(PlatformType type);

/// The stepper on the base and the rig geometry along its axis.
struct MotorMountConfig {
  MotorAxis axis = MotorAxis::kHorizontal;
  double tilt_deg = 30.0;  ///< kTilted only: angle of motor z above base +x, towards base +z, in [-90, 90]
  Eigen::Vector3d position_m = Eigen::Vector3d(0.12, 0.0, 0.0);  ///< motor frame origin (the flange) in base
  double mass_kg = 0.28;             ///< NEMA-17 17HS4401 body (datasheet 0.28 kg)
  double body_width_m = 0.0423;      ///< NEMA-17 square flange
  double body_length_m = 0.040;      ///< 17HS4401 body length (behind the flange, along -motor z)
  double rotor_inertia_kgm2 = 5.4e-6;  ///< 17HS4401 rotor inertia 54 g cm^2 (added as hinge armature)
};

/// What turns with the hinge, apart from the VLP-16 (approximate geometry: docs/rig_model.md).
struct RotorConfig {
  double lidar_offset_m = 0.08;        ///< VLP-16 origin along motor z from the flange (T_rotor_lidar.z)
  double slip_ring_mass_kg = 0.06;     ///< 12-circuit capsule slip ring (assumed), half turns with the rotor
  double slip_ring_diameter_m = 0.022;
  double slip_ring_length_m = 0.030;
  double bracket_mass_kg = 0.12;       ///< aluminium cradle (flange + 2 cheeks, 3 mm plate; assumed), balanced
  double imbalance_kgm = 1.0e-3;       ///< static imbalance m*r [kg m] as a point mass off the axis (0 = none)
  double imbalance_radius_m = 0.05;    ///< radius r of that point mass (mass = imbalance_kgm / r)
  double imbalance_angle_rad = 0.0;    ///< its direction about rotor z, from rotor +x
  double hinge_damping_nms = 2.0e-4;   ///< bearing viscous damping [N m s/rad] (assumed)
  double hinge_frictionloss_nm = 0.01;  ///< dry friction of slip ring + bearings [N m] (assumed)
  double hinge_extra_armature_kgm2 = 0.0;  ///< armature added to the motor's rotor inertia [kg m^2]
};

/// VLP-16 as a uniform cylinder (datasheet: 0.83 kg, D 103.3 mm x H 71.7 mm), centred on the lidar origin.
struct LidarBodyConfig {
  double mass_kg = 0.83;
  double diameter_m = 0.1033;
  double height_m = 0.0717;
};

/// Integration and the carrier's compliance. The base is a free body carried along the mocap target by a
/// feed-forward wrench (its mass and inertia times the target's acceleration, plus its weight) and held on it by a
/// soft weld that acts like a spring-damper of natural frequency tracking_natural_hz (a hand holding the rig, a
/// chassis on its suspension): forces the rig makes itself (rotor imbalance, reaction and gyroscopic torques)
/// shake the platform against that spring (rig_physics.hpp, docs/rig_model.md).
struct RigPhysicsConfig {
  double timestep_s = 0.001;          ///< physics step (1 kHz: the encoder rate; divides the IMU's 5 ms)
  double tracking_natural_hz = 8.0;   ///< weld natural frequency [Hz]
  double tracking_damping_ratio = 1.0;
  /// MuJoCo solimp d of the weld, in [1e-4, 0.9999]: the share of any other force the weld cancels at once
  /// instead of through its spring. Small = a physical spring; near 1 = a rigid mount.
  double tracking_impedance = 0.01;
  int solver_iterations = 20;         ///< Newton iterations cap (the weld converges in 1-2)
};

struct RigModelConfig {
  PlatformType carrier = PlatformType::kHandheld;
  PlatformConfig platform;  ///< DefaultPlatform(carrier) unless overridden
  MotorMountConfig motor;
  RotorConfig rotor;
  LidarBodyConfig lidar;
  Pose3 T_base_imu = DefaultTBaseImu();  ///< IMU measurement axes on the base (DefaultRigCalib's)
  Pose3 T_base_cam = DefaultTBaseCam();  ///< camera optical frame on the base (DefaultRigCalib's)
  RigPhysicsConfig physics;
  /// MJCF template; "" = ResolveRigTemplatePath("").
  std::string mjcf_template_path;

  /// False with a message naming the field ("rotor.imbalance_kgm must be >= 0") when a value is unusable.
  bool Validate(std::string* error) const;

  static Pose3 DefaultTBaseImu();
  static Pose3 DefaultTBaseCam();
};

/// `path` when non-empty, else $ROTOLIDAR_RIG_MODEL_DIR/rig.xml when that is set, else <source>/rig_model/rig.xml.
std::string ResolveRigTemplatePath(const std::string& path);

/// Rotation of the motor frame in the base frame for the configured axis (horizontal = RotY(pi/2)).
Eigen::Matrix3d MotorAxisRotation(const MotorMountConfig& motor);

/// Fills the rig geometry of *calib (T_base_motor, T_rotor_lidar, T_base_imu, T_base_cam) exactly as the MJCF
/// places the bodies and sites; other fields are untouched. The default config reproduces DefaultRigCalib()'s
/// geometry bit for bit.
void FillRigGeometry(const RigModelConfig& config, RigCalib* calib);

/// The resolved MJCF: the template with every {{placeholder}} filled from `config` (which must Validate) and
/// the weld's torquescale [m] (RigModel::Create derives it from the compiled masses; 1 is only a first guess).
/// Returns "" and sets *error (naming the template file or placeholder) on failure.
std::string BuildRigMjcf(const RigModelConfig& config, std::string* error, double weld_torquescale_m = 1.0);

/// YAML (rig_model/rig.yaml layout, docs/rig_model.md). Unknown keys are errors naming file:line. Setting
/// `carrier:` resets `platform` to DefaultPlatform(carrier) before `platform:` overrides are read.
/// ParseRigModelConfig reads `node` (a map, e.g. nested in the sim config; null = keep *config) over *config; an
/// error names `file`:line and the field (*config untouched then); it does not Validate.
Status ParseRigModelConfig(const std::string& file, const YAML::Node& node, RigModelConfig* config);
Status LoadRigModelConfig(const std::string& path, RigModelConfig* config);  ///< reads, parses and Validates
void EmitRigModelConfig(YAML::Emitter& out, const RigModelConfig& config);   ///< a map (all fields)

/// The compiled rig: immutable after Create, so const access is thread-safe. Owns its mjModel; non-copyable.
class RigModel {
 public:
  /// Validates `config`, builds the MJCF, compiles it (in-memory VFS) and looks up every named element.
  static Status Create(const RigModelConfig& config, std::unique_ptr<RigModel>* model);
  ~RigModel();
  RigModel(const RigModel&) = delete;
  RigModel& operator=(const RigModel&) = delete;

  const mjModel* model() const { return model_; }
  const RigModelConfig& config() const { return config_; }
  const std::string& mjcf() const { return mjcf_; }  ///< the resolved MJCF text (write it beside run outputs)
  /// The geometry the model was built with (FillRigGeometry on a default RigCalib; only geometry is meaningful).
  const RigCalib& geometry() const { return geometry_; }
  double timestep_s() const;
  double weld_torquescale_m() const;  ///< the weld's torquescale Create chose (see rig_model.cpp)

  // MuJoCo ids (element index in its mjModel arrays).
  int target_body_id() const { return target_body_; }
  int target_mocap_id() const { return target_mocap_; }  ///< index into mjData::mocap_pos / mocap_quat
  int base_body_id() const { return base_body_; }
  int motor_body_id() const { return motor_body_; }
  int rotor_body_id() const { return rotor_body_; }
  int lidar_body_id() const { return lidar_body_; }
  int base_joint_id() const { return base_joint_; }
  int hinge_joint_id() const { return hinge_joint_; }
  int imu_site_id() const { return imu_site_; }
  int cam_site_id() const { return cam_site_; }
  int lidar_site_id() const { return lidar_site_; }
  int accel_sensor_id() const { return accel_sensor_; }
  int gyro_sensor_id() const { return gyro_sensor_; }
  int motor_actuator_id() const { return motor_actuator_; }
  int weld_id() const { return weld_; }

 private:
  RigModel() = default;
  Status LookUpIds();

  mjModel* model_ = nullptr;
  RigModelConfig config_;
  std::string mjcf_;
  RigCalib geometry_;
  int target_body_ = -1, target_mocap_ = -1, base_body_ = -1, motor_body_ = -1, rotor_body_ = -1, lidar_body_ = -1;
  int base_joint_ = -1, hinge_joint_ = -1, imu_site_ = -1, cam_site_ = -1, lidar_site_ = -1;
  int accel_sensor_ = -1, gyro_sensor_ = -1, motor_actuator_ = -1, weld_ = -1;
};

}  // namespace rotolidar::sim
