#pragma once
// Private pieces shared by estimator.cpp and estimator_fuse.cpp (not part of the public API).
#include <chrono>
#include <initializer_list>
#include <optional>
#include <vector>

#include "core/deskew/deskew.hpp"
#include "core/imu/preintegration.hpp"
#include "core/pipeline/estimator.hpp"
#include "core/pipeline/free_space.hpp"

namespace rotolidar {

/// Wall-clock stopwatch [ms].
class Stopwatch {
 public:
  Stopwatch() : t0_(std::chrono::steady_clock::now()) {}
  void Restart() { t0_ = std::chrono::steady_clock::now(); }
  double ms() const {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0_).count();
  }

 private:
  std::chrono::steady_clock::time_point t0_;
};

/// The motion prior of one scan: the pose guess at its start and the carrier's motion over it.
struct Estimator::Prediction {
  Pose3 T_world_base = Pose3::Identity();  ///< guess at the scan start
  MotionTable motion;                      ///< T_base(t0)_base(t) over the scan (deskew)
  bool imu_motion = false;                 ///< `motion` integrates the IMU (else constant twist / identity)
  /// [window's latest state, scan start] integrated at the latest state's biases (the window's next IMU factor);
  /// empty before IMU initialisation or without IMU data.
  std::optional<PreintegratedImu> imu_since_latest;
};

/// IMU readings over [t0, t1] (clipped intervals, mean of the two bracketing readings; the first / last reading
/// is held where the samples do not reach t0 / t1) at linearisation biases bg, ba. Empty without samples or
/// when t1 <= t0.
std::optional<PreintegratedImu> PreintegrateSpan(const std::vector<ImuSample>& imu, Seconds t0_s, Seconds t1_s,
                                                 const Eigen::Vector3d& bias_gyro_radps,
                                                 const Eigen::Vector3d& bias_accel_mps2, const ImuNoise& noise);

/// Drops the points of each cloud (base frame at T_world_base, world [m]) that scans before t_s saw through (the
/// free-space test's SeenThroughBefore: they stand where space was seen empty); returns how many in all. The
/// clouds are judged in one pass over the earlier scans' range images.
size_t DropSeenThrough(const FreeSpaceFilter& filter, Seconds t_s, const Pose3& T_world_base,
                       std::initializer_list<pcl::PointCloud<pcl::PointXYZI>*> clouds);
/// Drops the points i of the clouds, counted across them in order, with drop[i] != 0 (drop holds one entry per
/// point of all clouds); returns how many in all.
size_t DropFlagged(const std::vector<uint8_t>& drop, std::initializer_list<pcl::PointCloud<pcl::PointXYZI>*> clouds);
/// The edge and planar features' positions (their frame, [m]), edge first, one per column.
Eigen::Matrix3Xf RegistrationFeatures(const FeatureSet& features);

}  // namespace rotolidar
