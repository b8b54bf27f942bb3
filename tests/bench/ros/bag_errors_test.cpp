// ImportBag on small hand-made bags: a minimal valid bag (epoch, rig times, encoder counts, image conversion), and
// every kind of bad input giving a clear message that names the bag, the topic, the message index and the field;
// the VLP-16 clock offset moved onto the new epoch.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "bench/ros/bag_import.hpp"
#include "bench/ros/bag_io.hpp"
#include "core/io/calib_yaml.hpp"
#include "core/io/recording.hpp"

namespace rotolidar::bench::rosmsg {
namespace {

namespace fs = std::filesystem;

class BagImportErrors : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = (fs::temp_directory_path() / ("rotolidar_bag_errors_" + std::to_string(getpid()))).string();
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    calib_.encoder.counts_per_rev = 4096;
    calib_.encoder.zero_offset_rad = 0.25;
    ASSERT_TRUE(SaveCalibYaml(dir_ + "/calib.yaml", calib_));
  }
  void TearDown() override { fs::remove_all(dir_); }

  /// What a test bag holds; every stream starts at 1700000123.25 s (Unix).
  struct Content {
    std::vector<std::string> imu_topics{"/imu"};
    std::string lidar_type = "velodyne";  ///< "velodyne", "cloud", "none"
    int encoder_messages = 5;
    std::string image_encoding;  ///< "" = no camera topic
    bool empty_joint_position = false;
    int truncated_imu_message = -1;  ///< index of an Imu message cut short
  };

  static RosTime At(int k) { return RosTime{1700000123, static_cast<uint32_t>(250000000 + 10000000 * k)}; }

  std::string WriteBag(const Content& c) {
    const std::string path = dir_ + "/test.bag";
    BagWriter w;
    EXPECT_TRUE(w.Open(path));
    for (int k = 0; k < 5; ++k) {
      if (c.lidar_type == "velodyne") {
        VelodyneScanMsg scan;
        scan.header.stamp = At(k);
        scan.packets.resize(2);
        scan.packets[0].stamp = At(k);
        scan.packets[1].stamp = At(k);
        scan.packets[1].data[0] = 0xFF;
        EXPECT_TRUE(w.WriteMsg("/velodyne_packets", At(k), scan));
      } else if (c.lidar_type == "cloud") {
        PointCloud2Msg cloud;
        cloud.header.stamp = At(k);
        EXPECT_TRUE(w.WriteMsg("/velodyne_points", At(k), cloud));
      }
      for (const std::string& topic : c.imu_topics) {
        ImuMsg imu;
        imu.header.stamp = At(k);
        imu.angular_velocity = {0.01 * k, 0.0, 0.0};
        imu.linear_acceleration = {0.0, 0.0, 9.81};
        std::vector<uint8_t> body = Serialize(imu);
        if (k == c.truncated_imu_message) body.resize(40);
        EXPECT_TRUE(w.Write(topic, At(k), ImuMsg::Type(), body));
      }
      if (k < c.encoder_messages) {
        JointStateMsg joint;
        joint.header.stamp = At(k);
        joint.name = {"motor"};
        if (!c.empty_joint_position) joint.position = {calib_.EncoderAngle(static_cast<uint32_t>(1000 * k + 7))};
        EXPECT_TRUE(w.WriteMsg("/joint_states", At(k), joint));
      }
      if (!c.image_encoding.empty()) {
        ImageMsg image;
        image.header.stamp = At(k);
        image.width = 4, image.height = 2, image.encoding = c.image_encoding;
        image.step = c.image_encoding == "mono8" ? 4 : 12;
        for (uint32_t b = 0; b < image.step * image.height; ++b) image.data.push_back(static_cast<uint8_t>(b));
        EXPECT_TRUE(w.WriteMsg("/camera/image_raw", At(k), image));
      }
    }
    EXPECT_TRUE(w.Close());
    return path;
  }

  Status Import(const std::string& bag, BagImportOptions options = {}) {
    if (options.calib_path.empty()) options.calib_path = dir_ + "/calib.yaml";
    options.force = true;
    return ImportBag(bag, dir_ + "/out", options, &summary_);
  }

  static void ExpectMessage(const Status& s, const std::vector<std::string>& parts) {
    ASSERT_FALSE(s.ok);
    for (const std::string& p : parts)
      EXPECT_NE(s.message.find(p), std::string::npos) << "'" << p << "' not in: " << s.message;
  }

  std::string dir_;
  RigCalib calib_;
  BagImportSummary summary_;
};

