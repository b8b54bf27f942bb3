#include "core/backend/imu_init.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <utility>

#include <Eigen/Dense>

namespace rotolidar {

namespace {

ImuInitResult Fail(ImuInitResult r, const std::string& reason) {
  r.success = false;
  r.reason = reason;
  return r;
}

std::string Num(double x) {
  std::ostringstream os;
  os.precision(4);
  os << x;
  return os.str();
}

/// Per-axis mean and maximum per-axis standard deviation of a set of vectors.
void MeanAndMaxStd(const std::vector<Eigen::Vector3d>& xs, Eigen::Vector3d* mean, double* max_std) {
  *mean = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& x : xs) *mean += x;
  *mean /= static_cast<double>(xs.size());
  Eigen::Vector3d var = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& x : xs) var += (x - *mean).cwiseAbs2();
  *max_std = (var / static_cast<double>(xs.size())).cwiseSqrt().maxCoeff();
}

/// The means of consecutive blocks of `block_s` seconds from `t0_s` (samples binned by their time), or the
/// samples themselves when block_s is 0: the still test's low-pass (ImuInitConfig::static_block_s). A block with
/// less than half the samples of the fullest one (the window's ragged ends) is left out: its mean would keep
/// the vibration the blocks average away.
std::vector<Eigen::Vector3d> BlockMeans(const std::vector<double>& t_s, const std::vector<Eigen::Vector3d>& xs,
                                        double t0_s, double block_s) {
  if (block_s <= 0.0) return xs;
  std::vector<std::pair<Eigen::Vector3d, int>> blocks;  // sum, count
  long block = 0;
  for (size_t k = 0; k < xs.size(); ++k) {
    const long b = static_cast<long>(std::floor((t_s[k] - t0_s) / block_s));
    if (blocks.empty() || b != block) blocks.emplace_back(Eigen::Vector3d::Zero(), 0);
    block = b;
    blocks.back().first += xs[k];
    ++blocks.back().second;
  }
  int fullest = 0;
  for (const auto& b : blocks) fullest = std::max(fullest, b.second);
  std::vector<Eigen::Vector3d> means;
  for (const auto& b : blocks)
    if (2 * b.second >= fullest) means.push_back(b.first / b.second);
  return means;
}

/// The per-axis max standard deviation of gyro and accelerometer for the still test, over block means, and the
/// factor the thresholds are taken with: 1. Under two blocks (a run's first scans) no block spread exists; the
/// samples' own spread is then judged against kShortSpanThresholdFactor x the thresholds, which a standing rig's
/// stepper shake passes (harsh twin: 0.40 m/s^2, 0.01 rad/s per sample) and a walk does not (2.3 m/s^2,
/// 0.17 rad/s).
constexpr double kShortSpanThresholdFactor = 4.0;
double StillSpread(const std::vector<double>& t_s, const std::vector<Eigen::Vector3d>& gyro,
                   const std::vector<Eigen::Vector3d>& accel, const ImuInitConfig& config, double* gyro_std,
                   double* accel_std) {
  const std::vector<Eigen::Vector3d> g = BlockMeans(t_s, gyro, t_s.front(), config.static_block_s);
  const std::vector<Eigen::Vector3d> a = BlockMeans(t_s, accel, t_s.front(), config.static_block_s);
  const bool blocks = g.size() >= 2;
  Eigen::Vector3d unused;
  MeanAndMaxStd(blocks ? g : gyro, &unused, gyro_std);
  MeanAndMaxStd(blocks ? a : accel, &unused, accel_std);
  return blocks || config.static_block_s <= 0.0 ? 1.0 : kShortSpanThresholdFactor;
}

/// Gyro bias from the LiDAR rotations (VINS-Mono solveGyroscopeBias): minimises sum |Log(dR(bg)^T R_k^T R_k+1)|^2
/// with dR(bg) = dR Exp(dR_dbg (bg - bg_lin)), by Gauss-Newton steps with re-integration at each new bias.
Eigen::Vector3d SolveGyroBias(const std::vector<Pose3>& T, std::vector<PreintegratedImu>* pre, int iterations,
                              double* rms_rad) {
  Eigen::Vector3d bg = (*pre)[0].bias_gyro_radps();
  const Eigen::Vector3d ba = (*pre)[0].bias_accel_mps2();
  for (PreintegratedImu& p : *pre) p.Repropagate(bg, ba);  // one common linearisation point
  for (int it = 0; it < iterations; ++it) {
    Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    for (size_t k = 0; k < pre->size(); ++k) {
      // r(d) = Log(Exp(-J d) E) ~= e - J d for small e = Log(dR^T R_k^T R_k+1), J = dR_dbg.
      const Eigen::Vector3d e =
          LogSO3((*pre)[k].delta_R().transpose() * T[k].linear().transpose() * T[k + 1].linear());
      const Eigen::Matrix3d& J = (*pre)[k].dR_dbg();
      A += J.transpose() * J;
      b += J.transpose() * e;
    }
    bg += A.ldlt().solve(b);
    for (PreintegratedImu& p : *pre) p.Repropagate(bg, ba);
  }
  double sum_sq = 0.0;
  for (size_t k = 0; k < pre->size(); ++k) {
    sum_sq += LogSO3((*pre)[k].delta_R().transpose() * T[k].linear().transpose() * T[k + 1].linear()).squaredNorm();
  }
  *rms_rad = std::sqrt(sum_sq / static_cast<double>(pre->size()));
  return bg;
}

