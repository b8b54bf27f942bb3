#pragma once
// RigState: the mutable physics state of a RigModel (MuJoCo's model/data split: RigModel owns the immutable
// mjModel, RigState owns one mjData). It advances one physics step at a time:
//   Step(T_world_target, drive): the mocap carrier_target goes to the carrier's intended pose, the drive answers
//   the hinge torque from the TRUE hinge state at the start of the step, then mj_step integrates [t, t + dt).
// The base is a dynamic free body, carried along the target by a feed-forward wrench (the whole rig, rotor
// locked, as one rigid body: F = M (a - g), tau = I alpha + w x I w) and held on it by a soft weld to the mocap
// body that behaves like a spring-damper (RigPhysicsConfig: natural frequency tracking_natural_hz). What the
// feed-forward leaves out is what the IMU should feel on top of the carrier's motion: the rotor imbalance's
// once-per-revolution vibration, the rotor's reaction and gyroscopic torques. The target's velocity and
// acceleration come from backward differences of successive targets (one step apart) (docs/rig_model.md).
//
// Time: one physics step = RigModel::timestep_s(); time_s() = step_count() * timestep_s() from the Reset (t = 0),
// independent of MuJoCo's own clock (which it resets after an instability). Not thread-safe; distinct RigStates
// of one RigModel may step concurrently. Identical inputs give bit-identical states (StateBytes()).
#include <cstdint>
#include <string>

#include <Eigen/Core>

#include "core/types/geometry.hpp"
#include "core/types/time.hpp"
#include "core/util/status.hpp"
#include "sim/rig/base_motion.hpp"
#include "sim/rig/rig_model.hpp"
#include "sim/rig/rotor_drive.hpp"

typedef struct mjData_ mjData;  // MuJoCo's data (mujoco/mjdata.h)

namespace rotolidar::sim {

/// The true IMU reading at the imu site, in the imu frame (MuJoCo's accelerometer and gyro sensors).
struct ImuTruth {
  Seconds t_s = 0.0;  ///< the instant it describes: the start of the last step (accelerations need that step's forces)
  Eigen::Vector3d specific_force_imu_mps2 = Eigen::Vector3d::Zero();  ///< R_imu_world (a - g); at rest +9.81 up
  Eigen::Vector3d angular_rate_imu_radps = Eigen::Vector3d::Zero();   ///< angular velocity wrt world, imu frame
};

class RigState {
 public:
  /// Allocates the mjData; `model` must outlive this object. Starts as Reset(identity, 0, 0).
  explicit RigState(const RigModel& model);
  explicit RigState(RigModel&&) = delete;  ///< holds a reference to the model: a temporary would dangle
  ~RigState();
  RigState(const RigState&) = delete;
  RigState& operator=(const RigState&) = delete;

  /// Time 0; base and mocap target at T_world_base0 (at rest), hinge angle/speed, then mj_forward. Clears errors.
  void Reset(const Pose3& T_world_base0, double theta0_rad, double omega0_radps);
  /// As above, with the base already moving as `base0` says (pose, world velocity, base-frame angular velocity;
  /// its accelerations prime the target's feed-forward), so a path that starts in motion starts without a jolt.
  void Reset(const BaseKinematics& base0, double theta0_rad, double omega0_radps);

  /// One physics step from time_s() to time_s() + dt. T_world_target: the carrier's intended pose at time_s().
  /// `drive` (may be null: no torque) gets the true hinge state at time_s() and returns the torque for the step.
  /// Errors (non-finite torque, a MuJoCo warning such as "Nan, Inf or huge value in QACC", a MuJoCo error) name
  /// the step and time; the state is then invalid and every further Step fails until Reset.
  Status Step(const Pose3& T_world_target, RotorDrive* drive);

  Seconds time_s() const { return static_cast<double>(steps_) * dt_s_; }
  int64_t step_count() const { return steps_; }
  double timestep_s() const { return dt_s_; }

  // Physics state at time_s() (from qpos/qvel after the last step).
  Pose3 T_world_base() const;
  Pose3 T_world_lidar() const;  ///< T_world_base * T_base_lidar(rotor_angle_rad()) (RigModel::geometry())
  Eigen::Vector3d v_world_base_mps() const;        ///< velocity of the base origin, world frame
  Eigen::Vector3d omega_base_radps() const;        ///< angular velocity of the base wrt world, base frame
  BaseKinematics base_kinematics() const;          ///< pose, v, omega (accelerations left zero)
  double rotor_angle_rad() const;                  ///< unwrapped hinge angle about motor +z
  double rotor_speed_radps() const;
  RotorJointState rotor_state() const { return {time_s(), rotor_angle_rad(), rotor_speed_radps()}; }
  /// The IMU at the start of the last step (after Reset: at time 0 with zero motor torque).
  ImuTruth imu() const;
  double last_torque_nm() const { return last_torque_nm_; }

  /// The state's bytes (time, qpos, qvel, act, warm start, mocap, ctrl, sensors, feed-forward memory) for
  /// determinism checks: equal inputs must give equal bytes.
  std::string StateBytes() const;
  const mjData* data() const { return data_; }
  const RigModel& model() const { return model_; }

 private:
  void ResetTo(const BaseKinematics& base0, double theta0_rad, double omega0_radps);

  const RigModel& model_;
  mjData* data_ = nullptr;
  double dt_s_ = 0.0;
  int64_t steps_ = 0;
  Seconds imu_t_s_ = 0.0;
  double last_torque_nm_ = 0.0;
  bool failed_ = false;
  int hinge_qpos_ = 0, hinge_dof_ = 0, base_qpos_ = 0, base_dof_ = 0, accel_adr_ = 0, gyro_adr_ = 0;
  // Feed-forward memory: the previous target and its backward-difference velocities (world frame).
  Pose3 prev_target_ = Pose3::Identity();
  Eigen::Vector3d prev_v_world_ = Eigen::Vector3d::Zero(), prev_omega_world_ = Eigen::Vector3d::Zero();
};

}  // namespace rotolidar::sim