TEST_F(BagImportErrors, MinimalBagImports) {
  Content c;
  c.image_encoding = "rgb8";
  const Status s = Import(WriteBag(c));
  ASSERT_TRUE(s.ok) << s.message;
  EXPECT_EQ(summary_.epoch_unix_s, 1700000123.0);
  EXPECT_EQ(summary_.lidar_topic, "/velodyne_packets");
  EXPECT_EQ(summary_.packets, 10u);
  Recording rec;
  const Status l = LoadRecording(dir_ + "/out", &rec);
  ASSERT_TRUE(l.ok) << l.message;
  EXPECT_EQ(rec.calib.epoch_unix_s, 1700000123.0);
  ASSERT_EQ(rec.encoder.size(), 5u);
  for (int k = 0; k < 5; ++k) {
    EXPECT_EQ(rec.encoder[k].count, static_cast<uint32_t>(1000 * k + 7));
    EXPECT_EQ(rec.encoder[k].t_s, (250000000.0 + 10000000.0 * k) / 1e9);
  }
  EXPECT_EQ(rec.imu[3].gyro_radps.x(), 0.03);
  EXPECT_EQ(rec.lidar_packets[1].payload[0], 0xFF);
  EXPECT_EQ(rec.lidar_packets[0].t_capture_s, 0.25);
  ASSERT_EQ(rec.camera.size(), 5u);
  CameraFrame frame;
  ASSERT_TRUE(LoadCameraFrame(rec.camera[0], &frame));
  EXPECT_EQ(frame.image.at<cv::Vec3b>(0, 0), cv::Vec3b(2, 1, 0));  // rgb8 (0, 1, 2) stored as BGR
}

TEST_F(BagImportErrors, NotABag) {
  const std::string path = dir_ + "/garbage.bag";
  std::ofstream(path) << "#ROSBAG V2.0\nthis is not a bag";
  ExpectMessage(Import(path), {path, "not a readable ROS 1 bag"});
  ExpectMessage(Import(dir_ + "/missing.bag"), {"missing.bag", "not a readable ROS 1 bag"});
  // A real bag cut in half: its index (at the end) is gone.
  const std::string bag = WriteBag(Content{});
  fs::resize_file(bag, fs::file_size(bag) / 2);
  ExpectMessage(Import(bag), {"test.bag", "not a readable ROS 1 bag"});
}

TEST_F(BagImportErrors, AmbiguousAndMissingTopics) {
  Content c;
  c.imu_topics = {"/imu_a", "/imu_b"};
  const std::string bag = WriteBag(c);
  ExpectMessage(Import(bag),
                {"several sensor_msgs/Imu topics", "/imu_a (sensor_msgs/Imu, 5 messages)", "/imu_b", "--imu-topic"});
  BagImportOptions pick;
  pick.imu_topic = "/imu_b";
  EXPECT_TRUE(Import(bag, pick).ok);
  pick.imu_topic = "/imu_c";
  ExpectMessage(Import(bag, pick), {"no topic /imu_c (--imu-topic)", "/imu_a"});
  Content no_imu;
  no_imu.imu_topics.clear();
  ExpectMessage(Import(WriteBag(no_imu)), {"no sensor_msgs/Imu topic for the imu stream"});
}

TEST_F(BagImportErrors, WrongMessageType) {
  const std::string bag = WriteBag(Content{});
  BagImportOptions o;
  o.imu_topic = "/joint_states";
  ExpectMessage(Import(bag, o),
                {"topic /joint_states (--imu-topic) has type sensor_msgs/JointState, expected sensor_msgs/Imu"});
  // Same type name, another definition (md5sum).
  BagWriter w;
  ASSERT_TRUE(w.Open(dir_ + "/md5.bag"));
  const RosMsgType other{"sensor_msgs/Imu", "0123456789abcdef0123456789abcdef", "float64 x\n"};
  ASSERT_TRUE(w.Write("/imu", At(0), other, std::vector<uint8_t>(8, 0)));
  ASSERT_TRUE(w.WriteMsg("/velodyne_packets", At(0), VelodyneScanMsg{}));
  ASSERT_TRUE(w.Close());
  ExpectMessage(Import(dir_ + "/md5.bag"), {"md5sum 0123456789abcdef0123456789abcdef", "expected 6a62c6daae10"});
}