/// Linear least squares for velocities v_0..v_N-1 and gravity g = g0 + B y (odometry frame). Per interval k:
///   (p_k+1 - p_k - R_k dp_k) / T = v_k + T/2 g        (position, divided by T to read in m/s)
///   R_k dv_k                     = v_k+1 - v_k - T g   (velocity)
/// Returns false when the system is rank-deficient.
bool SolveVelocityGravity(const std::vector<Pose3>& T, const std::vector<PreintegratedImu>& pre,
                          const Eigen::Vector3d& g0, const Eigen::MatrixXd& B, std::vector<Eigen::Vector3d>* v,
                          Eigen::Vector3d* g) {
  const int n_poses = static_cast<int>(T.size()), m = static_cast<int>(B.cols());
  const int cols = 3 * n_poses + m;
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(6 * (n_poses - 1), cols);
  Eigen::VectorXd rhs(6 * (n_poses - 1));
  for (int k = 0; k + 1 < n_poses; ++k) {
    const double dt = pre[k].dt_s();
    const Eigen::Matrix3d& Rk = T[k].linear();
    const int row = 6 * k;
    A.block<3, 3>(row, 3 * k) = Eigen::Matrix3d::Identity();
    A.block(row, 3 * n_poses, 3, m) = 0.5 * dt * B;
    rhs.segment<3>(row) = (T[k + 1].translation() - T[k].translation() - Rk * pre[k].delta_p_m()) / dt - 0.5 * dt * g0;
    A.block<3, 3>(row + 3, 3 * k) = -Eigen::Matrix3d::Identity();
    A.block<3, 3>(row + 3, 3 * (k + 1)) = Eigen::Matrix3d::Identity();
    A.block(row + 3, 3 * n_poses, 3, m) = -dt * B;
    rhs.segment<3>(row + 3) = Rk * pre[k].delta_v_mps() + dt * g0;
  }
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
  if (qr.rank() < cols) return false;
  const Eigen::VectorXd x = qr.solve(rhs);
  v->resize(n_poses);
  for (int k = 0; k < n_poses; ++k) (*v)[k] = x.segment<3>(3 * k);
  *g = g0 + B * x.tail(m);
  return x.allFinite();
}

/// Two unit vectors spanning the plane orthogonal to unit u.
Eigen::Matrix<double, 3, 2> TangentBasis(const Eigen::Vector3d& u) {
  const Eigen::Vector3d helper = std::abs(u.z()) < 0.9 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitX();
  Eigen::Matrix<double, 3, 2> B;
  B.col(0) = u.cross(helper).normalized();
  B.col(1) = u.cross(B.col(0));
  return B;
}

}  // namespace

bool ImuInitConfig::Validate(std::string* error) const {
  auto fail = [&](const std::string& m) {
    if (error) *error = "imu_init." + m;
    return false;
  };
  auto positive = [](double x) { return x > 0.0 && std::isfinite(x); };
  if (!positive(gravity_mps2)) return fail("gravity_mps2 must be > 0");
  if (!positive(static_window_s)) return fail("static_window_s must be > 0");
  if (static_min_samples < 2) return fail("static_min_samples must be >= 2");
  if (!positive(static_max_gyro_std_radps)) return fail("static_max_gyro_std_radps must be > 0");
  if (!positive(static_max_accel_std_mps2)) return fail("static_max_accel_std_mps2 must be > 0");
  if (!(static_block_s >= 0.0) || !std::isfinite(static_block_s))
    return fail("static_block_s must be >= 0 (0: per sample)");
  if (static_block_s > 0.5 * static_window_s)
    return fail("static_block_s must be <= static_window_s / 2 (the spread needs two blocks)");
  if (!positive(still_max_gyro_mean_radps)) return fail("still_max_gyro_mean_radps must be > 0");
  if (!positive(max_gravity_error_mps2)) return fail("max_gravity_error_mps2 must be > 0");
  if (moving_min_poses < 3) return fail("moving_min_poses must be >= 3 (fewer leave velocity and gravity free)");
  if (gyro_bias_iterations < 1) return fail("gyro_bias_iterations must be >= 1");
  if (gravity_refine_iterations < 0) return fail("gravity_refine_iterations must be >= 0");
  return true;
}

