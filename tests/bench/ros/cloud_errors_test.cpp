// Malformed sensor_msgs/PointCloud2 LiDAR input of `rotolidar import`: each gives an error naming the bag, the topic,
// the message index and the field (or the point); valid clouds with a `time` (float32 s) or `t` (uint32 ns) field
// import to the points they hold.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <functional>

#include "bench/ros/bag_import.hpp"
#include "bench/ros/bag_io.hpp"
#include "core/io/calib_yaml.hpp"
#include "core/io/recording.hpp"
#include "tests/bench/ros/cloud_test_util.hpp"

namespace rotolidar::bench::rosmsg {
namespace {

namespace fs = std::filesystem;
using namespace cloudtest;  // NOLINT: the test helpers

class CloudImportErrors : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = (fs::temp_directory_path() / ("rotolidar_cloud_errors_" + std::to_string(getpid()))).string();
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    ASSERT_TRUE(SaveCalibYaml(dir_ + "/calib.yaml", calib_));
  }
  void TearDown() override { fs::remove_all(dir_); }

  static RosTime At(int k) { return RosTime{1700000123, static_cast<uint32_t>(250000000 + 10000000 * k)}; }

  /// Five clouds of 6 firings each (10 ms apart), Imu and JointState beside; `bad` changes cloud `bad_index`.
  std::string WriteBag(const std::function<void(PointCloud2Msg*)>& bad, int bad_index = 0,
                       const CloudLayout& layout = {}) {
    const std::string path = dir_ + "/test.bag";
    BagWriter w;
    EXPECT_TRUE(w.Open(path));
    for (int k = 0; k < 5; ++k) {
      const double stamp_rig = 0.25 + 0.01 * k;  // rig time of At(k) for an epoch of 1700000123
      PointCloud2Msg cloud = MakeCloud(At(k), Firings(calib_, stamp_rig, 6, 36.0 * k), stamp_rig, layout);
      if (k == bad_index && bad) bad(&cloud);
      EXPECT_TRUE(w.WriteMsg("/velodyne_points", At(k), cloud));
      ImuMsg imu;
      imu.header.stamp = At(k);
      EXPECT_TRUE(w.WriteMsg("/imu", At(k), imu));
      JointStateMsg joint;
      joint.header.stamp = At(k);
      joint.position = {0.1 * k};
      EXPECT_TRUE(w.WriteMsg("/joint_states", At(k), joint));
    }
    EXPECT_TRUE(w.Close());
    return path;
  }

  Status Import(const std::string& bag, BagImportOptions options = {}) {
    options.calib_path = dir_ + "/calib.yaml";
    options.force = true;
    return ImportBag(bag, dir_ + "/out", options, &summary_);
  }

  void ExpectError(const std::function<void(PointCloud2Msg*)>& bad, const std::vector<std::string>& parts,
                   int bad_index = 0) {
    const Status s = Import(WriteBag(bad, bad_index));
    ASSERT_FALSE(s.ok) << parts.front();
    const std::string where = "test.bag: topic /velodyne_points, message " + std::to_string(bad_index) + ": ";
    EXPECT_NE(s.message.find(where), std::string::npos) << s.message;
    for (const std::string& p : parts)
      EXPECT_NE(s.message.find(p), std::string::npos) << "'" << p << "' not in: " << s.message;
  }

  static PointFieldMsg* Find(PointCloud2Msg* c, const std::string& name) {
    for (PointFieldMsg& f : c->fields)
      if (f.name == name) return &f;
    return nullptr;
  }

  std::string dir_;
  RigCalib calib_;
  BagImportSummary summary_;
};

TEST_F(CloudImportErrors, ValidCloudsWithTimeOrT) {
  for (const char* field : {"time", "t"}) {
    CloudLayout layout;
    layout.time_field = field;
    const Status s = Import(WriteBag(nullptr, 0, layout));
    ASSERT_TRUE(s.ok) << field << ": " << s.message;
    EXPECT_EQ(summary_.lidar_topic, "/velodyne_points");
    EXPECT_EQ(summary_.scans, 5u);
    EXPECT_EQ(summary_.cloud_points, 5u * 6 * 16);
    EXPECT_EQ(summary_.packets, 5u);  // 10 ms apart: each cloud's 6 firings start a packet of their own
    EXPECT_EQ(summary_.epoch_unix_s, 1700000123.0);
    Recording rec;
    ASSERT_TRUE(LoadRecording(dir_ + "/out", &rec).ok);
    const std::vector<LidarPoint> points = DecodeAll(rec.lidar_packets, rec.calib);
    ASSERT_EQ(points.size(), 5u * 6 * 16);
    EXPECT_NEAR(points.front().t_s, 0.25, 1e-6);
    EXPECT_NEAR(points.back().t_s, 0.29 + 5 * kVlp16SequencePeriodS + 15 * kVlp16FiringPeriodS, 1e-6);
  }
}

