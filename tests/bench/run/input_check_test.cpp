// The degraded inputs a careful user found to pass silently are each named, with counts: no IMU, IMU and encoder
// gaps, an encoder resolution that disagrees with calib.yaml, a calibration pose left out, lost packets. A clean
// recording gives no warning.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "bench/run/input_check.hpp"
#include "core/io/calib_yaml.hpp"
#include "core/wire/pcap.hpp"
#include "core/wire/vlp16.hpp"

namespace rotolidar::bench {
namespace {

/// 10 s of a clean rig: 200 Hz IMU, 1 kHz 12-bit encoder at 2.6 rad/s, 754 packets per second.
Recording CleanRecording(const std::string& name) {
  Recording rec;
  rec.dir = (std::filesystem::temp_directory_path() / ("rotolidar_input_check_" + name)).string();
  std::filesystem::create_directories(rec.dir);
  rec.calib.motor_speed_radps = 2.6;
  EXPECT_TRUE(SaveCalibYaml(rec.dir + "/calib.yaml", rec.calib).ok);  // every key written
  for (int i = 0; i < 2000; ++i)
    rec.imu.push_back({0.005 * i, Eigen::Vector3d(0.01 * std::sin(i), 0, 0), Eigen::Vector3d(0, 0, 9.81 + 0.01 * std::cos(i))});
  for (int i = 0; i < 10000; ++i) {
    const double t = 1e-3 * i, turns = 2.6 * t / (2 * M_PI);
    rec.encoder.push_back({t, static_cast<uint32_t>((turns - std::floor(turns)) * 4096)});
  }
  for (int i = 0; i < 7540; ++i) {
    Vlp16RawPacket raw;
    raw.timestamp_us = static_cast<uint32_t>(i * 1327.104);
    for (Vlp16RawBlock& block : raw.blocks) block.distance_2mm.fill(2500);  // every laser sees 5 m
    rec.lidar_packets.push_back({raw.timestamp_us * 1e-6, kVlp16DataPort, SerializeVlp16DataPacket(raw)});
  }
  return rec;
}

const InputWarning* Find(const std::vector<InputWarning>& w, const std::string& code) {
  for (const InputWarning& x : w)
    if (x.code == code) return &x;
  return nullptr;
}

TEST(InputCheck, ACleanRecordingHasNoWarning) {
  const std::vector<InputWarning> w = CheckRecording(CleanRecording("clean"));
  EXPECT_TRUE(w.empty()) << InputWarningsText(w);
}

TEST(InputCheck, MissingImuAndGapsAreNamedWithCounts) {
  Recording rec = CleanRecording("gaps");
  rec.imu.erase(rec.imu.begin() + 1000, rec.imu.begin() + 1200);         // a 1 s IMU gap
  rec.encoder.erase(rec.encoder.begin() + 3000, rec.encoder.begin() + 4500);  // a 1.5 s encoder gap
  rec.lidar_packets.erase(rec.lidar_packets.begin() + 100, rec.lidar_packets.begin() + 110);
  const std::vector<InputWarning> w = CheckRecording(rec);
  ASSERT_NE(Find(w, "imu.gaps"), nullptr) << InputWarningsText(w);
  EXPECT_EQ(Find(w, "imu.gaps")->count, 1u);
  EXPECT_NE(Find(w, "imu.gaps")->message.find("the longest 1.005 s"), std::string::npos);
  ASSERT_NE(Find(w, "encoder.gaps"), nullptr);
  EXPECT_NE(Find(w, "encoder.gaps")->message.find("1.501 s"), std::string::npos) << Find(w, "encoder.gaps")->message;
  ASSERT_NE(Find(w, "lidar.lost_packets"), nullptr);
  EXPECT_EQ(Find(w, "lidar.lost_packets")->count, 10u);
  rec.imu.clear();
  EXPECT_NE(Find(CheckRecording(rec), "imu.missing"), nullptr);
}

TEST(InputCheck, CalibrationThatDisagreesWithTheDataIsNamed) {
  Recording rec = CleanRecording("calib");
  rec.calib.encoder.counts_per_rev = 16384;  // a 14-bit setting on 12-bit data
  std::ofstream(rec.dir + "/calib.yaml") << "format_version: 1\nmotor_speed_radps: 2.6\n";  // no poses
  const std::vector<InputWarning> w = CheckRecording(rec);
  ASSERT_NE(Find(w, "encoder.resolution"), nullptr) << InputWarningsText(w);
  EXPECT_NE(Find(w, "encoder.resolution")->message.find("counts never exceed 4095"), std::string::npos);
  std::size_t poses = 0;
  for (const InputWarning& x : w) poses += x.code == "calib.pose_missing";
  EXPECT_EQ(poses, 3u);  // T_base_motor, T_rotor_lidar, T_base_imu
}

TEST(InputCheck, ReorderedPacketsAreNotLost) {
  Recording rec = CleanRecording("reordered");
  for (std::size_t i = 10; i + 3 < rec.lidar_packets.size(); i += 50) std::swap(rec.lidar_packets[i], rec.lidar_packets[i + 3]);
  const std::vector<InputWarning> w = CheckRecording(rec);
  EXPECT_EQ(Find(w, "lidar.lost_packets"), nullptr) << InputWarningsText(w);
}

TEST(InputCheck, FrozenEncoderSaturatedImuAndBlindLidarAreNamed) {
  Recording rec = CleanRecording("faults");
  for (int i = 4000; i < 5000; ++i) rec.encoder[i].count = rec.encoder[3999].count;  // 1 s frozen
  for (int i = 0; i < 2000; i += 100) rec.imu[i].gyro_radps.z() = (i % 200 ? -0.5 : 0.5);  // clipped at 0.5 rad/s
  for (int i = 3000; i < 3000 + 754; ++i) {  // 1 s of packets without a return
    Vlp16RawPacket raw;
    ASSERT_TRUE(ParseVlp16DataPacket(rec.lidar_packets[i].payload.data(), kVlp16PacketBytes, &raw).ok);
    for (Vlp16RawBlock& block : raw.blocks) block.distance_2mm.fill(0);
    rec.lidar_packets[i].payload = SerializeVlp16DataPacket(raw);
  }
  const std::vector<InputWarning> w = CheckRecording(rec);
  ASSERT_NE(Find(w, "encoder.frozen"), nullptr) << InputWarningsText(w);
  EXPECT_NE(Find(w, "encoder.frozen")->message.find("the longest 1.00 s"), std::string::npos);
  ASSERT_NE(Find(w, "imu.saturated"), nullptr) << InputWarningsText(w);
  EXPECT_EQ(Find(w, "imu.saturated")->count, 20u);
  ASSERT_NE(Find(w, "lidar.blind"), nullptr) << InputWarningsText(w);
  EXPECT_EQ(Find(w, "lidar.blind")->count, 1u);
}

TEST(InputCheck, AStreamedRecordingGivesTheSameWarnings) {
  Recording rec = CleanRecording("streamed");
  for (int i = 3000; i < 3000 + 754; ++i) {  // 1 s without a return
    Vlp16RawPacket raw;
    ASSERT_TRUE(ParseVlp16DataPacket(rec.lidar_packets[i].payload.data(), kVlp16PacketBytes, &raw).ok);
    for (Vlp16RawBlock& block : raw.blocks) block.distance_2mm.fill(0);
    rec.lidar_packets[i].payload = SerializeVlp16DataPacket(raw);
  }
  rec.lidar_packets.erase(rec.lidar_packets.begin() + 100, rec.lidar_packets.begin() + 105);  // 5 lost
  PcapWriter pcap;
  ASSERT_TRUE(pcap.Open(rec.dir + "/lidar.pcap").ok);
  for (const LidarPacket& p : rec.lidar_packets) ASSERT_TRUE(pcap.Write(p).ok);
  ASSERT_TRUE(pcap.Close().ok);
  Recording streamed = rec;
  streamed.lidar_packets.clear();
  streamed.lidar_packets_streamed = true;

  const std::vector<InputWarning> in_memory = CheckRecording(rec);
  std::vector<InputWarning> from_disk;
  ASSERT_TRUE(CheckRecording(streamed, InputCheckConfig{}, &from_disk).ok);
  ASSERT_NE(Find(in_memory, "lidar.lost_packets"), nullptr) << InputWarningsText(in_memory);
  EXPECT_EQ(Find(in_memory, "lidar.lost_packets")->count, 5u);
  ASSERT_NE(Find(in_memory, "lidar.blind"), nullptr) << InputWarningsText(in_memory);
  EXPECT_EQ(InputWarningsText(from_disk), InputWarningsText(in_memory));

  // A file that goes bad is an error of the Status overload, and a warning of the other.
  { std::ofstream truncate(rec.dir + "/lidar.pcap", std::ios::binary | std::ios::trunc); truncate << "not a pcap"; }
  std::vector<InputWarning> none;
  const Status bad = CheckRecording(streamed, InputCheckConfig{}, &none);
  EXPECT_FALSE(bad.ok);
  EXPECT_NE(bad.message.find(rec.dir + "/lidar.pcap"), std::string::npos) << bad.message;
  EXPECT_NE(Find(CheckRecording(streamed), "lidar.unreadable"), nullptr);
}

}  // namespace
}  // namespace rotolidar::bench
