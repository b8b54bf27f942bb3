#include "sim/rig/rig_physics.hpp"

#include <cmath>
#include <cstring>

#include "sim/rig/mujoco_util.hpp"
#include "core/util/log.hpp"

namespace rotolidar::sim {
namespace {

// The target's rates, world frame: linear velocity/acceleration of its origin, angular velocity/acceleration.
struct TargetRates {
  Eigen::Vector3d v = Eigen::Vector3d::Zero(), a = Eigen::Vector3d::Zero();
  Eigen::Vector3d omega = Eigen::Vector3d::Zero(), alpha = Eigen::Vector3d::Zero();
};

Eigen::Matrix3d QuatToRotation(const mjtNum* wxyz) {
  return Eigen::Quaterniond(wxyz[0], wxyz[1], wxyz[2], wxyz[3]).normalized().toRotationMatrix();
}

template <typename T>
void AppendBytes(std::string* out, const T* values, int count) {
  out->append(reinterpret_cast<const char*>(values), sizeof(T) * static_cast<size_t>(count));
}

}  // namespace

RigState::RigState(const RigModel& model) : model_(model) {
  InstallMujocoHandlers();
  const mjModel* m = model_.model();
  data_ = mj_makeData(m);
  ROTOLIDAR_CHECK(data_ != nullptr, "mj_makeData failed");
  dt_s_ = m->opt.timestep;
  hinge_qpos_ = m->jnt_qposadr[model_.hinge_joint_id()];
  hinge_dof_ = m->jnt_dofadr[model_.hinge_joint_id()];
  base_qpos_ = m->jnt_qposadr[model_.base_joint_id()];
  base_dof_ = m->jnt_dofadr[model_.base_joint_id()];
  accel_adr_ = m->sensor_adr[model_.accel_sensor_id()];
  gyro_adr_ = m->sensor_adr[model_.gyro_sensor_id()];
  Reset(Pose3::Identity(), 0.0, 0.0);
}

RigState::~RigState() {
  if (data_) mj_deleteData(data_);
}

void RigState::Reset(const Pose3& T_world_base0, double theta0_rad, double omega0_radps) {
  BaseKinematics base0;
  base0.T_world_base = T_world_base0;
  ResetTo(base0, theta0_rad, omega0_radps);
}

void RigState::Reset(const BaseKinematics& base0, double theta0_rad, double omega0_radps) {
  ResetTo(base0, theta0_rad, omega0_radps);
}

namespace {

// The carrier's drive, in two parts (docs/rig_model.md):
//  1. A feed-forward wrench on the base (xfrc_applied) that moves the whole rig, treated as one rigid body with
//     the rotor locked, along the target and carries its weight: F = M (a_com - g), tau = I_c alpha + w x I_c w
//     about the rig's centre of mass. Mass, centre of mass and composite inertia come from the last forward pass
//     (one step old). What it leaves out -- the rotor's spin (imbalance, gyroscopic and reaction torques) -- is
//     what the platform and the IMU should feel.
//  2. The soft weld to the mocap body: a spring-damper (natural frequency f_n, damping ratio zeta) that holds the
//     base on the target against those forces. Mocap bodies have no velocity in MuJoCo, so the weld's damper acts
//     on the base's absolute velocity; placing the mocap body ahead of the target by (2 zeta / w_n) * velocity
//     (and likewise in rotation) makes the damper and the spring cancel exactly when the base moves with the
//     target. With a small solimp d the weld passes a share (1 - d) of every other force through, like a spring.
void DriveCarrier(const RigModel& model, mjData* d, const Pose3& T_world_target, const TargetRates& r) {
  const RigPhysicsConfig& p = model.config().physics;
  const double lead_s = 2.0 * p.tracking_damping_ratio / (2.0 * M_PI * p.tracking_natural_hz);
  Pose3 T_mocap = T_world_target;
  T_mocap.translation() += lead_s * r.v;
  // MuJoCo 2.2.2 scales the weld's rotational Jacobian by torquescale but not its rotational error, so the
  // rotation spring would be 1/torquescale too stiff: scale the error instead, placing the mocap rotation only
  // that fraction of the way from the base's present rotation (the state this step's constraint sees) to the lead.
  const int b = model.base_body_id();
  const int base_qpos = model.model()->jnt_qposadr[model.base_joint_id()];
  const Eigen::Matrix3d R_world_base = QuatToRotation(d->qpos + base_qpos + 3);
  const Eigen::Matrix3d R_lead = ExpSO3(lead_s * r.omega) * T_world_target.linear();
  T_mocap.linear() =
      R_world_base * ExpSO3(model.weld_torquescale_m() * LogSO3(R_world_base.transpose() * R_lead));
  const int mocap = model.target_mocap_id();
  PoseToMujoco(T_mocap, d->mocap_pos + 3 * mocap, d->mocap_quat + 4 * mocap);

  const mjModel* m = model.model();
  const Eigen::Vector3d com(d->subtree_com + 3 * b), origin(d->xpos + 3 * b), ipos(d->xipos + 3 * b);
  const Eigen::Vector3d r_com = com - origin;
  const Eigen::Vector3d a_com = r.a + r.alpha.cross(r_com) + r.omega.cross(r.omega.cross(r_com));
  const Eigen::Vector3d force = m->body_subtreemass[b] * (a_com - GravityWorld());
  const mjtNum* c = d->crb + 10 * b;  // composite inertia about the subtree's centre of mass, world axes
  Eigen::Matrix3d I_com;
  I_com << c[0], c[3], c[4], c[3], c[1], c[5], c[4], c[5], c[2];
  const Eigen::Vector3d torque = I_com * r.alpha + r.omega.cross(I_com * r.omega) + (com - ipos).cross(force);
  for (int i = 0; i < 3; ++i) {  // applied at the base body's own centre of mass (xipos)
    d->xfrc_applied[6 * b + i] = force[i];
    d->xfrc_applied[6 * b + 3 + i] = torque[i];
  }
}

}  // namespace

void RigState::ResetTo(const BaseKinematics& base0, double theta0_rad, double omega0_radps) {
  const mjModel* m = model_.model();
  mj_resetData(m, data_);
  steps_ = 0;
  imu_t_s_ = 0.0;
  last_torque_nm_ = 0.0;
  failed_ = false;
  const Pose3& T0 = base0.T_world_base;
  PoseToMujoco(T0, data_->qpos + base_qpos_, data_->qpos + base_qpos_ + 3);
  for (int i = 0; i < 3; ++i) {
    data_->qvel[base_dof_ + i] = base0.v_world_mps[i];            // free joint: linear velocity in world
    data_->qvel[base_dof_ + 3 + i] = base0.omega_base_radps[i];   // angular velocity in the body frame
  }
  data_->qpos[hinge_qpos_] = theta0_rad;
  data_->qvel[hinge_dof_] = omega0_radps;
  // Prime the feed-forward memory so that the first Step, given the target at t = 0, sees these rates.
  TargetRates r;
  r.v = base0.v_world_mps;
  r.a = base0.a_world_mps2;
  r.omega = T0.linear() * base0.omega_base_radps;
  r.alpha = T0.linear() * base0.alpha_base_radps2;
  prev_target_ = T0;
  prev_target_.translation() -= r.v * dt_s_;
  prev_target_.linear() = ExpSO3(-r.omega * dt_s_) * T0.linear();
  prev_v_world_ = r.v - r.a * dt_s_;
  prev_omega_world_ = r.omega - r.alpha * dt_s_;
  // Two passes: the first finds the rig's centre of mass and inertia, which the carrier's wrench needs.
  const Status status = GuardMujoco("rig physics reset", [&] {
    DriveCarrier(model_, data_, T0, r);
    mj_forward(m, data_);
    DriveCarrier(model_, data_, T0, r);
    mj_forward(m, data_);
  });
  if (!status) {
    LOG_ERROR(status.message);
    failed_ = true;
  }
}

Status RigState::Step(const Pose3& T_world_target, RotorDrive* drive) {
  auto where = [&] {
    return "rig physics: step " + std::to_string(steps_) + " (t = " + std::to_string(time_s()) + " s)";
  };
  if (failed_) return Status::Error(where() + ": the state is invalid after an earlier error; Reset it first");
  const mjModel* m = model_.model();
  data_->time = time_s();
  // The target's rates by backward differences of successive targets (one step apart).
  TargetRates r;
  r.v = (T_world_target.translation() - prev_target_.translation()) / dt_s_;
  r.a = (r.v - prev_v_world_) / dt_s_;
  r.omega = LogSO3(T_world_target.linear() * prev_target_.linear().transpose()) / dt_s_;
  r.alpha = (r.omega - prev_omega_world_) / dt_s_;
  DriveCarrier(model_, data_, T_world_target, r);

  const double torque_nm = drive ? drive->Torque(rotor_state(), dt_s_) : 0.0;
  if (!std::isfinite(torque_nm)) {
    failed_ = true;
    return Status::Error(where() + ": the rotor drive returned a non-finite torque");
  }
  data_->ctrl[model_.motor_actuator_id()] = torque_nm;
  last_torque_nm_ = torque_nm;

  const MujocoWarningCounts before = WarningCounts(data_);
  try {
    mj_step(m, data_);
  } catch (const MujocoError& e) {
    failed_ = true;
    return Status::Error(where() + ": MuJoCo error: " + e.what());
  }
  if (WarningCounts(data_) != before) {
    failed_ = true;
    return NewMujocoWarnings(before, data_, where());
  }
  imu_t_s_ = time_s();
  ++steps_;
  prev_target_ = T_world_target;
  prev_v_world_ = r.v;
  prev_omega_world_ = r.omega;
  return Status::Ok();
}

Pose3 RigState::T_world_base() const {
  return PoseFromMujoco(data_->qpos + base_qpos_, data_->qpos + base_qpos_ + 3);
}

Pose3 RigState::T_world_lidar() const { return T_world_base() * model_.geometry().T_base_lidar(rotor_angle_rad()); }

Eigen::Vector3d RigState::v_world_base_mps() const {
  return Eigen::Vector3d(data_->qvel[base_dof_], data_->qvel[base_dof_ + 1], data_->qvel[base_dof_ + 2]);
}

Eigen::Vector3d RigState::omega_base_radps() const {
  return Eigen::Vector3d(data_->qvel[base_dof_ + 3], data_->qvel[base_dof_ + 4], data_->qvel[base_dof_ + 5]);
}

BaseKinematics RigState::base_kinematics() const {
  BaseKinematics k;
  k.T_world_base = T_world_base();
  k.v_world_mps = v_world_base_mps();
  k.omega_base_radps = omega_base_radps();
  return k;
}

double RigState::rotor_angle_rad() const { return data_->qpos[hinge_qpos_]; }
double RigState::rotor_speed_radps() const { return data_->qvel[hinge_dof_]; }

ImuTruth RigState::imu() const {
  ImuTruth imu;
  imu.t_s = imu_t_s_;
  const mjtNum* a = data_->sensordata + accel_adr_;
  const mjtNum* w = data_->sensordata + gyro_adr_;
  imu.specific_force_imu_mps2 = Eigen::Vector3d(a[0], a[1], a[2]);
  imu.angular_rate_imu_radps = Eigen::Vector3d(w[0], w[1], w[2]);
  return imu;
}

std::string RigState::StateBytes() const {
  const mjModel* m = model_.model();
  std::string bytes;
  AppendBytes(&bytes, &data_->time, 1);
  AppendBytes(&bytes, data_->qpos, m->nq);
  AppendBytes(&bytes, data_->qvel, m->nv);
  AppendBytes(&bytes, data_->act, m->na);
  AppendBytes(&bytes, data_->qacc_warmstart, m->nv);
  AppendBytes(&bytes, data_->mocap_pos, 3 * m->nmocap);
  AppendBytes(&bytes, data_->mocap_quat, 4 * m->nmocap);
  AppendBytes(&bytes, data_->ctrl, m->nu);
  AppendBytes(&bytes, data_->sensordata, m->nsensordata);
  AppendBytes(&bytes, &steps_, 1);
  AppendBytes(&bytes, prev_target_.matrix().data(), 16);
  AppendBytes(&bytes, prev_v_world_.data(), 3);
  AppendBytes(&bytes, prev_omega_world_.data(), 3);
  return bytes;
}

}  // namespace rotolidar::sim
