// The degraded inputs a careful user found to pass silently are each named, with counts: no IMU, IMU and encoder
// gaps, an encoder resolution that disagrees with calib.yaml, a calibration pose left out, lost packets. A clean
// recording gives no warning.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "bench/run/input_check.hpp"
#include "core/io/calib_yaml.hpp"
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
  for (int i = 0; i < 2000; ++i) rec.imu.push_back({0.005 * i, {}, {}});
  for (int i = 0; i < 10000; ++i) {
    const double t = 1e-3 * i, turns = 2.6 * t / (2 * M_PI);
    rec.encoder.push_back({t, static_cast<uint32_t>((turns - std::floor(turns)) * 4096)});
  }
  for (int i = 0; i < 7540; ++i) {
    Vlp16RawPacket raw;
    raw.timestamp_us = static_cast<uint32_t>(i * 1327.104);
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

}  // namespace
}  // namespace rotolidar::bench
