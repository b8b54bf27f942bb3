#pragma once
// Sliding-window LiDAR-inertial back end (seed paper "LV-SLAM", Sec. 3.3): a window of the most recent IMU states
// x_k = {T_world_imu, v_world, bg, ba}, optimised jointly with Ceres over
//   - one ImuFactor per interval between consecutive states (core/imu/imu_factor.hpp),
//   - one LidarPoseFactor per state that has a scan-to-map measurement (core/backend/pose_factors.hpp), or with
//     config.estimate_rotor_offset / estimate_time_offset a LidarOffsetFactor that also sees one shared
//     rotor-angle offset block and / or one shared IMU time-offset block (core/backend/lidar_offset_factor.hpp;
//     rotor_offset_rad() and time_offset_s() are the estimates),
//   - one LinearizedPriorFactor: the first state's prior, later the Schur-complement marginalisation prior.
// The seed's visual reprojection factors attach later to the same pose blocks (a landmark block is a BlockRef
// of kind kVector, and Marginalize() already handles any block set). docs/backend.md has the equations.
//
// Frames: gravity in world starts at config.gravity_world_mps2; with config.estimate_gravity its direction is a
// window variable (one block shared by every IMU factor, |g| fixed) that follows the LiDAR map's slow roll/pitch
// drift; gravity_world_mps2() is the estimate. Every LiDAR measurement must be the imu frame's pose in that world
// (convert a base-frame registration with LidarMeasurementInImuFrame()). Times are rig seconds.
// Ownership: the window owns its states, factors and preintegration copies.
// Thread safety: none; one owner calls AddState/Optimize. Failure: AddState returns a Status naming the bad
// argument and changes nothing; Optimize reports through WindowResult; programmer errors throw (ROTOLIDAR_CHECK).
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <ceres/manifold.h>
#include <ceres/solver.h>
#include <Eigen/Core>

#include "core/backend/pose_factors.hpp"
#include "core/backend/lidar_offset_factor.hpp"
#include "core/backend/visual_landmarks.hpp"
#include "core/imu/imu_factor.hpp"
#include "core/imu/preintegration.hpp"
#include "core/types/time.hpp"
#include "core/util/log.hpp"

namespace rotolidar {

enum class BackendLoss { kNone, kHuber, kCauchy };

/// What happens to the oldest state when the window is full.
enum class MarginalizationScheme {
  kSchurComplement,  ///< linearise its factors and fold them into a prior on its neighbours (default; exact for
                     ///< linear-Gaussian factors: the window then equals the full batch up to linearisation)
  kDropOldest,       ///< discard it and its factors (fixed lag without a prior: loses the accumulated bias
                     ///< information; kept as an ablation baseline)
};

struct SlidingWindowConfig {
  int window_size = 10;  ///< states kept (>= 2); the oldest is marginalised when a state would exceed it
  Eigen::Vector3d gravity_world_mps2 = Eigen::Vector3d(0.0, 0.0, -9.81);
  MarginalizationScheme marginalization = MarginalizationScheme::kSchurComplement;

  /// Estimate gravity's direction (|g| fixed) as one window block on the sphere, shared by the IMU factors
  /// (ImuGravityFactor), instead of holding gravity_world_mps2 fixed. The LiDAR map's roll/pitch drifts slowly;
  /// the LiDAR factors pull the attitudes to it, and a fixed gravity then leaks into the directions the LiDAR
  /// cannot see (a corridor's axis). false = the fixed gravity (why: docs/backend.md, 'Gravity direction').
  bool estimate_gravity = true;
  /// Random walk of gravity's direction in world [rad/sqrt(s)] (the map's tilt drift as seen by the window):
  /// the marginalised information on gravity is diluted by (this |g|)^2 dt per slide of dt. > 0. Default 3e-3:
  /// lets gravity follow the map's tilt in a corridor (why: docs/backend.md, 'Gravity direction').
  double gravity_random_walk_rad_per_sqrt_s = 3e-3;
  /// Prior on gravity's direction at Initialize (1-sigma per axis) [rad]: the initialisation's tilt error,
  /// dominated by the accelerometer bias it does not estimate (|ba| / g).
  double initial_gravity_sigma_rad = 0.01;