ImuInitResult InitializeStatic(const std::vector<ImuSample>& samples, const ImuInitConfig& config) {
  ImuInitResult r;
  std::string error;
  if (!config.Validate(&error)) return Fail(r, error);
  if (samples.empty()) return Fail(r, "static init: no IMU samples");
  const double t0 = samples.front().t_s, t_end = t0 + config.static_window_s;
  std::vector<Eigen::Vector3d> gyro, accel;
  std::vector<double> times;
  for (size_t k = 0; k < samples.size() && samples[k].t_s <= t_end; ++k) {
    if (!samples[k].gyro_radps.allFinite() || !samples[k].accel_mps2.allFinite() || !std::isfinite(samples[k].t_s))
      return Fail(r, "static init: IMU sample " + std::to_string(k) + " is not finite");
    if (k > 0 && !(samples[k].t_s > samples[k - 1].t_s))
      return Fail(r, "static init: IMU sample " + std::to_string(k) + " is not after the previous one");
    gyro.push_back(samples[k].gyro_radps);
    accel.push_back(samples[k].accel_mps2);
    times.push_back(samples[k].t_s);
    r.t_s = samples[k].t_s;
  }
  if (samples.back().t_s < t_end)
    return Fail(r, "static init: the samples span " + Num(samples.back().t_s - t0) + " s < static_window_s = " +
                       Num(config.static_window_s) + " s");
  if (static_cast<int>(gyro.size()) < config.static_min_samples)
    return Fail(r, "static init: " + std::to_string(gyro.size()) + " samples in the window < static_min_samples");
  Eigen::Vector3d mean_gyro, mean_accel;
  double gyro_std = 0.0, accel_std = 0.0;
  MeanAndMaxStd(gyro, &mean_gyro, &gyro_std);
  MeanAndMaxStd(accel, &mean_accel, &accel_std);
  // The window spans static_window_s >= 2 blocks (Validate), so the spreads are over block means.
  StillSpread(times, gyro, accel, config, &gyro_std, &accel_std);
  r.bias_gyro_radps = mean_gyro;
  r.gravity_residual_mps2 = std::abs(mean_accel.norm() - config.gravity_mps2);
  if (gyro_std > config.static_max_gyro_std_radps)
    return Fail(r, "static init: not still: gyro std " + Num(gyro_std) + " rad/s > static_max_gyro_std_radps");
  if (accel_std > config.static_max_accel_std_mps2)
    return Fail(r, "static init: not still: accel std " + Num(accel_std) + " m/s^2 > static_max_accel_std_mps2");
  if (r.gravity_residual_mps2 > config.max_gravity_error_mps2)
    return Fail(r, "static init: |mean accel| = " + Num(mean_accel.norm()) + " m/s^2 is " +
                       Num(r.gravity_residual_mps2) + " from gravity_mps2 (> max_gravity_error_mps2)");
  // At rest accel = R^T (0, 0, g) with R = Rz(yaw) Ry(pitch) Rx(roll): g (-sin p, cos p sin r, cos p cos r).
  const Eigen::Vector3d& f = mean_accel;
  const double roll = std::atan2(f.y(), f.z());
  const double pitch = std::atan2(-f.x(), std::hypot(f.y(), f.z()));
  r.R_world_imu = (Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                   Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX())).toRotationMatrix();
  r.velocities_world_mps = {Eigen::Vector3d::Zero()};
  NavState s;
  s.R_world_imu = r.R_world_imu;
  s.bias_gyro_radps = r.bias_gyro_radps;
  r.states = {s};
  r.success = true;
  return r;
}

