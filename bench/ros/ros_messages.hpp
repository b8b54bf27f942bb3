#pragma once
// The ROS 1 messages rotolidar reads and writes, serialised by hand (no generated ROS headers; velodyne_msgs is not
// packaged by Debian): std_msgs/Header, velodyne_msgs/VelodyneScan (+ VelodynePacket), sensor_msgs/Imu, Image,
// JointState, PointCloud2 (+ PointField), nav_msgs/Odometry, tf2_msgs/TFMessage (+ geometry_msgs/
// TransformStamped). Each has its type name, the md5sum of its definition (as genmsg computes it,
// the value rosbag and RViz check) and the full definition text stored in a bag's connection record
// (bench/ros/ros_msg_types.cpp; comments stripped, which changes neither the md5 nor what parsers read).
// Quaternions are stored x, y, z, w as in ROS. Units are the messages' own (REP-103: m, rad, rad/s, m/s^2).
//
// Parse* fail on a body that is too short, a length that cannot fit, or bytes left after the last field; the
// message names the field (by its path in the message) and the byte offset. *out is undefined on failure.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "bench/ros/ros_serial.hpp"

namespace rotolidar::bench::rosmsg {

/// A message type as a bag's connection record names it.
struct RosMsgType {
  const char* datatype;    ///< e.g. "sensor_msgs/Imu"
  const char* md5;         ///< 32 hex digits
  std::string definition;  ///< full definition: the message, then "=====...\nMSG: pkg/Type\n" per nested type
};

struct RosHeader {
  uint32_t seq = 0;
  RosTime stamp;
  std::string frame_id;
};

inline constexpr std::size_t kVelodynePacketBytes = 1206;
struct VelodynePacketMsg {
  RosTime stamp;
  std::array<uint8_t, kVelodynePacketBytes> data{};
};
struct VelodyneScanMsg {
  RosHeader header;
  std::vector<VelodynePacketMsg> packets;
  static const RosMsgType& Type();
};

struct ImuMsg {
  RosHeader header;
  std::array<double, 4> orientation_xyzw{0, 0, 0, 1};
  std::array<double, 9> orientation_covariance{};  ///< element 0 = -1: no orientation estimate (REP-145)
  std::array<double, 3> angular_velocity{};        ///< [rad/s]
  std::array<double, 9> angular_velocity_covariance{};
  std::array<double, 3> linear_acceleration{};  ///< [m/s^2]
  std::array<double, 9> linear_acceleration_covariance{};
  static const RosMsgType& Type();
};

struct ImageMsg {
  RosHeader header;
  uint32_t height = 0, width = 0;
  std::string encoding;  ///< "rgb8", "bgr8", "mono8", ... (sensor_msgs/image_encodings.h)
  uint8_t is_bigendian = 0;
  uint32_t step = 0;  ///< bytes per row
  std::vector<uint8_t> data;
  static const RosMsgType& Type();
};

struct JointStateMsg {
  RosHeader header;
  std::vector<std::string> name;
  std::vector<double> position, velocity, effort;  ///< [rad], [rad/s], [N m] for revolute joints
  static const RosMsgType& Type();
};

/// sensor_msgs/PointField datatype codes.
enum class PointFieldType : uint8_t { kInt8 = 1, kUint8, kInt16, kUint16, kInt32, kUint32, kFloat32, kFloat64 };
struct PointFieldMsg {
  std::string name;
  uint32_t offset = 0;
  uint8_t datatype = 0;
  uint32_t count = 1;
};
struct PointCloud2Msg {
  RosHeader header;
  uint32_t height = 0, width = 0;
  std::vector<PointFieldMsg> fields;
  uint8_t is_bigendian = 0;
  uint32_t point_step = 0, row_step = 0;
  std::vector<uint8_t> data;
  uint8_t is_dense = 0;
  static const RosMsgType& Type();
};

struct OdometryMsg {
  RosHeader header;            ///< frame_id: the pose's reference frame
  std::string child_frame_id;  ///< the body frame (also the twist's frame)
  std::array<double, 3> position{};
  std::array<double, 4> orientation_xyzw{0, 0, 0, 1};
  std::array<double, 36> pose_covariance{};
  std::array<double, 3> linear_velocity{}, angular_velocity{};
  std::array<double, 36> twist_covariance{};
  static const RosMsgType& Type();
};

struct TransformStampedMsg {
  RosHeader header;            ///< frame_id: the parent frame
  std::string child_frame_id;  ///< T_parent_child
  std::array<double, 3> translation{};
  std::array<double, 4> rotation_xyzw{0, 0, 0, 1};
};
struct TFMessageMsg {
  std::vector<TransformStampedMsg> transforms;
  static const RosMsgType& Type();
};

std::vector<uint8_t> Serialize(const VelodyneScanMsg& m);
std::vector<uint8_t> Serialize(const ImuMsg& m);
std::vector<uint8_t> Serialize(const ImageMsg& m);
std::vector<uint8_t> Serialize(const JointStateMsg& m);
std::vector<uint8_t> Serialize(const PointCloud2Msg& m);
std::vector<uint8_t> Serialize(const OdometryMsg& m);
std::vector<uint8_t> Serialize(const TFMessageMsg& m);

Status Parse(const std::vector<uint8_t>& body, VelodyneScanMsg* out);
Status Parse(const std::vector<uint8_t>& body, ImuMsg* out);
Status Parse(const std::vector<uint8_t>& body, ImageMsg* out);
Status Parse(const std::vector<uint8_t>& body, JointStateMsg* out);
Status Parse(const std::vector<uint8_t>& body, PointCloud2Msg* out);
Status Parse(const std::vector<uint8_t>& body, OdometryMsg* out);
Status Parse(const std::vector<uint8_t>& body, TFMessageMsg* out);

}  // namespace rotolidar::bench::rosmsg