  /// Estimate the rotor-angle offset phi (core/backend/lidar_offset_factor.hpp: an encoder zero error, or an
  /// encoder clock that drifts against the LiDAR's) as one block shared by the LiDAR factors (LidarOffsetFactor),
  /// a random walk between the marginalised past and the window as gravity is. The IMU observes it (gravity and
  /// rotation rates see the base, the LiDAR sees the scan turned by phi); the Estimator removes the estimate from
  /// the encoder angles of the scans that follow. Off: every LiDAR factor is a LidarPoseFactor.
  bool estimate_rotor_offset = false;
  /// Random walk of phi [rad/sqrt(s)]. A 20 ppm encoder clock at 2.6 rad/s drifts 5.2e-5 rad/s; 5e-4 lets the
  /// estimate follow that (5 mrad per 100 s) while a window's worth of data moves it little.
  double rotor_offset_random_walk_rad_per_sqrt_s = 5e-4;
  double initial_rotor_offset_sigma_rad = 0.05;  ///< prior on phi at Initialize (around 0) [rad]
  /// Estimate the IMU time offset td (IMU stamp = rig time + td: a free-running IMU clock's offset and drift;
  /// core/backend/lidar_offset_factor.hpp) as one block shared by the LiDAR factors, a random walk like phi. The
  /// Estimator removes the estimate from the IMU stamps that follow. Off: the stamps are taken as rig time.
  bool estimate_time_offset = false;
  /// Random walk of td [s/sqrt(s)]. A 20 ppm IMU clock drifts 2e-5 s/s; 2e-4 lets the estimate follow that
  /// (2 ms per 100 s) while a window's worth of data moves it little.
  double time_offset_random_walk_s_per_sqrt_s = 2e-4;
  double initial_time_offset_sigma_s = 0.01;  ///< prior on td at Initialize (around 0) [s]
  /// The motor axis and origin in the imu frame (the Estimator derives it from calib.yaml's T_base_motor and
  /// T_base_imu); used with estimate_rotor_offset.
  MotorAxisInImu motor_in_imu;

  // Ceres (Levenberg-Marquardt; a window is ~150 tangent dimensions).
  /// Per Optimize(); >= 1. Each scan adds one state to a window already at its optimum, so a few steps converge
  /// (why 3: docs/backend.md, 'The window').
  int max_iterations = 3;
  /// LM damps with diag(J^T J) / radius. The bias random walk puts ~1e10 on bias diagonals whose net information
  /// is ~1e2, so Ceres' default radius (1e4) shrinks bias steps ~1e4-fold and needs ~10 iterations to grow back
  /// (docs/backend.md, 'The window'). A large radius starts as Gauss-Newton (the window is nearly linear); a
  /// rejected step still shrinks it. > 0.
  double initial_trust_region_radius = 1e10;
  double max_solver_time_s = 1.0;      ///< wall-clock cap per Optimize() [s]
  double function_tolerance = 1e-8;    ///< relative cost change that counts as converged
  double gradient_tolerance = 1e-10;
  double parameter_tolerance = 1e-10;
  int num_threads = 1;
  /// The window's Jacobian (~350 x 150) is block-sparse, so sparse normal equations are cheaper than dense ones
  /// at the same estimates (docs/backend.md, 'The window'). Validate checks it with Ceres' Solver::Options.
  ceres::LinearSolverType linear_solver = ceres::SPARSE_NORMAL_CHOLESKY;

  /// Robust loss on the LiDAR factors only (outlier registrations); the scale is on the whitened residual
  /// norm: 4.1 = sqrt(16.8), the 99 % quantile of chi^2 with 6 dof, so consistent measurements are unaffected.
  BackendLoss lidar_loss = BackendLoss::kHuber;
  double lidar_loss_scale = 4.1;

