// Type names, md5sums and full definitions of the hand-serialised messages (bench/ros/ros_messages.hpp).
// The texts are the .msg files of ROS Noetic (std_msgs, geometry_msgs, sensor_msgs, nav_msgs, tf2_msgs) and
// velodyne_msgs with comments and blank lines stripped; the md5sums are genmsg's over these texts (each nested
// type replaced by its own md5sum) and equal the ones in the generated headers of the same messages.
#include <utility>

#include "bench/ros/ros_messages.hpp"

namespace rotolidar::bench::rosmsg {
namespace {

constexpr const char* kHeader = "uint32 seq\ntime stamp\nstring frame_id\n";
constexpr const char* kVector3 = "float64 x\nfloat64 y\nfloat64 z\n";
constexpr const char* kQuaternion = "float64 x\nfloat64 y\nfloat64 z\nfloat64 w\n";

/// genmsg's layout: the message text, then each nested type (depth first, in order of first use).
std::string FullDefinition(const char* text, const std::vector<std::pair<const char*, const char*>>& nested) {
  std::string def = text;
  for (const auto& [name, body] : nested) {
    def += "================================================================================\nMSG: ";
    def += name;
    def += "\n";
    def += body;
  }
  return def;
}

}  // namespace

const RosMsgType& VelodyneScanMsg::Type() {
  static const RosMsgType type{"velodyne_msgs/VelodyneScan", "50804fc9533a0e579e6322c04ae70566",
                               FullDefinition("Header header\nVelodynePacket[] packets\n",
                                              {{"std_msgs/Header", kHeader},
                                               {"velodyne_msgs/VelodynePacket", "time stamp\nuint8[1206] data\n"}})};
  return type;
}

const RosMsgType& ImuMsg::Type() {
  static const RosMsgType type{
      "sensor_msgs/Imu", "6a62c6daae103f4ff57a132d6f95cec2",
      FullDefinition("Header header\ngeometry_msgs/Quaternion orientation\nfloat64[9] orientation_covariance\n"
                     "geometry_msgs/Vector3 angular_velocity\nfloat64[9] angular_velocity_covariance\n"
                     "geometry_msgs/Vector3 linear_acceleration\nfloat64[9] linear_acceleration_covariance\n",
                     {{"std_msgs/Header", kHeader},
                      {"geometry_msgs/Quaternion", kQuaternion},
                      {"geometry_msgs/Vector3", kVector3}})};
  return type;
}

const RosMsgType& ImageMsg::Type() {
  static const RosMsgType type{
      "sensor_msgs/Image", "060021388200f6f0f447d0fcd9c64743",
      FullDefinition("Header header\nuint32 height\nuint32 width\nstring encoding\nuint8 is_bigendian\n"
                     "uint32 step\nuint8[] data\n",
                     {{"std_msgs/Header", kHeader}})};
  return type;
}

const RosMsgType& JointStateMsg::Type() {
  static const RosMsgType type{
      "sensor_msgs/JointState", "3066dcd76a6cfaef579bd0f34173e9fd",
      FullDefinition("Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\nfloat64[] effort\n",
                     {{"std_msgs/Header", kHeader}})};
  return type;
}

const RosMsgType& PointCloud2Msg::Type() {
  static const RosMsgType type{
      "sensor_msgs/PointCloud2", "1158d486dd51d683ce2f1be655c3c181",
      FullDefinition("Header header\nuint32 height\nuint32 width\nPointField[] fields\nbool is_bigendian\n"
                     "uint32 point_step\nuint32 row_step\nuint8[] data\nbool is_dense\n",
                     {{"std_msgs/Header", kHeader},
                      {"sensor_msgs/PointField",
                       "uint8 INT8 = 1\nuint8 UINT8 = 2\nuint8 INT16 = 3\nuint8 UINT16 = 4\nuint8 INT32 = 5\n"
                       "uint8 UINT32 = 6\nuint8 FLOAT32 = 7\nuint8 FLOAT64 = 8\nstring name\nuint32 offset\n"
                       "uint8 datatype\nuint32 count\n"}})};
  return type;
}

const RosMsgType& OdometryMsg::Type() {
  static const RosMsgType type{
      "nav_msgs/Odometry", "cd5e73d190d741a2f92e81eda573aca7",
      FullDefinition("Header header\nstring child_frame_id\ngeometry_msgs/PoseWithCovariance pose\n"
                     "geometry_msgs/TwistWithCovariance twist\n",
                     {{"std_msgs/Header", kHeader},
                      {"geometry_msgs/PoseWithCovariance", "Pose pose\nfloat64[36] covariance\n"},
                      {"geometry_msgs/Pose", "Point position\nQuaternion orientation\n"},
                      {"geometry_msgs/Point", "float64 x\nfloat64 y\nfloat64 z\n"},
                      {"geometry_msgs/Quaternion", kQuaternion},
                      {"geometry_msgs/TwistWithCovariance", "Twist twist\nfloat64[36] covariance\n"},
                      {"geometry_msgs/Twist", "Vector3 linear\nVector3 angular\n"},
                      {"geometry_msgs/Vector3", kVector3}})};
  return type;
}

const RosMsgType& TFMessageMsg::Type() {
  static const RosMsgType type{
      "tf2_msgs/TFMessage", "94810edda583a504dfda3829e70d7eec",
      FullDefinition("geometry_msgs/TransformStamped[] transforms\n",
                     {{"geometry_msgs/TransformStamped", "Header header\nstring child_frame_id\nTransform transform\n"},
                      {"std_msgs/Header", kHeader},
                      {"geometry_msgs/Transform", "Vector3 translation\nQuaternion rotation\n"},
                      {"geometry_msgs/Vector3", kVector3},
                      {"geometry_msgs/Quaternion", kQuaternion}})};
  return type;
}

}  // namespace rotolidar::bench::rosmsg