TEST_F(CloudImportErrors, MissingOrMistypedFields) {
  using T = PointFieldType;
  auto erase = [](const std::string& name) {
    return [name](PointCloud2Msg* c) {
      c->fields.erase(std::remove_if(c->fields.begin(), c->fields.end(),
                                     [&](const PointFieldMsg& f) { return f.name == name; }),
                      c->fields.end());
    };
  };
  ExpectError(erase("ring"), {"field 'ring': missing (uint16", "the cloud has x (float32), y (float32)"});
  ExpectError(erase("time"), {"field 'time': missing", "'t' uint32 [ns]", "'timestamp' is not supported"});
  ExpectError(erase("x"), {"field 'x': missing"});
  ExpectError([](PointCloud2Msg* c) { Find(c, "ring")->datatype = static_cast<uint8_t>(T::kFloat32); },
              {"field 'ring': datatype 7 (float32), expected uint16"});
  ExpectError([](PointCloud2Msg* c) { Find(c, "time")->datatype = static_cast<uint8_t>(T::kUint32); },
              {"field 'time': datatype 6 (uint32), expected float32"});
  ExpectError([](PointCloud2Msg* c) { Find(c, "time")->name = "t"; },
              {"field 't': datatype 7 (float32), expected uint32"});
  ExpectError([](PointCloud2Msg* c) { Find(c, "z")->count = 3; }, {"field 'z': count 3, expected 1"});
}

TEST_F(CloudImportErrors, LayoutThatDoesNotFit) {
  ExpectError([](PointCloud2Msg* c) { c->point_step = 24, c->row_step = 24 * c->width; },
              {"field 'time': offset 24 + 4 bytes does not fit in point_step 24"});
  ExpectError([](PointCloud2Msg* c) { c->is_bigendian = 1; }, {"field 'is_bigendian': big-endian"}, 3);
  ExpectError([](PointCloud2Msg* c) { c->data.resize(c->data.size() - 1); },
              {"field 'data': 3071 bytes, row_step x height = 3072"});
  ExpectError([](PointCloud2Msg* c) { c->row_step = 10; }, {"field 'row_step': 10 < width 96 x point_step 32"});
}

TEST_F(CloudImportErrors, PointsThatAreNotVlp16Rays) {
  ExpectError([](PointCloud2Msg* c) { c->data[32 * 3 + 20] = 16; }, {"point 3 (ring 16): field 'ring': 16 >= 16"});
  // Tilted by 10 deg (a cloud transformed into another frame).
  ExpectError(
      [](PointCloud2Msg* c) {
        for (uint32_t i = 0; i < c->width; ++i) {
          float x, z;
          std::memcpy(&x, &c->data[32 * i], 4), std::memcpy(&z, &c->data[32 * i + 8], 4);
          const float ca = std::cos(0.1745f), sa = std::sin(0.1745f);  // 10 deg about y
          const float xt = ca * x + sa * z, zt = -sa * x + ca * z;
          std::memcpy(&c->data[32 * i], &xt, 4), std::memcpy(&c->data[32 * i + 8], &zt, 4);
        }
      },
      {"point 0 (ring 0): elevation", "must be in the VLP-16's own frame", "transformed to another frame"}, 1);
  // Mirrored (y -> -y): every point stays on its ring, the head seems to turn counter-clockwise.
  ExpectError(
      [](PointCloud2Msg* c) {
        for (uint32_t i = 0; i < c->width; ++i) {
          float y;
          std::memcpy(&y, &c->data[32 * i + 4], 4);
          y = -y;
          std::memcpy(&c->data[32 * i + 4], &y, 4);
        }
      },
      {"does not increase with time", "mirrored"});
  // The same laser twice in one firing (a dual-return cloud).
  ExpectError(
      [](PointCloud2Msg* c) {
        c->data.insert(c->data.end(), c->data.begin(), c->data.begin() + 32);
        ++c->width, c->row_step += 32;
      },
      {"point 96: a second point of laser 0 in one firing sequence", "dual-return"});
  // An absolute time in the `time` field (float64 here, as some drivers write it).
  ExpectError(
      [](PointCloud2Msg* c) {
        c->point_step = 40, c->row_step = 40 * c->width;
        c->data.assign(c->row_step, 0);  // all at the origin (skipped) but point 0, at x = 5 m
        Find(c, "time")->offset = 32, Find(c, "time")->datatype = static_cast<uint8_t>(PointFieldType::kFloat64);
        const double t = 1700000123.25;
        std::memcpy(&c->data[32], &t, 8);
        const float x = 5.f;
        std::memcpy(&c->data[0], &x, 4);
      },
      {"point 0: field 'time': 1700000123.250000 s from header.stamp", "absolute times are not supported"});
  // A cloud going back in time past the previous one.
  ExpectError(
      [](PointCloud2Msg* c) {
        for (uint32_t i = 0; i < c->width; ++i) {
          float t;
          std::memcpy(&t, &c->data[32 * i + 24], 4);
          t -= 0.02f;
          std::memcpy(&c->data[32 * i + 24], &t, 4);
        }
      },
      {"is earlier than the packet before it", "time order"}, 2);
}

TEST_F(CloudImportErrors, LidarClockPpsIsForPackets) {
  BagImportOptions o;
  o.lidar_clock = LidarClock::kPps;
  const Status s = Import(WriteBag(nullptr), o);
  ASSERT_FALSE(s.ok);
  EXPECT_NE(s.message.find("--lidar-clock pps applies to raw VelodyneScan packets"), std::string::npos) << s.message;
}

}  // namespace
}  // namespace rotolidar::bench::rosmsg