bool ImuIsStill(const std::vector<ImuSample>& samples, Seconds t0_s, Seconds t1_s, const ImuInitConfig& config,
                std::string* why) {
  auto no = [&](const std::string& m) {
    if (why) *why = m;
    return false;
  };
  std::vector<Eigen::Vector3d> gyro, accel;
  std::vector<double> times;
  for (const ImuSample& s : samples) {
    if (s.t_s < t0_s || s.t_s > t1_s) continue;
    if (!s.gyro_radps.allFinite() || !s.accel_mps2.allFinite()) return no("a sample is not finite");
    gyro.push_back(s.gyro_radps);
    accel.push_back(s.accel_mps2);
    times.push_back(s.t_s);
  }
  if (static_cast<int>(gyro.size()) < config.static_min_samples)
    return no(std::to_string(gyro.size()) + " samples < static_min_samples");
  Eigen::Vector3d mean_gyro, mean_accel;
  double gyro_std = 0.0, accel_std = 0.0;
  MeanAndMaxStd(gyro, &mean_gyro, &gyro_std);
  MeanAndMaxStd(accel, &mean_accel, &accel_std);
  const double factor = StillSpread(times, gyro, accel, config, &gyro_std, &accel_std);
  if (gyro_std > factor * config.static_max_gyro_std_radps) return no("gyro std " + Num(gyro_std) + " rad/s");
  if (accel_std > factor * config.static_max_accel_std_mps2) return no("accel std " + Num(accel_std) + " m/s^2");
  if (mean_gyro.norm() > config.still_max_gyro_mean_radps) return no("|mean gyro| " + Num(mean_gyro.norm()) + " rad/s");
  if (std::abs(mean_accel.norm() - config.gravity_mps2) > config.max_gravity_error_mps2)
    return no("|mean accel| " + Num(mean_accel.norm()) + " m/s^2");
  return true;
}

ImuInitResult InitializeMoving(const std::vector<Pose3>& T_odom_imu, const std::vector<PreintegratedImu>& imu_between,
                               const ImuInitConfig& config) {
  ImuInitResult r;
  std::string error;
  if (!config.Validate(&error)) return Fail(r, error);
  const int n = static_cast<int>(T_odom_imu.size());
  if (n < config.moving_min_poses)
    return Fail(r, "moving init: " + std::to_string(n) + " poses < moving_min_poses = " +
                       std::to_string(config.moving_min_poses));
  if (static_cast<int>(imu_between.size()) != n - 1)
    return Fail(r, "moving init: imu_between has " + std::to_string(imu_between.size()) + " intervals, expected " +
                       std::to_string(n - 1));
  for (int k = 0; k < n; ++k) {
    if (!T_odom_imu[k].matrix().allFinite())
      return Fail(r, "moving init: pose " + std::to_string(k) + " is not finite");
    if (k + 1 < n && imu_between[k].num_steps() == 0)
      return Fail(r, "moving init: imu_between[" + std::to_string(k) + "] holds no IMU step");
  }
  std::vector<PreintegratedImu> pre = imu_between;
  r.bias_gyro_radps = SolveGyroBias(T_odom_imu, &pre, config.gyro_bias_iterations, &r.rotation_residual_rad);
  r.bias_accel_mps2 = pre[0].bias_accel_mps2();

  std::vector<Eigen::Vector3d> v;
  Eigen::Vector3d g;
  if (!SolveVelocityGravity(T_odom_imu, pre, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity(), &v, &g))
    return Fail(r, "moving init: the velocity/gravity system is rank-deficient");
  const double g_lsq_norm = g.norm();
  r.gravity_residual_mps2 = std::abs(g_lsq_norm - config.gravity_mps2);
  for (int it = 0; it < config.gravity_refine_iterations; ++it) {  // |g| known: solve on its tangent plane
    const Eigen::Vector3d g0 = g.normalized() * config.gravity_mps2;
    if (!SolveVelocityGravity(T_odom_imu, pre, g0, TangentBasis(g0.normalized()), &v, &g))
      return Fail(r, "moving init: the gravity refinement is rank-deficient");
  }
  g = g.normalized() * config.gravity_mps2;
  r.gravity_odom_mps2 = g;
  r.R_world_odom = Eigen::Quaterniond::FromTwoVectors(g, -Eigen::Vector3d::UnitZ()).toRotationMatrix();
  r.R_world_imu = r.R_world_odom * T_odom_imu[0].linear();
  for (int k = 0; k < n; ++k) {
    r.velocities_world_mps.push_back(r.R_world_odom * v[k]);
    NavState s;
    s.R_world_imu = r.R_world_odom * T_odom_imu[k].linear();
    s.p_world_m = r.R_world_odom * T_odom_imu[k].translation();
    s.v_world_mps = r.velocities_world_mps.back();
    s.bias_gyro_radps = r.bias_gyro_radps;
    s.bias_accel_mps2 = r.bias_accel_mps2;
    r.states.push_back(s);
  }
  if (r.gravity_residual_mps2 > config.max_gravity_error_mps2)
    return Fail(r, "moving init: the least-squares gravity has |g| = " + Num(g_lsq_norm) + " off by " +
                       Num(r.gravity_residual_mps2) + " m/s^2 (> max_gravity_error_mps2)");
  r.success = true;
  return r;
}

}  // namespace rotolidar