  /// Re-integrate an interval when the bias estimate of its first state moved this far from the preintegration's
  /// linearisation point (the first-order correction's error grows with the square of the change).
  double repropagate_gyro_bias_radps = 1e-2;
  double repropagate_accel_bias_mps2 = 0.1;

  /// Prior on the first state (1-sigma, per axis). Position and yaw are also fixed by the LiDAR measurements.
  double initial_position_sigma_m = 0.01;
  double initial_rotation_sigma_rad = 0.01;
  double initial_velocity_sigma_mps = 0.1;
  double initial_gyro_bias_sigma_radps = 0.02;
  double initial_accel_bias_sigma_mps2 = 0.2;

  /// |preintegration.dt_s() - (t_new - t_previous)| above this rejects AddState [s].
  double max_dt_mismatch_s = 1e-3;

  bool Validate(std::string* error) const;  ///< false with the offending field named in *error
  ceres::Solver::Options SolverOptions() const;
};

struct WindowResult {
  bool converged = false;     ///< Ceres reached a tolerance (not the iteration or time cap)
  int iterations = 0;         ///< Ceres iterations
  double initial_cost = 0.0;  ///< 1/2 sum rho(|r|^2) of the whitened residuals before the solve
  double final_cost = 0.0;    ///< the same after
  double solve_time_s = 0.0;  ///< Ceres' total time [s]
  int num_states = 0;
  int repropagated_intervals = 0;  ///< intervals re-integrated at new biases after this solve
  std::string message;             ///< Ceres' brief report, or why nothing was solved
};

struct WindowStateEstimate {
  Seconds t_s = 0.0;
  NavState state;
  bool has_lidar = false;  ///< the state carries a LiDAR factor
};

class SlidingWindow {
 public:
  /// config must be valid (a programmer error otherwise: ROTOLIDAR_CHECK).
  explicit SlidingWindow(const SlidingWindowConfig& config);
  ~SlidingWindow();
  SlidingWindow(const SlidingWindow&) = delete;
  SlidingWindow& operator=(const SlidingWindow&) = delete;

  /// Starts the window with the first state (e.g. from ImuInit), a Gaussian prior around it (config sigmas) and
  /// an optional LiDAR measurement. Error when already initialised (call Reset) or a value is not finite.
  Status Initialize(Seconds t_s, const NavState& initial_state,
                    const std::optional<LidarPoseMeasurement>& lidar = std::nullopt);

  /// Appends the state at t_s. imu_from_previous integrates [t_previous, t_s] (any linearisation biases, e.g. the
  /// latest estimate); the new state's initial guess is its Predict() from the latest state. When the window is
  /// full the oldest state is first marginalised (config.marginalization). Errors (nothing changes): not
  /// initialised, t_s not after the latest state, dt mismatch, an empty preintegration, a non-finite measurement.
  Status AddState(Seconds t_s, const PreintegratedImu& imu_from_previous,
                  const std::optional<LidarPoseMeasurement>& lidar = std::nullopt);

  /// Solves the window, then re-integrates intervals whose bias moved past the thresholds. Without states it
  /// returns converged = false with a message.
  WindowResult Optimize();

  bool initialized() const { return !states_.empty(); }
  int size() const { return static_cast<int>(states_.size()); }
  Seconds latest_time_s() const;   ///< requires initialized()
  NavState latest_state() const;   ///< requires initialized()
  std::vector<WindowStateEstimate> states() const;  ///< oldest first
  /// The state at the end of imu_since_latest (which starts at latest_time_s()): for deskewing the next scan.
  NavState PredictFromLatest(const PreintegratedImu& imu_since_latest) const;
  /// The rotor-angle offset estimate [rad] (config.estimate_rotor_offset; 0 otherwise).
  double rotor_offset_rad() const { return rotor_[0]; }
  /// The IMU time-offset estimate [s] (config.estimate_time_offset; 0 otherwise).
  double time_offset_s() const { return time_[0]; }
  /// Gravity in world [m/s^2]: the estimate (config.estimate_gravity) or config.gravity_world_mps2.
  Eigen::Vector3d gravity_world_mps2() const { return Eigen::Map<const Eigen::Vector3d>(gravity_); }
  /// The current prior (first-state or marginalisation prior), or null.
  const LinearizedPriorFactor* prior() const { return prior_.get(); }
  int num_marginalized() const { return num_marginalized_; }
  const SlidingWindowConfig& config() const { return config_; }

