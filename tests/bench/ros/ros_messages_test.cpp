// Hand-written ROS 1 messages (bench/ros/ros_messages.hpp): serialise -> parse round trips field by field, the
// wire layout of a known message, errors that name the field and the byte offset, the encoder angle <-> count
// inverse, and raw messages through a bag file (BagWriter / BagReader).
#include "bench/ros/ros_messages.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>

#include "bench/ros/bag_import.hpp"
#include "bench/ros/bag_io.hpp"
#include "core/types/calib.hpp"

namespace rotolidar::bench::rosmsg {
namespace {

RosHeader MakeHeader(uint32_t seq, uint32_t sec, uint32_t nsec, const std::string& frame) {
  RosHeader h;
  h.seq = seq;
  h.stamp = {sec, nsec};
  h.frame_id = frame;
  return h;
}

void ExpectHeader(const RosHeader& a, const RosHeader& b) {
  EXPECT_EQ(a.seq, b.seq);
  EXPECT_EQ(a.stamp, b.stamp);
  EXPECT_EQ(a.frame_id, b.frame_id);
}

TEST(RosMessages, ImuRoundTripAndLayout) {
  ImuMsg m;
  m.header = MakeHeader(7, 1700000000, 123456789, "imu");
  m.orientation_covariance[0] = -1.0;
  m.angular_velocity = {0.1, -0.2, 0.30000000000000004};
  m.linear_acceleration = {1e-300, 9.81, -std::numeric_limits<double>::max()};
  const std::vector<uint8_t> body = Serialize(m);
  // header: 4 seq + 8 stamp + 4 + 3 frame_id; then 4 + 9 + 3 + 9 + 3 + 9 doubles.
  ASSERT_EQ(body.size(), 19u + 37u * 8u);
  EXPECT_EQ(body[0], 7);
  EXPECT_EQ(body[12], 3);  // frame_id length, little-endian
  ImuMsg back;
  ASSERT_TRUE(Parse(body, &back));
  ExpectHeader(back.header, m.header);
  EXPECT_EQ(back.orientation_xyzw, m.orientation_xyzw);
  EXPECT_EQ(back.orientation_covariance, m.orientation_covariance);
  EXPECT_EQ(back.angular_velocity, m.angular_velocity);
  EXPECT_EQ(back.linear_acceleration, m.linear_acceleration);
}

TEST(RosMessages, VelodyneScanImageJointStateRoundTrip) {
  VelodyneScanMsg scan;
  scan.header = MakeHeader(1, 10, 20, "velodyne");
  for (int i = 0; i < 3; ++i) {
    VelodynePacketMsg p;
    p.stamp = {10, static_cast<uint32_t>(1000 * i)};
    for (std::size_t k = 0; k < p.data.size(); ++k) p.data[k] = static_cast<uint8_t>(k * 7 + i);
    scan.packets.push_back(p);
  }
  VelodyneScanMsg scan_back;
  ASSERT_TRUE(Parse(Serialize(scan), &scan_back));
  ExpectHeader(scan_back.header, scan.header);
  ASSERT_EQ(scan_back.packets.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(scan_back.packets[i].stamp, scan.packets[i].stamp);
    EXPECT_EQ(scan_back.packets[i].data, scan.packets[i].data);
  }
  ImageMsg image;
  image.header = MakeHeader(2, 11, 0, "camera");
  image.height = 2, image.width = 3, image.encoding = "rgb8", image.step = 9;
  for (int k = 0; k < 18; ++k) image.data.push_back(static_cast<uint8_t>(k));
  ImageMsg image_back;
  ASSERT_TRUE(Parse(Serialize(image), &image_back));
  EXPECT_EQ(image_back.encoding, "rgb8");
  EXPECT_EQ(image_back.step, 9u);
  EXPECT_EQ(image_back.data, image.data);
  JointStateMsg joint;
  joint.header = MakeHeader(3, 12, 5, "");
  joint.name = {"motor", "other"};
  joint.position = {1.25, -3.0};
  joint.velocity = {2.6};
  JointStateMsg joint_back;
  ASSERT_TRUE(Parse(Serialize(joint), &joint_back));
  EXPECT_EQ(joint_back.name, joint.name);
  EXPECT_EQ(joint_back.position, joint.position);
  EXPECT_EQ(joint_back.velocity, joint.velocity);
  EXPECT_TRUE(joint_back.effort.empty());
}

TEST(RosMessages, OdometryTfPointCloudRoundTrip) {
  OdometryMsg odom;
  odom.header = MakeHeader(4, 13, 6, "world");
  odom.child_frame_id = "base";
  odom.position = {1, 2, 3};
  odom.orientation_xyzw = {0.5, 0.5, 0.5, 0.5};
  odom.pose_covariance[35] = 0.25;
  OdometryMsg odom_back;
  ASSERT_TRUE(Parse(Serialize(odom), &odom_back));
  EXPECT_EQ(odom_back.child_frame_id, "base");
  EXPECT_EQ(odom_back.position, odom.position);
  EXPECT_EQ(odom_back.orientation_xyzw, odom.orientation_xyzw);
  EXPECT_EQ(odom_back.pose_covariance, odom.pose_covariance);
  TFMessageMsg tf;
  tf.transforms.resize(2);
  tf.transforms[1].header = odom.header;
  tf.transforms[1].child_frame_id = "base";
  tf.transforms[1].translation = {4, 5, 6};
  TFMessageMsg tf_back;
  ASSERT_TRUE(Parse(Serialize(tf), &tf_back));
  ASSERT_EQ(tf_back.transforms.size(), 2u);
  EXPECT_EQ(tf_back.transforms[1].translation, tf.transforms[1].translation);
  EXPECT_EQ(tf_back.transforms[1].child_frame_id, "base");
  PointCloud2Msg cloud;
  cloud.header = MakeHeader(5, 14, 0, "world");
  cloud.height = 1, cloud.width = 2, cloud.point_step = 12, cloud.row_step = 24, cloud.is_dense = 1;
  cloud.fields = {{"x", 0, 7, 1}, {"y", 4, 7, 1}, {"z", 8, 7, 1}};
  cloud.data.assign(24, 0xAB);
  PointCloud2Msg cloud_back;
  ASSERT_TRUE(Parse(Serialize(cloud), &cloud_back));
  ASSERT_EQ(cloud_back.fields.size(), 3u);
  EXPECT_EQ(cloud_back.fields[2].name, "z");
  EXPECT_EQ(cloud_back.fields[2].offset, 8u);
  EXPECT_EQ(cloud_back.data, cloud.data);
  EXPECT_EQ(cloud_back.is_dense, 1);
}

TEST(RosMessages, ErrorsNameTheFieldAndOffset) {
  ImuMsg m;
  m.header = MakeHeader(0, 1, 2, "imu");
  std::vector<uint8_t> body = Serialize(m);
  body.resize(19 + 8 * 13 + 4);  // cut inside angular_velocity
  ImuMsg back;
  const Status cut = Parse(body, &back);
  ASSERT_FALSE(cut.ok);
  EXPECT_NE(cut.message.find("field 'angular_velocity' at byte 123: message ends"), std::string::npos) << cut.message;
  std::vector<uint8_t> longer = Serialize(m);
  longer.push_back(0);
  const Status extra = Parse(longer, &back);
  ASSERT_FALSE(extra.ok);
  EXPECT_NE(extra.message.find("1 bytes left after the last field"), std::string::npos) << extra.message;
  // A VelodyneScan whose packet count cannot fit: no allocation of 4e9 packets, a clear message instead.
  VelodyneScanMsg scan;
  std::vector<uint8_t> bad = Serialize(scan);
  bad[bad.size() - 1] = 0xFF;  // the packets' length prefix is the last 4 bytes of an empty scan
  VelodyneScanMsg scan_back;
  const Status huge = Parse(bad, &scan_back);
  ASSERT_FALSE(huge.ok);
  EXPECT_NE(huge.message.find("field 'packets'"), std::string::npos) << huge.message;
  EXPECT_NE(huge.message.find("cannot fit"), std::string::npos) << huge.message;
}

TEST(RosMessages, TypesHaveTheNoeticMd5sumsAndFullDefinitions) {
  EXPECT_STREQ(ImuMsg::Type().md5, "6a62c6daae103f4ff57a132d6f95cec2");
  EXPECT_STREQ(VelodyneScanMsg::Type().md5, "50804fc9533a0e579e6322c04ae70566");
  EXPECT_STREQ(PointCloud2Msg::Type().datatype, "sensor_msgs/PointCloud2");
  EXPECT_NE(TFMessageMsg::Type().definition.find("\nMSG: geometry_msgs/TransformStamped\n"), std::string::npos);
  EXPECT_NE(VelodyneScanMsg::Type().definition.find("uint8[1206] data"), std::string::npos);
}

TEST(EncoderCountFromAngle, InvertsEncoderAngleForEveryCount) {
  for (uint32_t cpr : {4u, 4096u, 16384u}) {
    for (double zero : {0.0, 0.3, -2.0, 7.5}) {
      RigCalib calib;
      calib.encoder.counts_per_rev = cpr;
      calib.encoder.zero_offset_rad = zero;
      for (uint32_t c = 0; c < cpr; ++c) {
        const double theta = calib.EncoderAngle(c);
        ASSERT_EQ(EncoderCountFromAngle(theta, cpr, zero), c) << "cpr " << cpr << " zero " << zero;
        ASSERT_EQ(EncoderCountFromAngle(theta + 2.0 * M_PI * 3, cpr, zero), c);  // multi-turn positions wrap
        ASSERT_EQ(EncoderCountFromAngle(theta - 2.0 * M_PI * 5, cpr, zero), c);
      }
    }
  }
}

TEST(Bag, RawMessagesThroughABagFile) {
  const std::string path =
      (std::filesystem::temp_directory_path() / ("rotolidar_bag_raw_" + std::to_string(getpid()) + ".bag")).string();
  {
    BagWriter w;
    ASSERT_TRUE(w.Open(path));
    for (uint32_t i = 0; i < 5; ++i) {
      ImuMsg imu;
      imu.header = MakeHeader(i, 100 + i, 0, "imu");
      ASSERT_TRUE(w.WriteMsg("/imu", imu.header.stamp, imu));
    }
    JointStateMsg joint;
    joint.header = MakeHeader(0, 101, 500, "");
    joint.position = {0.5};
    ASSERT_TRUE(w.WriteMsg("/joint_states", joint.header.stamp, joint, /*latched=*/true));
    EXPECT_FALSE(w.WriteMsg("/imu", RosTime{0, 0}, ImuMsg{}).ok);  // rosbag refuses time 0
    ASSERT_TRUE(w.Close());
  }
  BagReader r;
  ASSERT_TRUE(r.Open(path));
  ASSERT_EQ(r.topics().size(), 2u);
  EXPECT_EQ(r.topics()[0].topic, "/imu");
  EXPECT_EQ(r.topics()[0].messages, 5u);
  EXPECT_EQ(r.topics()[0].md5, ImuMsg::Type().md5);
  EXPECT_EQ(r.topics()[1].datatype, "sensor_msgs/JointState");
  std::vector<std::string> order;
  ASSERT_TRUE(r.ForEach({"/imu", "/joint_states"}, [&](const BagMessage& m) {
    order.push_back(m.topic + "#" + std::to_string(m.index));
    if (m.topic == "/joint_states") {
      JointStateMsg back;
      EXPECT_TRUE(Parse(m.body, &back));
      EXPECT_EQ(back.position, std::vector<double>{0.5});
    }
    return Status::Ok();
  }));
  const std::vector<std::string> expected = {"/imu#0", "/imu#1", "/joint_states#0", "/imu#2", "/imu#3", "/imu#4"};
  EXPECT_EQ(order, expected);  // bag time order, indices per topic
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace rotolidar::bench::rosmsg
