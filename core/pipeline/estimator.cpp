#include "core/pipeline/estimator.hpp"

#include <algorithm>
#include <chrono>

namespace rotolidar {
namespace {

Vlp16DecoderConfig DecoderConfigFor(const RigCalib& calib) {
  Vlp16DecoderConfig c;
  c.min_range_m = calib.lidar.min_range_m;
  c.max_range_m = calib.lidar.max_range_m;
  c.lidar_clock_offset_s = calib.lidar_clock_offset_s;
  return c;
}

/// exp of a twist scaled by s: interpolates the relative motion `delta` at fraction s (constant velocity).
Pose3 ScaleMotion(const Pose3& delta, double s) {
  Pose3 out = Pose3::Identity();
  out.linear() = ExpSO3(s * LogSO3(delta.linear()));
  out.translation() = s * delta.translation();
  return out;
}

}  // namespace

Estimator::Estimator(const RigCalib& calib, const EstimatorConfig& config)
    : calib_(calib),
      config_(config),
      decoder_(calib_.lidar, DecoderConfigFor(calib_)),
      splitter_(config.cut_azimuth_deg),
      rotor_(calib_),
      matcher_(config.registration),
      local_map_(config.local_map_voxel_m, config.local_map_points_per_voxel),
      dense_map_(config.output_map_voxel_m, config.output_map_points_per_voxel) {
  std::string why;
  ROTOLIDAR_CHECK(calib_.Validate(&why), why);
  ROTOLIDAR_CHECK(config_.Validate(&why), why);
}

void Estimator::Feed(const EncoderSample& sample) { rotor_.Add(sample); }

void Estimator::Feed(const ImuSample& sample) {
  if (imu_.empty() || sample.t_s > imu_.back().t_s) imu_.push_back(sample);
}

Status Estimator::Feed(const LidarPacket& packet) {
  packet_points_.clear();
  if (Status s = decoder_.Decode(packet, &packet_points_); !s) {
    ++bad_packets_;
    return s;
  }
  std::vector<LidarScan> completed;
  splitter_.Add(packet_points_, &completed);
  for (auto& scan : completed) pending_scans_.push_back(std::move(scan));
  return Status::Ok();
}

std::vector<ScanReport> Estimator::Process() {
  std::vector<ScanReport> reports;
  while (!pending_scans_.empty() && !rotor_.empty()) {
    // Wait until the encoder has covered the scan (or data ends: Finish).
    if (rotor_.last_time_s() < pending_scans_.front().t_end_s) break;
    reports.push_back(ProcessScan(pending_scans_.front()));
    pending_scans_.pop_front();
  }
  return reports;
}

std::vector<ScanReport> Estimator::Finish() {
  if (auto last = splitter_.Flush()) pending_scans_.push_back(std::move(*last));
  std::vector<ScanReport> reports;
  while (!pending_scans_.empty()) {
    reports.push_back(ProcessScan(pending_scans_.front()));
    pending_scans_.pop_front();
  }
  return reports;
}

// The main step: rotary transform -> deskew -> preprocess -> register -> map.
ScanReport Estimator::ProcessScan(const LidarScan& scan) {
  const auto t0 = std::chrono::steady_clock::now();
  ScanReport report;
  report.t_start_s = scan.t_start_s;
  report.t_end_s = scan.t_end_s;
  report.num_points = scan.points.size();

  std::vector<Eigen::Vector3d> p_base;  // each point in the base frame at its own time
  report.num_rotor_fallback = LidarToBase(calib_, rotor_, scan, &p_base);
  const std::vector<Eigen::Vector3d> p_start = DeskewToScanStart(scan, p_base);
  const std::vector<Eigen::Vector3d> p_source = Preprocess(p_start);
  report.num_registered = p_source.size();

  Pose3 T_world_base = PredictPose(scan.t_start_s);
  if (!local_map_.Empty()) {
    report.registration = matcher_.Align(p_source, T_world_base);
    if (report.registration.converged) T_world_base = report.registration.T_target_source;
  } else {
    report.registration.converged = true;  // the first scan defines the world frame
  }
  report.T_world_base = T_world_base;
  trajectory_.push_back({scan.t_start_s, T_world_base});
  UpdateMap(T_world_base, p_start);
  rotor_.DropBefore(scan.t_end_s - 1.0);
  while (imu_.size() > 2 && imu_[1].t_s < scan.t_start_s - 1.0) imu_.pop_front();
  report.process_time_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return report;
}

// Carrier motion during the scan: each point is moved into the base frame at the scan's start time. Rotation
// comes from the integrated gyro (exact to the gyro's noise), translation from the last two poses (constant
// velocity). M1-5 replaces the translation part with IMU preintegration.
std::vector<Eigen::Vector3d> Estimator::DeskewToScanStart(const LidarScan& scan,
                                                          const std::vector<Eigen::Vector3d>& p_base) const {
  Eigen::Vector3d v_base_per_s = Eigen::Vector3d::Zero();  // translation rate in the start frame [m/s]
  Pose3 delta = Pose3::Identity();
  double dt = 0.0;
  if (trajectory_.size() >= 2) {
    const StampedPose& a = trajectory_[trajectory_.size() - 2];
    const StampedPose& b = trajectory_.back();
    dt = b.t_s - a.t_s;
    if (dt > 0) {
      delta = a.T_ref_body.inverse() * b.T_ref_body;
      v_base_per_s = delta.translation() / dt;
    }
  }
  const std::vector<std::pair<Seconds, Eigen::Matrix3d>> gyro = GyroRotations(scan.t_start_s, scan.t_end_s);
  std::vector<Eigen::Vector3d> out(p_base.size());
  size_t k = 0;
  for (size_t i = 0; i < p_base.size(); ++i) {
    const Seconds t = scan.points[i].t_s;
    Eigen::Matrix3d R_start_t;
    if (!gyro.empty()) {
      while (k + 1 < gyro.size() && gyro[k + 1].first <= t) ++k;
      const Eigen::Matrix3d& R_k = gyro[k].second;
      Eigen::Vector3d w_next = Eigen::Vector3d::Zero();  // rate to the next table entry [rad/s]
      if (k + 1 < gyro.size())
        w_next = LogSO3(R_k.transpose() * gyro[k + 1].second) / (gyro[k + 1].first - gyro[k].first);
      R_start_t = R_k * ExpSO3(w_next * (t - gyro[k].first));
    } else {
      R_start_t = Eigen::Matrix3d::Identity();
      if (dt > 0) R_start_t = ScaleMotion(delta, (t - scan.t_start_s) / dt).linear();
    }
    out[i] = R_start_t * p_base[i] + v_base_per_s * (t - scan.t_start_s);
  }
  return out;
}

std::vector<Eigen::Vector3d> Estimator::Preprocess(const std::vector<Eigen::Vector3d>& p_base) const {
  std::vector<Eigen::Vector3d> kept;
  kept.reserve(p_base.size());
  const double min_sq = config_.min_range_m * config_.min_range_m, max_sq = config_.max_range_m * config_.max_range_m;
  for (const auto& p : p_base) {
    const double r_sq = p.squaredNorm();
    if (r_sq >= min_sq && r_sq <= max_sq) kept.push_back(p);
  }
  return VoxelDownsample(kept, config_.scan_voxel_m);
}

// Constant-velocity prediction of the base pose at t, with the rotation from the gyro where IMU data covers it.
Pose3 Estimator::PredictPose(Seconds t_s) const {
  if (trajectory_.empty()) return Pose3::Identity();
  const StampedPose& b = trajectory_.back();
  Pose3 delta = Pose3::Identity();
  if (trajectory_.size() >= 2) {
    const StampedPose& a = trajectory_[trajectory_.size() - 2];
    const double dt = b.t_s - a.t_s;
    if (dt > 0) delta = ScaleMotion(a.T_ref_body.inverse() * b.T_ref_body, (t_s - b.t_s) / dt);
  }
  if (const auto R_gyro = GyroRotation(b.t_s, t_s)) delta.linear() = *R_gyro;
  return b.T_ref_body * delta;
}

// R_base(t0)_base(t_k) at t0 and at each IMU sample time in (t0, t1], from the integrated gyro; empty when the
// IMU buffer does not cover [t0, t1].
std::vector<std::pair<Seconds, Eigen::Matrix3d>> Estimator::GyroRotations(Seconds t0_s, Seconds t1_s) const {
  std::vector<std::pair<Seconds, Eigen::Matrix3d>> out;
  if (imu_.size() < 2 || imu_.front().t_s > t0_s || imu_.back().t_s < t1_s) return out;
  const Eigen::Matrix3d R_base_imu = calib_.T_base_imu.linear();
  Eigen::Matrix3d R_imu0_imu = Eigen::Matrix3d::Identity();
  out.emplace_back(t0_s, Eigen::Matrix3d::Identity());
  for (size_t i = 0; i + 1 < imu_.size() && imu_[i].t_s < t1_s; ++i) {
    const double a = std::max(imu_[i].t_s, t0_s), b = std::min(imu_[i + 1].t_s, t1_s);
    if (b <= a) continue;
    R_imu0_imu = R_imu0_imu * ExpSO3(0.5 * (imu_[i].gyro_radps + imu_[i + 1].gyro_radps) * (b - a));
    out.emplace_back(b, R_base_imu * R_imu0_imu * R_base_imu.transpose());
  }
  return out;
}

// Rotation of the base between t0 and t1: the last entry of the integrated gyro table.
std::optional<Eigen::Matrix3d> Estimator::GyroRotation(Seconds t0_s, Seconds t1_s) const {
  const auto table = GyroRotations(t0_s, t1_s);
  if (table.empty()) return std::nullopt;
  return table.back().second;
}

void Estimator::UpdateMap(const Pose3& T_world_base, const std::vector<Eigen::Vector3d>& p_base) {
  std::vector<Eigen::Vector3d> p_world;
  p_world.reserve(p_base.size());
  const double min_sq = config_.min_range_m * config_.min_range_m, max_sq = config_.max_range_m * config_.max_range_m;
  for (const auto& p : p_base) {
    const double r_sq = p.squaredNorm();
    if (r_sq >= min_sq && r_sq <= max_sq) p_world.push_back(T_world_base * p);
  }
  local_map_.Add(p_world);
  dense_map_.Add(p_world);
  local_map_.RemoveFar(T_world_base.translation(), config_.local_map_radius_m);
  if (++scans_since_target_ >= config_.target_refresh_scans || trajectory_.size() <= 2) {
    matcher_.SetTarget(local_map_.Points());
    scans_since_target_ = 0;
  }
}

}  // namespace rotolidar