  void Reset();  ///< drops every state and the prior (and the attached landmarks)

  /// Attaches the visual landmarks (not owned; must outlive the window or be detached with nullptr): from then on
  /// Optimize adds their factors, drops their outliers after the solve, and the marginalisation folds the
  /// landmarks anchored at the oldest state into the prior.
  void AttachVisual(VisualLandmarks* landmarks) { visual_ = landmarks; }
  /// The camera observations of the newest state (attach first). Error when not initialised or none attached.
  Status AddVisualObservations(const std::vector<VisualObservation>& observations);

 private:
  struct State;

  void SlideOut();
  Status MarginalizeOldest();
  int RepropagateMovedIntervals();
  std::vector<MarginalizationTerm> TermsOfOldest();
  std::unique_ptr<ceres::CostFunction> MakeImuFactor(const PreintegratedImu& imu) const;
  BlockRef GravityRef() { return {gravity_, BlockKind::kVector, kGravityBlockSize}; }
  BlockRef RotorRef() { return {rotor_, BlockKind::kVector, kRotorOffsetBlockSize}; }
  BlockRef TimeRef() { return {time_, BlockKind::kVector, kImuTimeOffsetBlockSize}; }
  LidarOffsets EstimatedOffsets() const { return {config_.estimate_rotor_offset, config_.estimate_time_offset}; }
  std::unique_ptr<ceres::CostFunction> MakeLidarFactor(const LidarPoseMeasurement& m) const;
  /// A state's LiDAR factor's blocks, in LidarOffsetFactor's order.
  std::vector<BlockRef> LidarBlocks(State& s);
  /// The random-walk terms of the shared blocks (gravity, rotor and time offsets) for the oldest interval; their
  /// past copies are set to the current values.
  void AddRandomWalkTerms(double dt_s, std::vector<MarginalizationTerm>* terms);
  /// The random-walk term past -> window of one shared block (gravity, rotor offset), for a slide of dt_s.
  static std::unique_ptr<LinearizedPriorFactor> RandomWalk(const BlockRef& past, const BlockRef& now,
                                                           double sigma);

  SlidingWindowConfig config_;
  std::unique_ptr<ceres::Manifold> pose_manifold_;
  std::unique_ptr<ceres::Manifold> gravity_manifold_;
  double gravity_[kGravityBlockSize];            ///< the gravity block (constant without estimate_gravity)
  double gravity_past_[kGravityBlockSize];       ///< gravity of the marginalised past, during a slide only
  std::unique_ptr<LinearizedPriorFactor> gravity_walk_;  ///< random-walk term past -> window, during a slide
  double rotor_[kRotorOffsetBlockSize] = {0.0};       ///< the rotor-offset block (0 without estimate_rotor_offset)
  double rotor_past_[kRotorOffsetBlockSize] = {0.0};  ///< the marginalised past's, during a slide only
  std::unique_ptr<LinearizedPriorFactor> rotor_walk_;  ///< random-walk term past -> window, during a slide
  double time_[kImuTimeOffsetBlockSize] = {0.0};       ///< the IMU time-offset block (0 without estimate_time_offset)
  double time_past_[kImuTimeOffsetBlockSize] = {0.0};  ///< the marginalised past's, during a slide only
  std::unique_ptr<LinearizedPriorFactor> time_walk_;   ///< random-walk term past -> window, during a slide
  std::unique_ptr<ceres::LossFunction> lidar_loss_;
  std::deque<std::unique_ptr<State>> states_;
  std::unique_ptr<LinearizedPriorFactor> prior_;
  int num_marginalized_ = 0;
  VisualLandmarks* visual_ = nullptr;  ///< not owned
};

}  // namespace rotolidar
