#pragma once
// Recording folders and slam runs -> ROS 1 bags (docs/ros.md), for RViz, rosbag play and the import round trip.
//
// Recording (ExportRecordingToBag):
//   lidar.pcap data packets -> velodyne_msgs/VelodyneScan on lidar_topic (frame "velodyne"), packets_per_scan
//                              packets per message as the velodyne driver groups them; each VelodynePacket stamp =
//                              the packet's capture time, the scan's header stamp = its last packet's (the driver's
//                              convention). Position packets (UDP 8308) have no place in VelodyneScan: dropped.
//   imu.csv    -> sensor_msgs/Imu (frame "imu": the rig's imu frame; no orientation: orientation_covariance[0]=-1)
//   encoder.csv -> sensor_msgs/JointState, joint `joint_name`, position[0] = RigCalib::EncoderAngle(count) [rad]
//   camera     -> sensor_msgs/Image, bgr8 (frame "camera": the optical frame)
// Run (ExportRunToBag): trajectory.tum -> nav_msgs/Odometry (frame "world", child "base") on odom_topic plus the
// same pose on /tf (tf2_msgs/TFMessage); map.ply -> one sensor_msgs/PointCloud2 (x, y, z float32, frame "world")
// on map_topic, latched, stamped at the first pose.
// Times: stamp = epoch + rig time [s], in integer nanoseconds; every message is recorded at its stamp.
#include <cstddef>
#include <string>

#include "core/util/status.hpp"

namespace rotolidar::bench::rosmsg {

/// The Unix time given to rig time 0 when a recording has no epoch (calib.yaml epoch_unix_s 0: sim recordings):
/// 2023-11-14T22:13:20Z. ROS stamps near 1970 (and time 0, which rosbag refuses) are avoided.
inline constexpr double kDefaultBagEpochUnixS = 1700000000.0;

struct BagExportOptions {
  /// Unix time of rig time 0 [s]; < 0: the recording's calib.yaml epoch_unix_s when > 0, else
  /// kDefaultBagEpochUnixS (runs: kDefaultBagEpochUnixS).
  double epoch_unix_s = -1.0;
  /// Packets per VelodyneScan; 0: the driver's ceil(packet rate / revolution rate) = ceil(754 (dual: 1508) per s
  /// / (calib lidar.rpm / 60)), 76 at 600 rpm.
  int packets_per_scan = 0;
  std::string lidar_topic = "/velodyne_packets", imu_topic = "/imu/data", image_topic = "/camera/image_raw";
  std::string encoder_topic = "/joint_states", joint_name = "motor";
  std::string odom_topic = "/rotolidar/odometry", map_topic = "/rotolidar/map";
};

struct BagExportSummary {
  double epoch_unix_s = 0.0;
  std::size_t scans = 0, packets = 0, dropped_position_packets = 0, imu = 0, encoder = 0, images = 0;
  std::size_t poses = 0, map_points = 0;
  std::size_t messages = 0;  ///< written to the bag
};

/// Writes the recording folder `recording_dir` (LoadRecording's checks apply) as `bag_path`.
Status ExportRecordingToBag(const std::string& recording_dir, const std::string& bag_path,
                            const BagExportOptions& options, BagExportSummary* summary);

/// Writes a slam run folder (trajectory.tum required, map.ply optional) as `bag_path`.
Status ExportRunToBag(const std::string& run_dir, const std::string& bag_path, const BagExportOptions& options,
                      BagExportSummary* summary);

}  // namespace rotolidar::bench::rosmsg
