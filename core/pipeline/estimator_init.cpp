// IMU initialisation inside the estimator (imu_init.hpp): static start first, moving start otherwise, from the
// LiDAR-only poses of the first scans. The world frame stays the base frame at the first scan; gravity is
// estimated in it and handed to the sliding window.
#include "core/backend/imu_init.hpp"
#include "core/pipeline/estimator_internal.hpp"
#include "core/util/log.hpp"

namespace rotolidar {

void Estimator::TryInitializeImu() {
  const size_t n = init_poses_imu_.size();
  if (int(n) < config_.imu_init_scans) return;
  NavState state;
  state.R_world_imu = init_poses_imu_.back().linear();
  state.p_world_m = init_poses_imu_.back().translation();
  const double g = config_.imu_init.gravity_mps2;

  // Static start: the IMU's first still window gives gravity (in the imu frame, hence in world through the
  // LiDAR pose of the imu then) and the gyro bias; the rig is at rest, so v = 0.
  const ImuInitResult still = InitializeStatic(imu_, config_.imu_init);
  const double moved_m = (init_poses_imu_.back().translation() - init_poses_imu_.front().translation()).norm();
  if (still.success && moved_m < 0.05) {
    const Eigen::Vector3d g_imu = still.R_world_imu.transpose() * Eigen::Vector3d(0, 0, -g);
    state.bias_gyro_radps = still.bias_gyro_radps;
    if (StartWindow(init_poses_imu_.front().linear() * g_imu, state)) {
      LOG_INFO("estimator: IMU initialised (static start) at scan " << n);
      return;
    }
  }
  // Moving start: gyro bias, velocities and gravity from the LiDAR poses and the IMU between them.
  std::vector<PreintegratedImu> between;
  for (size_t k = 0; k + 1 < n; ++k) {
    auto pre = PreintegrateSpan(imu_, init_times_s_[k], init_times_s_[k + 1], Eigen::Vector3d::Zero(),
                                Eigen::Vector3d::Zero(), calib_.imu);
    if (!pre) return;
    between.push_back(std::move(*pre));
  }
  const ImuInitResult moving = InitializeMoving(init_poses_imu_, between, config_.imu_init);
  if (moving.success) {
    state.v_world_mps = moving.R_world_odom.transpose() * moving.velocities_world_mps.back();
    state.bias_gyro_radps = moving.bias_gyro_radps;
    if (StartWindow(moving.gravity_odom_mps2, state)) {
      LOG_INFO("estimator: IMU initialised (moving start) at scan " << n);
      return;
    }
  }
  // Not yet: slide the collection window (keeps the linear system's span bounded).
  if (int(n) >= 3 * config_.imu_init_scans) {
    init_poses_imu_.erase(init_poses_imu_.begin());
    init_times_s_.erase(init_times_s_.begin());
  }
}

bool Estimator::StartWindow(const Eigen::Vector3d& gravity_world_mps2, const NavState& state) {
  SlidingWindowConfig wc = config_.window;
  wc.gravity_world_mps2 = gravity_world_mps2;
  wc.motor_in_imu = MotorAxisInImu::From(calib_.T_base_motor, calib_.T_base_imu);
  // A fixed sensor (motor_speed_radps 0) has no encoder angles to be off: a rotor offset would only be a spare
  // turn of the LiDAR-IMU extrinsic.
  if (calib_.motor_speed_radps == 0.0) wc.estimate_rotor_offset = false;
  std::string why;
  if (!wc.Validate(&why)) return false;
  auto window = std::make_unique<SlidingWindow>(wc);
  if (Status s = window->Initialize(init_times_s_.back(), state); !s) {
    LOG_WARN("estimator: IMU initialisation rejected: " << s.message);
    return false;
  }
  window_ = std::move(window);
  if (visual_) window_->AttachVisual(visual_->landmarks());
  init_poses_imu_.clear();
  init_times_s_.clear();
  return true;
}

}  // namespace rotolidar
