#pragma once
// The estimator: sensor messages in, a trajectory of T_world_base and a dense map out.
//
// Feed() every message in time order (LiDAR packets by capture time). Each completed VLP-16 revolution is one
// scan; Process() runs the pipeline on every scan whose encoder coverage has arrived:
//   rotary transform (encoder) -> deskew (carrier motion) -> preprocess -> register to the local map -> map
// This is the M1-1 core (GICP scan-to-map, constant-velocity deskew); issue M1-5 replaces the front and back end
// with the seed's features, Ceres registration and IMU fusion, behind this same interface.
//
// The world frame is the base frame at the first scan's start time.
#include <deque>
#include <memory>
#include <optional>
#include <vector>

#include "core/io/vlp16.hpp"
#include "core/io/scan_splitter.hpp"
#include "core/pipeline/estimator_config.hpp"
#include "core/pipeline/rotary.hpp"
#include "core/pipeline/scan_matcher.hpp"
#include "core/pipeline/voxel_map.hpp"
#include "core/types/trajectory.hpp"

namespace rotolidar {

/// What happened to one scan.
struct ScanReport {
  Seconds t_start_s = 0.0, t_end_s = 0.0;
  size_t num_points = 0;          ///< decoded points in the revolution
  size_t num_registered = 0;      ///< points given to registration after filtering
  size_t num_rotor_fallback = 0;  ///< points placed with the uniform-rotation model (no encoder bracket)
  RegistrationResult registration;
  double process_time_ms = 0.0;   ///< wall time of Process for this scan [ms]
  Pose3 T_world_base = Pose3::Identity();  ///< at t_start_s
};

class Estimator {
 public:
  /// `calib` must be valid; `config` must Validate (both ROTOLIDAR_CHECKed).
  Estimator(const RigCalib& calib, const EstimatorConfig& config);

  void Feed(const EncoderSample& sample);
  void Feed(const ImuSample& sample);
  /// Decodes a data or position packet; a malformed packet is reported and skipped (no points lost silently:
  /// the Status says which field at which offset).
  Status Feed(const LidarPacket& packet);
  /// Processes every ready scan; returns their reports (in time order).
  std::vector<ScanReport> Process();
  /// End of data: flushes the partial last revolution and processes everything left.
  std::vector<ScanReport> Finish();

  const Trajectory& trajectory() const { return trajectory_; }  ///< T_world_base at each scan start
  const VoxelMap& map() const { return dense_map_; }            ///< dense map of deskewed points [world]
  size_t bad_packets() const { return bad_packets_; }

 private:
  ScanReport ProcessScan(const LidarScan& scan);
  std::vector<Eigen::Vector3d> DeskewToScanStart(const LidarScan& scan, const std::vector<Eigen::Vector3d>& p_base) const;
  std::vector<Eigen::Vector3d> Preprocess(const std::vector<Eigen::Vector3d>& p_base) const;
  Pose3 PredictPose(Seconds t_s) const;
  void UpdateMap(const Pose3& T_world_base, const std::vector<Eigen::Vector3d>& p_base);
  /// R_base(t0)_base(t1) from integrated gyro samples; nullopt when the IMU buffer does not cover [t0, t1].
  std::optional<Eigen::Matrix3d> GyroRotation(Seconds t0_s, Seconds t1_s) const;
  /// R_base(t0)_base(t) at t0 and at each IMU sample in (t0, t1]; empty when the IMU does not cover [t0, t1].
  std::vector<std::pair<Seconds, Eigen::Matrix3d>> GyroRotations(Seconds t0_s, Seconds t1_s) const;

  RigCalib calib_;
  EstimatorConfig config_;
  Vlp16Decoder decoder_;
  RevolutionSplitter splitter_;
  RotorAngleInterpolator rotor_;
  std::deque<ImuSample> imu_;
  std::deque<LidarScan> pending_scans_;
  std::vector<LidarPoint> packet_points_;
  ScanMatcher matcher_;
  VoxelMap local_map_;
  VoxelMap dense_map_;
  Trajectory trajectory_;
  int scans_since_target_ = 0;
  size_t bad_packets_ = 0;
};

}  // namespace rotolidar