// A PointCloud2 LiDAR topic is taken (cloud_errors_test.cpp has the valid and malformed clouds); these have no
// fields. A LiDAR flag naming a topic of a third type lists both accepted types.
TEST_F(BagImportErrors, PointCloudLidarWithoutFields) {
  Content c;
  c.lidar_type = "cloud";
  const std::string bag = WriteBag(c);
  ExpectMessage(Import(bag), {"test.bag: topic /velodyne_points, message 0: field 'x': missing", "the cloud has none"});
  BagImportOptions o;
  o.lidar_topic = "/velodyne_points";
  ExpectMessage(Import(bag, o), {"message 0: field 'x': missing"});
  o.lidar_topic = "/imu";
  ExpectMessage(Import(bag, o), {"topic /imu (--lidar-topic) has type sensor_msgs/Imu, expected "
                                 "velodyne_msgs/VelodyneScan or sensor_msgs/PointCloud2"});
}

TEST_F(BagImportErrors, BadMessagesNameTopicIndexAndField) {
  Content truncated;
  truncated.truncated_imu_message = 2;
  ExpectMessage(Import(WriteBag(truncated)), {"test.bag: topic /imu, message 2: field 'orientation' at byte 40"});
  Content rgba;
  rgba.image_encoding = "rgba8";
  ExpectMessage(Import(WriteBag(rgba)),
                {"topic /camera/image_raw, message 0: field 'encoding': 'rgba8' is not supported (rgb8, bgr8, mono8)"});
  Content no_position;
  no_position.empty_joint_position = true;
  ExpectMessage(Import(WriteBag(no_position)), {"topic /joint_states, message 0: field 'position': empty"});
  Content one_encoder;
  one_encoder.encoder_messages = 1;
  ExpectMessage(Import(WriteBag(one_encoder)), {"/joint_states: 1 messages, a recording needs at least 2"});
  BagImportOptions no_calib;
  no_calib.calib_path = dir_ + "/nope.yaml";
  ExpectMessage(Import(WriteBag(Content{}), no_calib), {"nope.yaml"});
}

TEST_F(BagImportErrors, MonoImagesAndNonIncreasingStamps) {
  Content mono;
  mono.image_encoding = "mono8";
  ASSERT_TRUE(Import(WriteBag(mono)).ok);
  BagWriter w;
  ASSERT_TRUE(w.Open(dir_ + "/order.bag"));
  for (int k : {0, 1, 1}) {
    ImuMsg imu;
    imu.header.stamp = At(k);
    ASSERT_TRUE(w.WriteMsg("/imu", At(k), imu));
  }
  VelodyneScanMsg scan;
  scan.packets.resize(1);
  scan.packets[0].stamp = At(0);
  ASSERT_TRUE(w.WriteMsg("/velodyne_packets", At(0), scan));
  JointStateMsg joint;
  joint.position = {0.0};
  joint.header.stamp = At(0);
  ASSERT_TRUE(w.WriteMsg("/joint_states", At(0), joint));
  ASSERT_TRUE(w.Close());
  ExpectMessage(Import(dir_ + "/order.bag"), {"topic /imu, message 2: field 'header.stamp'", "does not increase"});
}

// The VLP-16 clock offset follows the new epoch: moved by (calib epoch - new epoch) when the calib has one, kept when
// its epoch is 0, or set from UTC with --lidar-clock pps (1700000123 mod 3600 = 923 s past the hour).
TEST_F(BagImportErrors, LidarClockOffsetFollowsTheEpoch) {
  const std::string bag = WriteBag(Content{});
  RigCalib with_epoch = calib_;
  with_epoch.epoch_unix_s = 1700000000.0;
  with_epoch.lidar_clock_offset_s = 0.5;
  ASSERT_TRUE(SaveCalibYaml(dir_ + "/epoch.yaml", with_epoch));
  BagImportOptions o;
  o.calib_path = dir_ + "/epoch.yaml";
  ASSERT_TRUE(Import(bag, o).ok);
  EXPECT_EQ(summary_.lidar_clock_offset_s, 0.5 - 123.0);
  with_epoch.epoch_unix_s = 0.0;
  ASSERT_TRUE(SaveCalibYaml(dir_ + "/epoch.yaml", with_epoch));
  ASSERT_TRUE(Import(bag, o).ok);
  EXPECT_EQ(summary_.lidar_clock_offset_s, 0.5);
  o.lidar_clock = LidarClock::kPps;
  ASSERT_TRUE(Import(bag, o).ok);
  EXPECT_EQ(summary_.lidar_clock_offset_s, -923.0);
  RigCalib written;
  ASSERT_TRUE(LoadCalibYaml(dir_ + "/out/calib.yaml", &written));
  EXPECT_EQ(written.lidar_clock_offset_s, -923.0);
  EXPECT_EQ(written.epoch_unix_s, 1700000123.0);
}

}  // namespace
}  // namespace rotolidar::bench::rosmsg
