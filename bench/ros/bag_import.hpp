#pragma once
// ROS 1 bag -> recording folder (docs/recording_format.md; the mapping is in docs/ros.md):
//   velodyne_msgs/VelodyneScan  each packet's 1206 data bytes -> a lidar.pcap data packet on UDP 2368, captured at
//                               the packet's stamp (position packets are not carried by VelodyneScan)
//   sensor_msgs/PointCloud2     (instead of VelodyneScan) the velodyne driver's clouds in the VLP-16 frame, fields
//                               x, y, z, ring and time [s] or t [ns] relative to header.stamp -> VLP-16 data
//                               packets that decode back to the same points (bench/ros/cloud_to_packets.hpp); the
//                               VLP-16 clock of the recording is then the rig clock (lidar_clock_offset_s 0)
//   sensor_msgs/Imu             angular_velocity [rad/s], linear_acceleration [m/s^2] -> imu.csv; the message's
//                               frame is taken to be the rig's imu frame (calib.yaml T_base_imu); orientation and
//                               covariances are ignored
//   sensor_msgs/Image           rgb8, bgr8, mono8 -> camera.csv + camera/NNNNNN.png (stored BGR8)
//   sensor_msgs/JointState      position[0] [rad] = the rotor angle -> the encoder count whose bin holds it:
//                               count = floor((theta + zero_offset_rad) * counts_per_rev / 2pi) mod counts_per_rev,
//                               the exact inverse of RigCalib::EncoderAngle (bin centres map back to their count)
// Times: the rig clock is stamp - epoch_unix_s, epoch_unix_s = the whole second (floor) of the earliest stamp of
// any imported message (header stamps, VelodynePacket stamps, a cloud's earliest firing sequence), written into the
// output calib.yaml. Stamps are the messages' header stamps, not the bag's record times.
#include <string>

#include "core/util/status.hpp"

namespace rotolidar::bench::rosmsg {

/// How the VLP-16's own clock (microseconds past the hour) maps onto the new rig clock (VelodyneScan input; a
/// PointCloud2 import makes its packets on the rig clock: lidar_clock_offset_s 0, and kPps is an error).
enum class LidarClock {
  /// calib.yaml's lidar_clock_offset_s, moved to the new epoch: + (calib epoch_unix_s - new epoch) when the
  /// calib has an epoch (epoch_unix_s > 0); kept as it is when its epoch_unix_s is 0 (no epoch recorded).
  kCalib,
  /// The head is PPS-locked to UTC and the ROS stamps are UTC: lidar_clock_offset_s = -(epoch_unix_s mod 3600).
  kPps,
};

struct BagImportOptions {
  std::string calib_path;  ///< calib.yaml of the rig (required)
  /// Topics; "" = the only topic of the right type in the bag (an error when there are none or several).
  /// image_topic "none" imports no camera (the camera stream is optional: no Image topic at all is not an error).
  std::string lidar_topic, imu_topic, image_topic, encoder_topic;
  LidarClock lidar_clock = LidarClock::kCalib;
  bool force = false;  ///< allow a non-empty output folder
};

struct BagImportSummary {
  std::string lidar_topic, imu_topic, image_topic, encoder_topic;  ///< as chosen ("" = no camera)
  std::size_t scans = 0, packets = 0, imu = 0, encoder = 0, images = 0;  ///< scans: VelodyneScan or cloud messages
  std::size_t cloud_points = 0;            ///< PointCloud2 points with a return (0 for VelodyneScan input)
  double epoch_unix_s = 0.0;               ///< written into calib.yaml
  double lidar_clock_offset_s = 0.0;       ///< written into calib.yaml
  double first_t_s = 0.0, last_t_s = 0.0;  ///< rig-clock span of the imported stamps
};

/// Converts `bag_path` into a new recording folder `out_dir`. Errors name the bag, the topic, the message index
/// (0-based within its topic, bag time order) and the field: unreadable bag, missing or ambiguous topics (the
/// candidates are listed; a bag with both a VelodyneScan and a PointCloud2 topic needs --lidar-topic), a topic of
/// the wrong type or md5sum, PointCloud2 clouds that cannot be VLP-16 data (missing or mistyped ring/time fields,
/// a layout that does not fit, big-endian data, points off their laser's ray, overlapping clouds: the message names
/// the field or point), --lidar-clock pps with a PointCloud2, unsupported image encodings, empty or non-finite
/// JointState positions, stamps that do not increase on the cloud, IMU, encoder and camera topics, fewer than 2
/// encoder samples. On failure the folder may hold partial output.
Status ImportBag(const std::string& bag_path, const std::string& out_dir, const BagImportOptions& options,
                 BagImportSummary* summary);

/// The count of the encoder bin holding rotor angle theta_rad (any real angle; wraps) for `counts_per_rev` and
/// `zero_offset_rad` (docs/frames.md "Encoder angle"): the inverse of RigCalib::EncoderAngle.
uint32_t EncoderCountFromAngle(double theta_rad, uint32_t counts_per_rev, double zero_offset_rad);

}  // namespace rotolidar::bench::rosmsg
