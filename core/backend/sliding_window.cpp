#include "core/backend/sliding_window.hpp"
#include "core/util/log.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include <ceres/loss_function.h>
#include <ceres/problem.h>

namespace rotolidar {

namespace {

bool Finite(const NavState& s) {
  return s.R_world_imu.allFinite() && s.p_world_m.allFinite() && s.v_world_mps.allFinite() &&
         s.bias_gyro_radps.allFinite() && s.bias_accel_mps2.allFinite();
}

bool Finite(const LidarPoseMeasurement& m) {
  return m.T_world_imu.matrix().allFinite() && m.information.allFinite();
}

std::unique_ptr<ceres::LossFunction> MakeLoss(BackendLoss loss, double scale) {
  switch (loss) {
    case BackendLoss::kHuber: return std::make_unique<ceres::HuberLoss>(scale);
    case BackendLoss::kCauchy: return std::make_unique<ceres::CauchyLoss>(scale);
    case BackendLoss::kNone: break;
  }
  return nullptr;
}

}  // namespace

bool SlidingWindowConfig::Validate(std::string* error) const {
  auto fail = [&](const std::string& m) {
    if (error) *error = "sliding_window." + m;
    return false;
  };
  auto positive = [](double x) { return x > 0.0 && std::isfinite(x); };
  if (window_size < 2) return fail("window_size must be >= 2 (got " + std::to_string(window_size) + ")");
  if (!gravity_world_mps2.allFinite() || !(gravity_world_mps2.norm() > 0.0))
    return fail("gravity_world_mps2 must be a finite non-zero vector");
  if (max_iterations < 1) return fail("max_iterations must be >= 1");
  if (!positive(initial_trust_region_radius)) return fail("initial_trust_region_radius must be > 0");
  if (!positive(max_solver_time_s)) return fail("max_solver_time_s must be > 0");
  if (!(function_tolerance >= 0.0)) return fail("function_tolerance must be >= 0");
  if (!(gradient_tolerance >= 0.0)) return fail("gradient_tolerance must be >= 0");
  if (!(parameter_tolerance >= 0.0)) return fail("parameter_tolerance must be >= 0");
  if (num_threads < 1) return fail("num_threads must be >= 1");
  if (lidar_loss != BackendLoss::kNone && !positive(lidar_loss_scale)) return fail("lidar_loss_scale must be > 0");
  if (!positive(repropagate_gyro_bias_radps)) return fail("repropagate_gyro_bias_radps must be > 0");
  if (!positive(repropagate_accel_bias_mps2)) return fail("repropagate_accel_bias_mps2 must be > 0");
  if (!positive(initial_position_sigma_m)) return fail("initial_position_sigma_m must be > 0");
  if (!positive(initial_rotation_sigma_rad)) return fail("initial_rotation_sigma_rad must be > 0");
  if (!positive(initial_velocity_sigma_mps)) return fail("initial_velocity_sigma_mps must be > 0");
  if (!positive(initial_gyro_bias_sigma_radps)) return fail("initial_gyro_bias_sigma_radps must be > 0");
  if (!positive(initial_accel_bias_sigma_mps2)) return fail("initial_accel_bias_sigma_mps2 must be > 0");
  if (!(max_dt_mismatch_s >= 0.0)) return fail("max_dt_mismatch_s must be >= 0");
  if (!positive(gravity_random_walk_rad_per_sqrt_s)) return fail("gravity_random_walk_rad_per_sqrt_s must be > 0");
  if (!positive(initial_gravity_sigma_rad)) return fail("initial_gravity_sigma_rad must be > 0");
  if (!positive(rotor_offset_random_walk_rad_per_sqrt_s))
    return fail("rotor_offset_random_walk_rad_per_sqrt_s must be > 0");
  if (!positive(initial_rotor_offset_sigma_rad)) return fail("initial_rotor_offset_sigma_rad must be > 0");
  if (!positive(time_offset_random_walk_s_per_sqrt_s))
    return fail("time_offset_random_walk_s_per_sqrt_s must be > 0");
  if (!positive(initial_time_offset_sigma_s)) return fail("initial_time_offset_sigma_s must be > 0");
  if (!(std::abs(motor_in_imu.axis.norm() - 1.0) < 1e-6) || !motor_in_imu.origin_m.allFinite())
    return fail("motor_in_imu: the axis must be a unit vector and the origin finite");
  std::string ceres_error;
  if (!SolverOptions().IsValid(&ceres_error)) return fail("linear_solver: " + ceres_error);
  return true;
}

ceres::Solver::Options SlidingWindowConfig::SolverOptions() const {
  ceres::Solver::Options o;
  o.linear_solver_type = linear_solver;
  o.max_num_iterations = max_iterations;
  o.initial_trust_region_radius = initial_trust_region_radius;
  o.max_trust_region_radius = std::max(o.max_trust_region_radius, initial_trust_region_radius);
  o.max_solver_time_in_seconds = max_solver_time_s;
  o.function_tolerance = function_tolerance;
  o.gradient_tolerance = gradient_tolerance;
  o.parameter_tolerance = parameter_tolerance;
  o.num_threads = num_threads;
  o.logging_type = ceres::SILENT;
  return o;
}

/// One window state: its parameter blocks (stable addresses: states live behind unique_ptr) and its factors.
struct SlidingWindow::State {
  Seconds t_s = 0.0;
  double pose[kImuPoseBlockSize];
  double speed_bias[kImuSpeedBiasBlockSize];
  std::optional<PreintegratedImu> imu;     ///< [previous state, this state]; unused for the oldest state
  std::unique_ptr<ceres::CostFunction> imu_factor;  ///< built from `imu` (MakeImuFactor)
  /// LidarPoseFactor, or LidarOffsetFactor with an offset estimated; null when the state has no LiDAR measurement
  std::unique_ptr<ceres::CostFunction> lidar;
  BlockRef PoseRef() { return {pose, BlockKind::kPose, kImuPoseBlockSize}; }
  BlockRef SpeedBiasRef() { return {speed_bias, BlockKind::kVector, kImuSpeedBiasBlockSize}; }
};

SlidingWindow::SlidingWindow(const SlidingWindowConfig& config)
    : config_(config), pose_manifold_(MakeImuPoseManifold()), gravity_manifold_(MakeGravityManifold()) {
  std::string error;
  ROTOLIDAR_CHECK(config.Validate(&error), error);
  lidar_loss_ = MakeLoss(config.lidar_loss, config.lidar_loss_scale);
  Eigen::Vector3d::Map(gravity_) = config.gravity_world_mps2;
}

SlidingWindow::~SlidingWindow() = default;

void SlidingWindow::Reset() {
  prior_.reset();
  states_.clear();
  num_marginalized_ = 0;
  Eigen::Vector3d::Map(gravity_) = config_.gravity_world_mps2;
  rotor_[0] = 0.0;
  time_[0] = 0.0;
  if (visual_) visual_->Clear();
}

Status SlidingWindow::AddVisualObservations(const std::vector<VisualObservation>& observations) {
  if (!initialized()) return Status::Error("SlidingWindow::AddVisualObservations: not initialised");
  if (!visual_) return Status::Error("SlidingWindow::AddVisualObservations: no landmarks attached (AttachVisual)");
  visual_->AddObservations(states_.back()->pose, observations);
  return Status::Ok();
}

std::unique_ptr<ceres::CostFunction> SlidingWindow::MakeImuFactor(const PreintegratedImu& imu) const {
  if (config_.estimate_gravity) return std::make_unique<ImuGravityFactor>(imu);
  return std::make_unique<ImuFactor>(imu, config_.gravity_world_mps2);
}

std::unique_ptr<ceres::CostFunction> SlidingWindow::MakeLidarFactor(const LidarPoseMeasurement& m) const {
  if (EstimatedOffsets().any()) return std::make_unique<LidarOffsetFactor>(m, config_.motor_in_imu, EstimatedOffsets());
  return std::make_unique<LidarPoseFactor>(m);
}

std::vector<BlockRef> SlidingWindow::LidarBlocks(State& s) {
  std::vector<BlockRef> blocks = {s.PoseRef()};
  if (config_.estimate_time_offset) blocks.push_back(s.SpeedBiasRef());
  if (config_.estimate_rotor_offset) blocks.push_back(RotorRef());
  if (config_.estimate_time_offset) blocks.push_back(TimeRef());
  return blocks;
}

std::unique_ptr<LinearizedPriorFactor> SlidingWindow::RandomWalk(const BlockRef& past, const BlockRef& now,
                                                                 double sigma) {
  const int n = now.size;
  const Eigen::VectorXd x = Eigen::Map<const Eigen::VectorXd>(now.values, n);
  Eigen::MatrixXd J(n, 2 * n);
  J << -Eigen::MatrixXd::Identity(n, n) / sigma, Eigen::MatrixXd::Identity(n, n) / sigma;
  return std::make_unique<LinearizedPriorFactor>(std::vector<BlockRef>{past, now}, std::vector<Eigen::VectorXd>{x, x},
                                                 std::move(J), Eigen::VectorXd::Zero(n));
}

Status SlidingWindow::Initialize(Seconds t_s, const NavState& initial_state,
                                 const std::optional<LidarPoseMeasurement>& lidar) {
  if (initialized()) return Status::Error("SlidingWindow::Initialize: already initialised (call Reset first)");
  if (!std::isfinite(t_s) || !Finite(initial_state))
    return Status::Error("SlidingWindow::Initialize: t_s or initial_state is not finite");
  if (lidar && !Finite(*lidar)) return Status::Error("SlidingWindow::Initialize: the LiDAR measurement is not finite");
  auto s = std::make_unique<State>();
  s->t_s = t_s;
  PackImuState(initial_state, s->pose, s->speed_bias);
  if (lidar) s->lidar = MakeLidarFactor(*lidar);
  // Gaussian prior on [pose (6); speed-bias (9); gravity (3, ambient)] around the initial state, diagonal sqrt
  // information 1 / sigma (gravity's radial axis carries no error: the sphere keeps |g|).
  Eigen::Vector3d::Map(gravity_) = config_.gravity_world_mps2;
  rotor_[0] = 0.0;
  time_[0] = 0.0;
  const int n = 15 + (config_.estimate_gravity ? 3 : 0) + (config_.estimate_rotor_offset ? 1 : 0) +
                (config_.estimate_time_offset ? 1 : 0);
  Eigen::VectorXd inv_sigma(n);
  inv_sigma.head<15>() << Eigen::Vector3d::Constant(1.0 / config_.initial_position_sigma_m),
      Eigen::Vector3d::Constant(1.0 / config_.initial_rotation_sigma_rad),
      Eigen::Vector3d::Constant(1.0 / config_.initial_velocity_sigma_mps),
      Eigen::Vector3d::Constant(1.0 / config_.initial_gyro_bias_sigma_radps),
      Eigen::Vector3d::Constant(1.0 / config_.initial_accel_bias_sigma_mps2);
  std::vector<BlockRef> blocks = {s->PoseRef(), s->SpeedBiasRef()};
  std::vector<Eigen::VectorXd> x0 = {Eigen::Map<const Eigen::VectorXd>(s->pose, kImuPoseBlockSize),
                                     Eigen::Map<const Eigen::VectorXd>(s->speed_bias, kImuSpeedBiasBlockSize)};
  if (config_.estimate_gravity) {
    const double g = config_.gravity_world_mps2.norm();
    inv_sigma.segment<3>(15).setConstant(1.0 / (config_.initial_gravity_sigma_rad * g));
    blocks.push_back(GravityRef());
    x0.push_back(Eigen::Map<const Eigen::VectorXd>(gravity_, kGravityBlockSize));
  }
  int next = 15 + (config_.estimate_gravity ? 3 : 0);
  if (config_.estimate_rotor_offset) {
    inv_sigma(next++) = 1.0 / config_.initial_rotor_offset_sigma_rad;
    blocks.push_back(RotorRef());
    x0.push_back(Eigen::VectorXd::Zero(kRotorOffsetBlockSize));
  }
  if (config_.estimate_time_offset) {
    inv_sigma(next++) = 1.0 / config_.initial_time_offset_sigma_s;
    blocks.push_back(TimeRef());
    x0.push_back(Eigen::VectorXd::Zero(kImuTimeOffsetBlockSize));
  }
  prior_ = std::make_unique<LinearizedPriorFactor>(std::move(blocks), std::move(x0),
                                                   Eigen::MatrixXd(inv_sigma.asDiagonal()), Eigen::VectorXd::Zero(n));
  states_.push_back(std::move(s));
  return Status::Ok();
}

Status SlidingWindow::AddState(Seconds t_s, const PreintegratedImu& imu_from_previous,
                               const std::optional<LidarPoseMeasurement>& lidar) {
  std::ostringstream os;
  os.precision(17);
  if (!initialized()) return Status::Error("SlidingWindow::AddState: not initialised (call Initialize first)");
  const Seconds t_prev = latest_time_s();
  if (!(t_s > t_prev) || !std::isfinite(t_s)) {
    os << "SlidingWindow::AddState: t_s = " << t_s << " s is not after the latest state (" << t_prev << " s)";
    return Status::Error(os.str());
  }
  if (imu_from_previous.num_steps() == 0)
    return Status::Error("SlidingWindow::AddState: imu_from_previous holds no IMU step");
  if (std::abs(imu_from_previous.dt_s() - (t_s - t_prev)) > config_.max_dt_mismatch_s) {
    os << "SlidingWindow::AddState: imu_from_previous spans " << imu_from_previous.dt_s() << " s but the states are "
       << (t_s - t_prev) << " s apart (max_dt_mismatch_s = " << config_.max_dt_mismatch_s << ")";
    return Status::Error(os.str());
  }
  if (lidar && !Finite(*lidar)) return Status::Error("SlidingWindow::AddState: the LiDAR measurement is not finite");

  if (size() >= config_.window_size) SlideOut();
  auto s = std::make_unique<State>();
  s->t_s = t_s;
  PackImuState(imu_from_previous.Predict(latest_state(), gravity_world_mps2()), s->pose, s->speed_bias);
  s->imu.emplace(imu_from_previous);
  s->imu_factor = MakeImuFactor(*s->imu);
  if (lidar) s->lidar = MakeLidarFactor(*lidar);
  states_.push_back(std::move(s));
  return Status::Ok();
}

void SlidingWindow::SlideOut() {
  if (config_.marginalization == MarginalizationScheme::kSchurComplement) {
    const Status st = MarginalizeOldest();
    if (!st.ok) {
      LOG_WARN(st.message << "; dropping the oldest state without a prior");
      prior_.reset();
    }
  } else {
    prior_.reset();  // the only prior sits on the dropped state
  }
  if (visual_) visual_->RemoveState(states_.front()->pose);
  states_.pop_front();
  states_.front()->imu.reset();  // the interval into the new oldest state left with the dropped state
  states_.front()->imu_factor.reset();
  ++num_marginalized_;
}

// With estimate_gravity the window treats gravity as constant over its span and as a random walk between the
// marginalised past and the window: the factors being folded (prior, oldest IMU interval) are re-pointed at a
// copy gravity_past_, tied to the window's gravity by (g - g_past) / (q |g| sqrt(dt)) over the oldest interval,
// and gravity_past_ is marginalised with the oldest state. The prior thus carries gravity (and its correlation
// with the kept state), and information older by T is diluted by q^2 T, so gravity can follow the map's tilt.
// The rotor and time offsets are random walks in the same way.
std::vector<MarginalizationTerm> SlidingWindow::TermsOfOldest() {
  auto to_past = [&](std::vector<BlockRef> blocks) {
    for (BlockRef& b : blocks) {
      if (b.values == gravity_) b.values = gravity_past_;
      if (b.values == rotor_) b.values = rotor_past_;
      if (b.values == time_) b.values = time_past_;
    }
    return blocks;
  };
  std::vector<MarginalizationTerm> terms;
  State& oldest = *states_[0];
  if (prior_) terms.push_back({prior_.get(), nullptr, to_past(prior_->blocks())});
  if (oldest.lidar) terms.push_back({oldest.lidar.get(), lidar_loss_.get(), to_past(LidarBlocks(oldest))});
  State& next = *states_[1];
  std::vector<BlockRef> imu_blocks = {oldest.PoseRef(), oldest.SpeedBiasRef(), next.PoseRef(), next.SpeedBiasRef()};
  if (config_.estimate_gravity) imu_blocks.push_back(GravityRef());
  terms.push_back({next.imu_factor.get(), nullptr, to_past(std::move(imu_blocks))});
  AddRandomWalkTerms(next.t_s - oldest.t_s, &terms);
  return terms;
}

void SlidingWindow::AddRandomWalkTerms(double dt_s, std::vector<MarginalizationTerm>* terms) {
  auto walk = [&](const BlockRef& now, double* past_values, double sigma, std::unique_ptr<LinearizedPriorFactor>* f) {
    std::copy(now.values, now.values + now.size, past_values);
    const BlockRef past{past_values, BlockKind::kVector, now.size};
    *f = RandomWalk(past, now, sigma);
    terms->push_back({f->get(), nullptr, {past, now}});
  };
  const double sqrt_dt = std::sqrt(dt_s);
  if (config_.estimate_gravity) {
    const double g = Eigen::Map<const Eigen::Vector3d>(gravity_).norm();
    walk(GravityRef(), gravity_past_, config_.gravity_random_walk_rad_per_sqrt_s * g * sqrt_dt, &gravity_walk_);
  }
  if (config_.estimate_rotor_offset)
    walk(RotorRef(), rotor_past_, config_.rotor_offset_random_walk_rad_per_sqrt_s * sqrt_dt, &rotor_walk_);
  if (config_.estimate_time_offset)
    walk(TimeRef(), time_past_, config_.time_offset_random_walk_s_per_sqrt_s * sqrt_dt, &time_walk_);
}

Status SlidingWindow::MarginalizeOldest() {
  State& oldest = *states_[0];
  std::vector<const double*> dropped = {oldest.pose, oldest.speed_bias};
  if (config_.estimate_gravity) dropped.push_back(gravity_past_);
  if (config_.estimate_rotor_offset) dropped.push_back(rotor_past_);
  if (config_.estimate_time_offset) dropped.push_back(time_past_);
  std::vector<MarginalizationTerm> terms = TermsOfOldest();
  if (visual_) {  // the landmarks anchored at the oldest state leave with it (VINS-Mono's marginalisation)
    std::vector<MarginalizationTerm> visual = visual_->TermsOf(oldest.pose, &dropped);
    terms.insert(terms.end(), visual.begin(), visual.end());
  }
  MarginalizationResult m = Marginalize(terms, dropped);
  gravity_walk_.reset();
  rotor_walk_.reset();
  time_walk_.reset();
  if (!m.success) return Status::Error("SlidingWindow: marginalisation failed: " + m.message);
  prior_ = std::move(m.prior);
  return Status::Ok();
}

WindowResult SlidingWindow::Optimize() {
  WindowResult result;
  result.num_states = size();
  if (!initialized()) {
    result.message = "SlidingWindow::Optimize: no state (call Initialize first)";
    return result;
  }
  ceres::Problem::Options problem_options;  // the window owns every factor, loss and manifold
  problem_options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  for (const auto& s : states_) {
    problem.AddParameterBlock(s->pose, kImuPoseBlockSize, pose_manifold_.get());
    problem.AddParameterBlock(s->speed_bias, kImuSpeedBiasBlockSize);
  }
  if (config_.estimate_gravity) problem.AddParameterBlock(gravity_, kGravityBlockSize, gravity_manifold_.get());
  if (config_.estimate_rotor_offset) problem.AddParameterBlock(rotor_, kRotorOffsetBlockSize);
  if (config_.estimate_time_offset) problem.AddParameterBlock(time_, kImuTimeOffsetBlockSize);
  if (prior_) problem.AddResidualBlock(prior_.get(), nullptr, prior_->block_values());
  for (size_t k = 0; k < states_.size(); ++k) {
    State& s = *states_[k];
    if (s.lidar) {
      std::vector<double*> blocks;
      for (const BlockRef& b : LidarBlocks(s)) blocks.push_back(b.values);
      problem.AddResidualBlock(s.lidar.get(), lidar_loss_.get(), blocks);
    }
    if (k == 0) continue;
    State& prev = *states_[k - 1];
    std::vector<double*> blocks = {prev.pose, prev.speed_bias, s.pose, s.speed_bias};
    if (config_.estimate_gravity) blocks.push_back(gravity_);
    problem.AddResidualBlock(s.imu_factor.get(), nullptr, blocks);
  }
  if (visual_) visual_->AddToProblem(&problem);
  ceres::Solver::Summary summary;
  ceres::Solve(config_.SolverOptions(), &problem, &summary);
  if (visual_) visual_->RejectOutliers();
  result.converged = summary.termination_type == ceres::CONVERGENCE;
  result.iterations = static_cast<int>(summary.iterations.size()) - 1;  // iteration 0 is the initial evaluation
  result.initial_cost = summary.initial_cost;
  result.final_cost = summary.final_cost;
  result.solve_time_s = summary.total_time_in_seconds;
  result.message = summary.BriefReport();
  result.repropagated_intervals = RepropagateMovedIntervals();
  return result;
}

int SlidingWindow::RepropagateMovedIntervals() {
  int count = 0;
  for (size_t k = 1; k < states_.size(); ++k) {
    State& s = *states_[k];
    const NavState prev = UnpackImuState(states_[k - 1]->pose, states_[k - 1]->speed_bias);
    if ((prev.bias_gyro_radps - s.imu->bias_gyro_radps()).norm() <= config_.repropagate_gyro_bias_radps &&
        (prev.bias_accel_mps2 - s.imu->bias_accel_mps2()).norm() <= config_.repropagate_accel_bias_mps2) {
      continue;
    }
    s.imu->Repropagate(prev.bias_gyro_radps, prev.bias_accel_mps2);
    s.imu_factor = MakeImuFactor(*s.imu);
    ++count;
  }
  return count;
}

Seconds SlidingWindow::latest_time_s() const {
  ROTOLIDAR_CHECK(initialized(), "SlidingWindow has no state");
  return states_.back()->t_s;
}

NavState SlidingWindow::latest_state() const {
  ROTOLIDAR_CHECK(initialized(), "SlidingWindow has no state");
  return UnpackImuState(states_.back()->pose, states_.back()->speed_bias);
}

std::vector<WindowStateEstimate> SlidingWindow::states() const {
  std::vector<WindowStateEstimate> out;
  for (const auto& s : states_) {
    out.push_back({s->t_s, UnpackImuState(s->pose, s->speed_bias), s->lidar != nullptr});
  }
  return out;
}

NavState SlidingWindow::PredictFromLatest(const PreintegratedImu& imu_since_latest) const {
  return imu_since_latest.Predict(latest_state(), gravity_world_mps2());
}

}  // namespace rotolidar
